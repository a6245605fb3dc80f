"""Layout of the flat arrays the jitted kernels read: index constants and :class:`ModelArrays`.

This module sits below :mod:`amra_core.kernels`: it imports nothing of AMRA, so the jitted core
depends on the layout only, never on the code that assembles models (:mod:`amra_core.model`
compiles a rotor into these arrays).

State vector ``y`` (SI): ``[psi, Omega, V_d, v0, zeta0, zeta1, zeta0', zeta1', x(n_s), x'(n_s),
wagner(2 blades x n_st x 2)(, v_s, v_c)]`` with ``x = [beta, q_blade0, q_blade1]``
(:mod:`amra_core.structure`), ``V_d`` the descent rate (positive down) and ``v0`` the uniform
induced velocity (positive down).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

# --- scalar parameter slots (indices into ModelArrays.p) -------------------------------------
P_RHO, P_A_SOUND, P_G, P_MASS, P_R, P_R0, P_VH, P_ALPHA_S = range(8)
P_HOLD_OMEGA, P_HOLD_VD, P_AERO, P_IR, P_ILAG, P_SLAG, P_KLAG, P_K2LAG = range(8, 16)
P_NQ, P_NST, P_NS, P_QUASI_STATIC, P_CLAG, P_INFLOW3 = range(16, 22)
P_VACUUM = 22  #: 1: no aerodynamic loads, inflow and descent frozen (conservation tests only)
P_FLAG = 23  #: static lag moment per Omega^2 [kg m] (RotorStructure.f_lag)
P_UNIT_MASS = 24  #: 1: minv is the identity (a mass-normalised modal basis), so ugyh = gyh, uglh = glh
#: 1: :func:`amra_core.kernels.advance` integrates the modal oscillators
#: ``x_i'' = -(k0_ii + Omega^2 k2_ii) x_i`` exactly (Lawson's integrating-factor RK4); 0: plain RK4
P_LAWSON = 25
#: 1: :func:`amra_core.kernels.advance` integrates the Wagner lag states' decay at the section speed
#: ``Omega r`` exactly (Lawson); 0: RK4 resolves it
P_LAWSON_LAGS = 26
N_P = 27

# --- station table columns --------------------------------------------------------------------
S_R, S_W, S_C, S_XEA, S_XAC, S_THETA0, S_A = range(7)
N_S_COLS = 7

# --- station vectors: one column per blade station, blade 0's n_st then blade 1's (ModelArrays.sv)
SV_R, SV_W, SV_C, SV_XEA, SV_XAC, SV_THETA0, SV_A, SV_SIGN = range(8)  #: SV_SIGN: +1 blade 0, -1 blade 1
N_SV_ROWS = 8
#: row length of the station-major arrays (``sv``, ``kin`` and the right-hand side's station scratch):
#: at least 2 x the largest station count (60), and a constant, so the compiler knows the rows of
#: one array do not overlap and vectorises the station loops without run-time overlap checks
STATION_STRIDE = 128

# --- fixed state slots --------------------------------------------------------------------------
Y_PSI, Y_OMEGA, Y_VD, Y_V0, Y_ZETA0, Y_ZETA1, Y_ZETAD0, Y_ZETAD1 = range(8)
N_Y_FIXED = 8

# --- loads written by the right-hand side -----------------------------------------------------
L_THRUST, L_TORQUE, L_HFORCE, L_FVERT, L_FHORIZ, L_VM = range(6)
N_LOADS = 6

#: R.T. Jones approximation of Wagner's function (physics-reference §4.4)
WAGNER_A = (0.165, 0.335)
WAGNER_B = (0.0455, 0.3)


class ModelArrays(NamedTuple):
    p: np.ndarray  #: scalar parameters, see P_* slots
    minv: np.ndarray  #: inverse of structural + apparent mass (n_s x n_s)
    k0: np.ndarray  #: stiffness independent of rotor speed
    k2: np.ndarray  #: stiffness per Omega^2
    c: np.ndarray  #: structural damping (n_s x n_s), see :func:`structural_damping`
    st: np.ndarray  #: (n_st, N_S_COLS) station table
    shw: np.ndarray  #: (2 blades, n_st, n) flap displacement per coordinate (teeter included)
    shd: np.ndarray  #: (2, n_st, n) flap slope d w/d r per coordinate
    sht: np.ndarray  #: (2, n_st, n) elastic twist per coordinate
    tip: np.ndarray  #: (2 blades, 2 [flap, twist], n) tip displacement and twist per coordinate
    teeter: np.ndarray  #: (n,) teeter angle per coordinate
    lag_inv: np.ndarray  #: inverse of the [Omega, zeta0, zeta1] inertia matrix at x = 0 (3 x 3; the
    #: kernel eliminates the state-dependent inertia itself, this stays for linear analyses)
    af_alpha0: float
    af_dalpha: float
    af_cl: np.ndarray
    af_cd: np.ndarray
    af_cm: np.ndarray
    sf: np.ndarray  #: (n,) static pitch load per Omega^2 [kg m] (``f`` of :mod:`amra_core.structure`)
    gy0: np.ndarray  #: (n,) gyroscopic coupling with the rotor speed at x = 0 (``g0``)
    gyh: np.ndarray  #: (n, n) gyroscopic coupling per coordinate (``H``, symmetric)
    ugy0: np.ndarray  #: (n,) minv @ gy0
    ugyh: np.ndarray  #: (n, n) minv @ gyh
    ls2: np.ndarray  #: (2, n, n) lag coupling per blade, S_b = S_lag - 1/2 x^T ls2[b] x
    li2: np.ndarray  #: (2, n, n) lag inertia per blade, I_b = I_lag - x^T li2[b] x
    gl0: np.ndarray  #: (2, n) lag-pivot gyroscopic coupling per blade at x = 0 (``gl_b = gl0[b] + glh[b] x``)
    glh: np.ndarray  #: (2, n, n) blade b's part of ``gyh`` (``glh[0] + glh[1] = gyh``)
    ugl0: np.ndarray  #: (2, n) minv @ gl0[b]
    uglh: np.ndarray  #: (2, n, n) minv @ glh[b]
    #: (N_SV_ROWS, STATION_STRIDE) the station table ``st`` once per blade (blade 0's n_st stations,
    #: then blade 1's, then zeros), one ``SV_*`` row per quantity: the right-hand side runs its
    #: station loops over both blades' stations as one vector
    sv: np.ndarray
    #: (n, N_XQ n) and (n, N_XQD n): the matrices above that the right-hand side multiplies by the
    #: coordinates x and by their rates x', transposed and side by side (:func:`coordinate_products`)
    xq: np.ndarray
    xqd: np.ndarray
    #: (n, 3 STATION_STRIDE) ``shw``, ``shd``, ``sht`` per coordinate, one after the other, each
    #: station-contiguous as ``sv``: the same numbers, laid out for the vectorised loop
    kin: np.ndarray


def station_vectors(st: np.ndarray) -> np.ndarray:
    """The station table ``st`` (n_st, N_S_COLS) as ModelArrays.sv (N_SV_ROWS, STATION_STRIDE):
    blade 0's stations then blade 1's, one row per quantity, the blade's sign (+1, -1) in SV_SIGN,
    zeros after the last station."""
    nst = st.shape[0]
    sv = np.zeros((N_SV_ROWS, STATION_STRIDE))
    rows = np.array([SV_R, SV_W, SV_C, SV_XEA, SV_XAC, SV_THETA0, SV_A])
    cols = st[:, [S_R, S_W, S_C, S_XEA, S_XAC, S_THETA0, S_A]].T
    sv[rows, :nst] = cols
    sv[rows, nst:2 * nst] = cols
    sv[SV_SIGN, :nst] = 1.0
    sv[SV_SIGN, nst:2 * nst] = -1.0
    return sv


def station_shapes(shw: np.ndarray, shd: np.ndarray, sht: np.ndarray) -> np.ndarray:
    """``shw``, ``shd``, ``sht`` (2, n_st, n_s each) as ModelArrays.kin (n_s, 3 STATION_STRIDE)."""
    nsv, ns = 2 * shw.shape[1], shw.shape[2]
    kin = np.zeros((ns, 3 * STATION_STRIDE))
    for a, shape in enumerate((shw, shd, sht)):
        kin[:, a * STATION_STRIDE:a * STATION_STRIDE + nsv] = shape.reshape(nsv, ns).T
    return kin


#: the matrices of ModelArrays.xq (times x) in their order, the two a unit mass skips last; and of xqd (times x')
XQ_K0, XQ_K2, XQ_GYH, XQ_LS0, XQ_LS1, XQ_LI0, XQ_LI1, XQ_GLH0, XQ_UGYH, XQ_UGLH0 = range(10)
N_XQ = 10
N_XQ_UNIT = 8
XQD_C, XQD_GYH, XQD_GLH0 = range(3)
N_XQD = 3


def coordinate_products(a: ModelArrays) -> tuple:
    """(xq, xqd) of ModelArrays ``a``, from its matrices: ``xq[k, j n + i] = A_j[i, k]`` for the
    matrices A_j of ``XQ_*`` in that order, ``xqd`` likewise for ``XQD_*``, so the right-hand side
    forms the products ``A_j x`` of all of them in one loop over ``k`` whose inner loop runs along
    a contiguous row."""
    xq = np.concatenate([a.k0, a.k2, a.gyh, a.ls2[0], a.ls2[1], a.li2[0], a.li2[1], a.glh[0], a.ugyh,
                         a.uglh[0]], axis=0).T
    xqd = np.concatenate([a.c, a.gyh, a.glh[0]], axis=0).T
    return np.ascontiguousarray(xq), np.ascontiguousarray(xqd)


def with_coordinate_products(a: ModelArrays) -> ModelArrays:
    """``a`` with its ``xq``, ``xqd`` formed from its own matrices (after any change to them)."""
    xq, xqd = coordinate_products(a)
    return a._replace(xq=xq, xqd=xqd)
