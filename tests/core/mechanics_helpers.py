"""The linearised mechanics of a compiled model, for the time-step tests (``test_time_step``,
``test_lawson``): structure, lag and free rotor speed with damping and the Coriolis coupling."""
from __future__ import annotations

import numpy as np

from amra_core.model import P_CLAG, P_FLAG, P_ILAG, P_IR, P_K2LAG, P_KLAG, P_SLAG


def linear_mechanics(model, om: float):
    """``(A, n, nq)``: the first-order system ``y' = A y`` of the mechanics linearised at x = 0,
    zeta = 0, rotor speed ``om`` [rad/s] (free), state (x, zeta0, zeta1, x', Omega, zeta0', zeta1'):
    ``[[0, P], [-Mf^-1 P^T K P, -Mf^-1 (C + G)]]``; ``n`` structural coordinates, ``nq`` positions."""
    a, n, p = model.arrays, model.n_s, model.arrays.p
    N = n + 3
    Mf = np.zeros((N, N))
    Mf[:n, :n] = np.linalg.inv(a.minv)
    Mf[:n, n] = Mf[n, :n] = a.gy0
    Mf[n, n] = p[P_IR]
    G = np.zeros((N, N))  # velocity matrix C + G: damping and the Coriolis coupling with Omega
    G[:n, :n] = a.c
    G[:n, n] = -2 * om * a.sf
    G[n, :n] = 2 * om * a.sf
    for b in range(2):
        Mf[:n, n + 1 + b] = Mf[n + 1 + b, :n] = a.gl0[b]
        Mf[n, n + 1 + b] = Mf[n + 1 + b, n] = p[P_SLAG]
        Mf[n + 1 + b, n + 1 + b] = p[P_ILAG]
        G[n, n + 1 + b] = 2 * om * p[P_FLAG]
        G[n + 1 + b, n] = -2 * om * p[P_FLAG]
        G[n + 1 + b, n + 1 + b] = p[P_CLAG]
    nq = n + 2
    P = np.zeros((nq, N)); P[:n, :n] = np.eye(n); P[n, n + 1] = P[n + 1, n + 2] = 1.0
    K = np.zeros((nq, nq)); K[:n, :n] = a.k0 + om**2 * a.k2
    K[n, n] = K[n + 1, n + 1] = p[P_KLAG] + om**2 * p[P_K2LAG]
    Mi = np.linalg.inv(Mf)
    A = np.zeros((nq + N, nq + N))
    A[:nq, nq:] = P
    A[nq:, :nq] = -Mi @ P.T @ K
    A[nq:, nq:] = -Mi @ G
    return A, n, nq
