"""One place for the Numba decorator policy of every AMRA kernel.

All kernels are compiled ``nopython`` with ``nogil=True`` (so a thread pool or a
Panel worker thread can run several at once) and ``cache=True`` (so a fresh
process loads machine code from ``__pycache__`` instead of recompiling).
Kernels take only float64/int64 arrays and scalars: no Python objects.

Floating point: the LLVM fast-math flags that let the compiler use reciprocals and approximate
library calls (``arcp``, ``afn``, ``nsz``), but NOT ``nnan``/``ninf`` (the kernels test
``math.isfinite`` and ``isnan`` to stop a diverging run, and those tests must stay), NOT ``reassoc``
(reordering sums made the same right-hand side give different last bits in different callers: the
Jacobian kernel against single evaluations, a map in the process pool against the serial one) and
NOT ``contract``: with the vectorised station loops, fused multiply-adds made code compiled in a
process and the same code loaded from Numba's cache give different last bits (a map's critical GJ
622.3165644 fresh, 622.3165639 cached, so a pool's map differed from the serial one); without it
both are bitwise equal (tests/core/test_executor.py compares them) and the right-hand side is as fast
within the noise. Results must not depend on the path that computed them. ``error_model='numpy'``:
a division by zero gives inf/nan (caught by those tests) instead of a Python exception, so there
are no zero-check branches inside the loops.

Numba's on-disk cache is keyed on each function's own bytecode and its file's time stamp, not on
these flags nor on callees in other files: every jitted module therefore carries ``CACHE_STAMP``, a
hash of the amra_core modules it imports, which tests/core/test_kernel_cache_stamps.py checks; a
change here or in a kernel another module inlines fails that test until the importing modules'
stamps are updated, which changes their files and so invalidates their cached machine code.
"""
from numba import njit

#: fast-math flags of every kernel (see the module docstring)
FAST_MATH = {"nsz", "arcp", "afn"}

#: Decorator for every jitted kernel in ``amra_core``.
kernel = njit(cache=True, nogil=True, fastmath=FAST_MATH, error_model="numpy")

#: For small kernels called per blade station with the whole ModelArrays tuple: inlined at Numba
#: IR level, because an out-of-line call passes the tuple's ~15 arrays with a reference-count
#: increment and decrement each, per station and RK stage (measured: 5x slower right-hand side).
inline_kernel = njit(cache=True, nogil=True, inline="always", fastmath=FAST_MATH, error_model="numpy")

#: For the few kernels whose own arithmetic is promised to equal the same steps done in Python
#: bit for bit (the Jacobian's differences): no fast math there (``arcp`` would turn a division
#: into a multiplication by the reciprocal, one bit off).
exact_kernel = njit(cache=True, nogil=True)
