"""Jitted Newton iteration for the steady axial trim (issue 8 §5).
Compiled under the floating-point policy of :mod:`amra_core.jit` (fast math without ``reassoc``).

The axial trim solves ``f(z) = 0`` for the unknowns ``z = y[iu]`` (rotor speed unless held, descent
rate, inflow, lag and the static structural coordinates) with residuals ``dy[ir]`` of the full
right-hand side (:func:`amra_core.kernels.evaluate`). Doing the whole iteration inside one jitted
call (forward-difference Jacobian, LU solve, backtracking on the residual norm) replaces ~70
Python-level residual calls of ``scipy.optimize.root`` per trim; the caller checks the result
and falls back to ``hybr`` when this does not converge.
"""
from __future__ import annotations

import numpy as np

from . import kernels
from .jit import kernel

#: hash of the amra_core modules imported above: Numba's cache does not see them
#: (tests/core/test_kernel_cache_stamps.py)
CACHE_STAMP = "5e956a4a90ad8782"


@kernel
def _resid(y, m, ir, dy, loads, out):
    kernels.evaluate(y, m, dy, loads)
    for k in range(len(ir)):
        out[k] = dy[ir[k]]


@kernel
def residual_at(z, y0, m, iu, ir, y, dy, loads, out):
    """The residuals ``dy[ir]`` at the state ``y0`` with ``y[iu] = z`` (``y``, ``dy``, ``loads``:
    work arrays; ``out``: the residuals), for ``scipy.optimize.root`` where the Newton fails."""
    y[:] = y0
    for j in range(len(iu)):
        y[iu[j]] = z[j]
    _resid(y, m, ir, dy, loads, out)


@kernel
def newton_axial(y, m, iu, ir, tol, max_iter):
    """Newton on ``y[iu]`` for ``dy[ir] = 0`` in place; returns (iterations, max |residual|).
    ``iterations`` is -1 when the Jacobian is singular or the iteration stalls."""
    n = len(iu)
    dy = np.zeros(len(y))
    loads = np.zeros(8)
    r = np.zeros(n)
    rp = np.zeros(n)
    J = np.zeros((n, n))
    _resid(y, m, ir, dy, loads, r)
    rn = np.max(np.abs(r))
    for it in range(max_iter):
        if rn < tol:
            return it, rn
        for j in range(n):
            zj = y[iu[j]]
            h = 1e-7 * max(1.0, abs(zj))
            y[iu[j]] = zj + h
            _resid(y, m, ir, dy, loads, rp)
            y[iu[j]] = zj
            for i in range(n):
                J[i, j] = (rp[i] - r[i]) / h
        if not np.all(np.isfinite(J)):
            return -1, rn
        step = np.linalg.solve(J, -r)
        lam = 1.0
        z0 = np.empty(n)
        for j in range(n):
            z0[j] = y[iu[j]]
        accepted = False
        for _ in range(12):
            for j in range(n):
                y[iu[j]] = z0[j] + lam * step[j]
            _resid(y, m, ir, dy, loads, rp)
            rpn = np.max(np.abs(rp))
            if np.isfinite(rpn) and rpn < rn:
                accepted = True
                break
            lam *= 0.5
        if not accepted:
            for j in range(n):
                y[iu[j]] = z0[j]
            return -1, rn
        for i in range(n):
            r[i] = rp[i]
        rn = rpn
    return (max_iter if rn < tol else -1), rn
