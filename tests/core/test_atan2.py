"""The station loop's inlined arctangent (amra_core.atan2_kernel) against the C library's."""
import math

import numpy as np
from numba import njit

from amra_core.atan2_kernel import atan2


@njit
def _many(y, x):
    out = np.empty(y.shape[0])
    for i in range(y.shape[0]):
        out[i] = atan2(y[i], x[i])
    return out


def test_matches_math_atan2_on_a_dense_grid_of_directions_and_radii():
    rng = np.random.default_rng(7)
    ang = np.concatenate([np.linspace(-math.pi, math.pi, 200_001), rng.uniform(-math.pi, math.pi, 200_000)])
    rad = 10.0 ** rng.uniform(-8, 8, ang.size)
    y, x = rad * np.sin(ang), rad * np.cos(ang)
    got = _many(y, x)
    want = np.arctan2(y, x)
    assert np.max(np.abs(got - want)) <= 1e-15
    # near the switch points of the reduction (t = 0.66 and the diagonal) the result is smooth: a
    # central difference with the Jacobian's step agrees with the analytic derivative
    for t0 in (0.66, 1.0, 1.0 / 0.66):
        h = 1e-6
        xs = np.array([1.0, 1.0, 1.0])
        ys = np.array([t0 - h, t0, t0 + h])
        fd = (_many(ys[2:], xs[2:])[0] - _many(ys[:1], xs[:1])[0]) / (2 * h)
        assert abs(fd - 1.0 / (1.0 + t0 * t0)) < 1e-8


def test_axes_infinities_and_nan():
    cases = [(0.0, 1.0), (1.0, 0.0), (-1.0, 0.0), (0.0, -1.0), (0.0, 0.0), (1.0, 1.0), (-1.0, -1.0),
             (math.inf, 1.0), (1.0, math.inf), (1.0, -math.inf), (-1.0, -math.inf), (math.inf, math.inf),
             (-math.inf, -math.inf), (3.0, -1e-300), (-1e-300, -2.0)]
    y = np.array([c[0] for c in cases]); x = np.array([c[1] for c in cases])
    got = _many(y, x)
    for (yy, xx), g in zip(cases, got):
        assert abs(g - math.atan2(yy, xx)) <= 1e-15, (yy, xx, g)
    assert np.isnan(_many(np.array([math.nan, 1.0]), np.array([1.0, math.nan]))).all()
