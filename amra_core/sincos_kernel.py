"""Sine and cosine of one angle for the station loop, to full double precision without a library call.

``math.sin`` and ``math.cos`` are calls into the C library, which keep the compiler from vectorising
the loop over blade stations (the right-hand side's costliest part). :func:`sincos` here is Cephes'
``sin``/``cos`` (S. L. Moshier: the argument reduced to ``|r| <= pi/4`` by a multiple of pi/2 split
in three parts, Cody and Waite, then polynomials of degree 6 in ``r**2``), with the quadrant chosen
by selects, so it inlines into one basic block. Error: within a few units in the last place of the C
library for ``|x| <= 1e5`` rad (tests/core/test_trig_kernels.py); the blade pitch it serves is a few
radians at most. Non-finite arguments give NaN.
"""
from __future__ import annotations

import math

from .jit import inline_kernel

#: hash of the amra_core modules imported above: Numba's cache does not see them
#: (tests/core/test_kernel_cache_stamps.py)
CACHE_STAMP = "29b2b72e9273f3e8"

_S0, _S1, _S2, _S3, _S4, _S5 = (1.58962301576546568060e-10, -2.50507477628578072866e-8,
                                2.75573136213857245213e-6, -1.98412698295895385996e-4,
                                8.33333333332211858878e-3, -1.66666666666666307295e-1)
_C0, _C1, _C2, _C3, _C4, _C5 = (-1.13585365213876817300e-11, 2.08757008419747316778e-9,
                                -2.75573141792967388112e-7, 2.48015872888517045348e-5,
                                -1.38888888888730564116e-3, 4.16666666666665929218e-2)
# pi/2 in three parts (Cephes' DP1..DP3 times 2): n * _H1 and n * _H2 are exact for |n| < 2**27
_H1, _H2, _H3 = 1.5707962512969970703125, 7.54978941586159635336e-8, 5.3903028581581190529e-15


@inline_kernel
def sincos(x):
    """``(sin x, cos x)`` of an angle ``x`` [rad]."""
    n = math.floor(x * (2.0 / math.pi) + 0.5)  # nearest multiple of pi/2
    r = ((x - n * _H1) - n * _H2) - n * _H3
    r = r if abs(x) <= 1e300 else math.nan  # infinities (and NaN) give NaN, as the C library
    z = r * r
    s = r + r * z * (((((_S0 * z + _S1) * z + _S2) * z + _S3) * z + _S4) * z + _S5)
    c = 1.0 - 0.5 * z + z * z * (((((_C0 * z + _C1) * z + _C2) * z + _C3) * z + _C4) * z + _C5)
    q = n - 4.0 * math.floor(0.25 * n)  # quadrant 0..3
    sin_x = c if q == 1.0 else (-s if q == 2.0 else (-c if q == 3.0 else s))
    cos_x = -s if q == 1.0 else (-c if q == 2.0 else (s if q == 3.0 else c))
    return sin_x, cos_x
