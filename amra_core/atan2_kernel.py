"""Four-quadrant arctangent for the station loop, to full double precision without a library call.

``math.atan2`` is a call into the C library that the compiler can neither inline nor schedule
around: it was the costliest single operation of a blade station (about 20 ns of 64, measured with
``scripts/bench_kernels.py``). :func:`atan2` here is Cephes' ``atan`` (S. L. Moshier, rational
approximation of degree 4/5 in ``x**2`` on ``|x| <= 0.66``, with the ``(x - 1)/(x + 1)`` reduction
about pi/4 above it) applied to ``min(|y|, |x|) / max(|y|, |x|)`` in ``[0, 1]``, then mapped to the
quadrant. It is inlined and free of early returns, so the loop over blade stations stays one basic block the
compiler can vectorise. Error: within a few units in the last place of ``math.atan2`` (tests/core/test_atan2.py
checks 1e-15 rad on a dense grid and the signed zeros, infinities and NaN).
"""
from __future__ import annotations

import math

from .jit import inline_kernel

#: hash of the amra_core modules imported above: Numba's cache does not see them
#: (tests/core/test_kernel_cache_stamps.py)
CACHE_STAMP = "29b2b72e9273f3e8"

_P0, _P1, _P2, _P3, _P4 = (-8.750608600031904122785e-1, -1.615753718733365076637e1,
                           -7.500855792314704667340e1, -1.228866684490136173410e2,
                           -6.485021904942025371773e1)
_Q0, _Q1, _Q2, _Q3, _Q4 = (2.485846490142306297962e1, 1.650270098316988542046e2,
                           4.328810604912902668951e2, 4.853903996359136964868e2,
                           1.945506571482613964425e2)
_MOREBITS = 6.123233995736765886130e-17  #: pi/2 minus its double, for the pi/4 offset's last bit


@inline_kernel
def atan2(y, x):
    """Angle [rad] of the point ``(x, y)`` in ``[-pi, pi]``, as ``math.atan2(y, x)``."""
    ay = abs(y)
    ax = abs(x)
    big = ay if ay > ax else ax  # ternaries, not max/min: Numba's builtins keep the loop scalar
    small = ax if ay > ax else ay
    t = small / big if big > 0.0 else 0.0  # tan of the angle to the nearer axis, in [0, 1]
    upper = t > 0.66
    u = (t - 1.0) / (t + 1.0) if upper else t  # atan(t) = pi/4 + atan(u) above 0.66
    z = u * u
    num = (((_P0 * z + _P1) * z + _P2) * z + _P3) * z + _P4
    den = ((((z + _Q0) * z + _Q1) * z + _Q2) * z + _Q3) * z + _Q4
    r = u + u * z * num / den
    r = r + (0.25 * math.pi + 0.5 * _MOREBITS) if upper else r
    r = 0.5 * math.pi - r if ay > ax else r
    r = math.pi - r if x < 0.0 or (x == 0.0 and math.copysign(1.0, x) < 0.0 and y == 0.0) else r
    r = math.copysign(r, y)
    # the special cases as selects, not early returns, so a loop over stations stays vectorisable
    both_inf = math.isinf(ay) and math.isinf(ax)  # the diagonals, as the C library
    r = math.copysign(0.75 * math.pi if x < 0.0 else 0.25 * math.pi, y) if both_inf else r
    return r if (x == x and y == y) else math.nan
