"""The two blades' exchange symmetry of a linearised axial trim, used to halve its eigenproblem.

In axial flight nothing depends on the azimuth, so relabelling the blades (blade 0 <-> blade 1) maps
the model onto itself: the rotor speed, descent rate and uniform inflow stay, the teeter angle and
the first-harmonic inflow change sign, and each blade's lag, flap/torsion coordinates and Wagner
states trade places. The axial trim is symmetric, so the Jacobian ``J`` commutes with that
exchange ``P`` (``P J = J P``) and splits exactly into a collective block (``P v = v``) and a
cyclic block (``P v = -v``). Two eigenproblems of half the size cost about half the full one
(rigid, 65 states: 0.48 against 0.90 ms; fem-coupled, 113 states: 1.6 against 3.3 ms).

:func:`eig_axial` checks the split on the Jacobian it is given (the coupling between the blocks must
be at the level of its finite-difference roundoff) and otherwise solves the full problem.
"""
from __future__ import annotations

import numpy as np

from .layout import N_Y_FIXED, P_NQ, Y_OMEGA, Y_V0, Y_VD, Y_ZETA0, Y_ZETAD0

#: largest coupling between the collective and cyclic blocks, relative to max |J|, that is taken
#: as roundoff (the central-difference Jacobian at a symmetric trim: ~1e-11)
SPLIT_TOL = 1e-8


def exchange_bases(model) -> tuple[np.ndarray, np.ndarray]:
    """Orthonormal bases (columns) of the collective (``P v = v``) and cyclic (``P v = -v``)
    subspaces of ``model``'s state without the azimuth (the Jacobian's coordinates)."""
    n = model.n_y - 1
    nq = int(model.arrays.p[P_NQ])
    plus, minus = [], []

    def unit(i):
        e = np.zeros(n)
        e[i - 1] = 1.0  # state index i, without psi
        return e

    def pair(i, j):
        plus.append((unit(i) + unit(j)) / np.sqrt(2.0))
        minus.append((unit(i) - unit(j)) / np.sqrt(2.0))

    plus.extend(unit(i) for i in (Y_OMEGA, Y_VD, Y_V0))
    pair(Y_ZETA0, Y_ZETA0 + 1)
    pair(Y_ZETAD0, Y_ZETAD0 + 1)
    # physical coordinates [beta, q_blade0, q_blade1] -> [-beta, q_blade1, q_blade0], in the model's basis
    ex = np.zeros((1 + 2 * nq, 1 + 2 * nq))
    ex[0, 0] = -1.0
    ex[1:1 + nq, 1 + nq:] = ex[1 + nq:, 1:1 + nq] = np.eye(nq)
    p_modal = model.phi_pinv @ ex @ model.phi
    w, U = np.linalg.eigh(0.5 * (p_modal + p_modal.T))
    for sl in (model.x_slice(), model.xd_slice()):
        for k in range(len(w)):
            v = np.zeros(n)
            v[sl.start - 1:sl.stop - 1] = U[:, k]
            (plus if w[k] > 0 else minus).append(v)
    a = model.aero_slice()
    half = (a.stop - a.start) // 2  # blade 0's Wagner states, then blade 1's
    for i in range(a.start, a.start + half):
        pair(i, i + half)
    h = model.inflow_harmonics_slice()
    minus.extend(unit(i) for i in range(h.start, h.stop))
    T_plus, T_minus = np.array(plus).T, np.array(minus).T
    assert N_Y_FIXED - 1 + 2 * model.n_s + (a.stop - a.start) + (h.stop - h.start) == n == T_plus.shape[1] + T_minus.shape[1]
    return T_plus, T_minus


def eig_axial(model, J: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues and unit eigenvectors of the axial Jacobian ``J`` (as ``numpy.linalg.eig``), by
    its collective and cyclic blocks when ``J`` commutes with the blade exchange to ``SPLIT_TOL``."""
    T_plus, T_minus = exchange_bases(model)
    scale = float(np.abs(J).max()) or 1.0
    JT_minus = J @ T_minus
    if np.abs(T_plus.T @ JT_minus).max() > SPLIT_TOL * scale or \
            np.abs(T_minus.T @ (J @ T_plus)).max() > SPLIT_TOL * scale:
        return np.linalg.eig(J)  # not symmetric (an asymmetric state): the full problem
    lam_p, V_p = np.linalg.eig(T_plus.T @ J @ T_plus)
    lam_m, V_m = np.linalg.eig(T_minus.T @ JT_minus)
    return np.concatenate([lam_p, lam_m]), np.hstack([T_plus @ V_p, T_minus @ V_m])
