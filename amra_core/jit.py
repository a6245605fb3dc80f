"""One place for the Numba decorator policy of every AMRA kernel.

All kernels are compiled ``nopython`` with ``nogil=True`` (so a thread pool or a
Panel worker thread can run several at once) and ``cache=True`` (so a fresh
process loads machine code from ``__pycache__`` instead of recompiling).
Kernels take only float64/int64 arrays and scalars: no Python objects.
"""
from numba import njit

#: Decorator for every jitted kernel in ``amra_core``.
kernel = njit(cache=True, nogil=True)
