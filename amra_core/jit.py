"""One place for the Numba decorator policy of every AMRA kernel.

All kernels are compiled ``nopython`` with ``nogil=True`` (so a thread pool or a
Panel worker thread can run several at once) and ``cache=True`` (so a fresh
process loads machine code from ``__pycache__`` instead of recompiling).
Kernels take only float64/int64 arrays and scalars: no Python objects.
"""
from numba import njit

#: Decorator for every jitted kernel in ``amra_core``.
kernel = njit(cache=True, nogil=True)

#: For small kernels called per blade station with the whole ModelArrays tuple: inlined at Numba
#: IR level, because an out-of-line call passes the tuple's ~15 arrays with a reference-count
#: increment and decrement each, per station and RK stage (measured: 5x slower right-hand side).
inline_kernel = njit(cache=True, nogil=True, inline="always")
