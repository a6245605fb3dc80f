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
    subspaces of ``model``'s state without the azimuth (the Jacobian's coordinates). Collective:
    rotor speed, descent rate, inflow, the blades' lag sums, the model's collective structural
    modes, the Wagner sums; cyclic: the lag differences, the cyclic structural modes, the Wagner
    differences and the first-harmonic inflow."""
    n = model.n_y - 1
    nq = int(model.arrays.p[P_NQ])
    a, h = model.aero_slice(), model.inflow_harmonics_slice()
    half = (a.stop - a.start) // 2  # blade 0's Wagner states, then blade 1's
    # physical coordinates [beta, q_blade0, q_blade1] -> [-beta, q_blade1, q_blade0], in the model's basis
    ex = np.zeros((1 + 2 * nq, 1 + 2 * nq))
    ex[0, 0] = -1.0
    ex[1:1 + nq, 1 + nq:] = ex[1 + nq:, 1:1 + nq] = np.eye(nq)
    p_modal = model.phi_pinv @ ex @ model.phi
    w, U = np.linalg.eigh(0.5 * (p_modal + p_modal.T))
    up, um = U[:, w > 0], U[:, w <= 0]
    # the pairs (i, j) that trade places: the two blades' lag and lag rate, their Wagner states
    wagner = np.arange(a.start, a.start + half)
    pairs_i = np.concatenate([[Y_ZETA0, Y_ZETAD0], wagner]) - 1  # without psi
    pairs_j = np.concatenate([[Y_ZETA0 + 1, Y_ZETAD0 + 1], wagner + half]) - 1
    n_plus = 3 + len(pairs_i) + 2 * up.shape[1]
    T_plus, T_minus = np.zeros((n, n_plus)), np.zeros((n, n - n_plus))
    T_plus[[Y_OMEGA - 1, Y_VD - 1, Y_V0 - 1], [0, 1, 2]] = 1.0
    c = 1.0 / np.sqrt(2.0)
    # column order: singles, the lag pairs, the structural modes (x then x'), the Wagner pairs
    cols_plus = np.concatenate([3 + np.arange(2), 3 + 2 + 2 * up.shape[1] + np.arange(half)])
    cols_minus = np.concatenate([np.arange(2), 2 + 2 * um.shape[1] + np.arange(half)])
    T_plus[pairs_i, cols_plus] = c
    T_plus[pairs_j, cols_plus] = c
    T_minus[pairs_i, cols_minus] = c
    T_minus[pairs_j, cols_minus] = -c
    for k, sl in enumerate((model.x_slice(), model.xd_slice())):
        T_plus[sl.start - 1:sl.stop - 1, 5 + k * up.shape[1]:5 + (k + 1) * up.shape[1]] = up
        T_minus[sl.start - 1:sl.stop - 1, 2 + k * um.shape[1]:2 + (k + 1) * um.shape[1]] = um
    n_h = h.stop - h.start
    T_minus[np.arange(h.start, h.stop) - 1, n - n_plus - n_h + np.arange(n_h)] = 1.0
    assert N_Y_FIXED - 1 + 2 * model.n_s + (a.stop - a.start) + n_h == n
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
