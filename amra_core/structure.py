"""Structural matrices of the teetering two-bladed rotor (in vacuo), by Galerkin integration.

Generalised coordinates of the flap/torsion system: ``x = [beta, q_blade0, q_blade1]`` with the
teeter angle ``beta`` shared by both blades (blade 0 displaced by ``+beta r``, blade 1 by
``-beta r``) and each blade's coordinates ``q`` from :mod:`amra_core.shapes`. The equations are
``M x'' + (K0 + Omega^2 K2) x = Q`` with, per unit span (``e = (x_cg - x_ea) c`` aft positive):

* kinetic energy ``1/2 m (w' - e theta')^2 + 1/2 I_ea theta'^2`` (dots), giving the inertial
  flap-torsion coupling through the CG offset;
* elastic energy ``1/2 EI w''^2 + 1/2 GJ theta'^2`` (FEM levels) or root springs (rigid level);
* centrifugal energy ``1/2 T(r) w'^2`` with ``T = Omega^2 int_r^R m rho drho`` (stiffening;
  the rigid hub bar between the axis and the root carries ``T(r0)`` for the teeter motion, so a
  rigid teetering rotor has exactly 1/rev), the propeller moment ``1/2 Omega^2 I_ea theta^2``
  (``nu^2 = nu0^2 + 1``), and ``-Omega^2 m e r w' theta``: a coned blade with its CG aft of the
  EA is pitched nose up by centrifugal force.

Equivalent root springs of the ``rigid`` level (model-notes §2), chosen so that the uniform rigid
blade has the first non-rotating frequency of the uniform cantilever: torsion
``k_theta = (pi/2)^2 GJ/L``; flap ``k_beta = 1.8751^4 EI/(3L)`` (rigid blade inertia ``m L^3/3``);
lag likewise with EI_lag. GJ and EI are span averages for a non-uniform blade.

Lag: one rigid lead-lag angle per blade about a root spring at ``r0`` (paper: Lagrange
equations), inertially coupled with rotor speed: ``[[I_R, S, S], [S, I_z, 0], [S, 0, I_z]]``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .rotor import Rotor
from .shapes import BladeMesh

BETA1_L = 1.87510407  # first root of cos(x) cosh(x) = -1
K_FLAP_SPRING = BETA1_L**4 / 3.0
K_TORSION_SPRING = (np.pi / 2.0) ** 2

_GAUSS_X, _GAUSS_W = np.polynomial.legendre.leggauss(4)


def quadrature(rotor: Rotor, mesh: BladeMesh):
    """Composite 4-point Gauss points and weights over the blade, breaking at nodes and stations."""
    bps = set(np.round(mesh.nodes_m, 12)) | set(np.round(rotor.stations.r_m, 12))
    if rotor.point_mass is not None:
        bps.add(round(rotor.point_mass.r_m, 12))
    bps = np.array(sorted(bps))
    a, b = bps[:-1], bps[1:]
    r = (0.5 * (b - a)[:, None] * (_GAUSS_X[None, :] + 1.0) + a[:, None]).ravel()
    w = (0.5 * (b - a)[:, None] * _GAUSS_W[None, :]).ravel()
    return r, w


def tension_per_omega2(rotor: Rotor, r) -> np.ndarray:
    """Centrifugal tension divided by Omega^2, ``int_r^R m rho drho`` (+ point mass) [kg m]."""
    st = rotor.stations
    fine = np.linspace(st.r_m[0], st.r_m[-1], 4001)
    fine = np.union1d(fine, st.r_m)
    f = st.at("mass_kg_m", fine) * fine
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(fine))])
    T = cum[-1] - np.interp(r, fine, cum)
    if rotor.point_mass is not None:
        pm = rotor.point_mass
        T = T + np.where(np.asarray(r) < pm.r_m, pm.mass_kg * pm.r_m, 0.0)
    return T


@dataclass(frozen=True)
class RotorStructure:
    """Assembled matrices. Flap/torsion: ``M``, ``K0``, ``K2`` over ``[beta, q0, q1]``.
    Lag/rotor: polar inertia ``I_R`` [kg m^2], lag inertia ``I_lag``, coupling ``S_lag``,
    spring ``k_lag`` [N m/rad] and centrifugal lag stiffness per Omega^2 ``k2_lag``."""

    mesh: BladeMesh
    M: np.ndarray
    K0: np.ndarray
    K2: np.ndarray
    kinds: tuple  #: per coordinate: 'teeter', 'flap' or 'torsion'
    blade_of: tuple  #: per coordinate: -1 (shared), 0 or 1
    I_R: float
    I_lag: float
    S_lag: float
    k_lag: float
    k2_lag: float

    @property
    def n(self) -> int:
        return self.M.shape[0]


def blade_matrices(rotor: Rotor, mesh: BladeMesh, added_mass=None):
    """(M, K0, K2) of one blade over ``[beta, q]`` (blade displaced by ``+beta r``).

    ``added_mass``: optional (m_a, s_a, i_a) callables of r for the aerodynamic apparent mass
    per length: lift ``m_a w''``, cross ``s_a``, pitch ``i_a`` (see :mod:`amra_core.model`)."""
    st = rotor.stations
    r, wq = quadrature(rotor, mesh)
    pw, dpw, ddpw, pt, dpt = mesh.shapes(r)
    n = 1 + mesh.n_q
    Pw = np.zeros((len(r), n)); Pw[:, 0] = r; Pw[:, 1:] = pw
    dPw = np.zeros_like(Pw); dPw[:, 0] = 1.0; dPw[:, 1:] = dpw
    ddPw = np.zeros_like(Pw); ddPw[:, 1:] = ddpw
    Pt = np.zeros_like(Pw); Pt[:, 1:] = pt
    dPt = np.zeros_like(Pw); dPt[:, 1:] = dpt

    c = st.at("chord_m", r)
    m = st.at("mass_kg_m", r)
    e = (st.at("x_cg", r) - st.at("x_ea", r)) * c
    I = st.at("torsional_inertia_kg_m", r)
    EI = st.at("ei_flap_nm2", r)
    GJ = st.at("gj_nm2", r)
    T = tension_per_omega2(rotor, r)

    def integ(a, A, B):
        return (A * (a * wq)[:, None]).T @ B

    M = integ(m, Pw, Pw) - integ(m * e, Pw, Pt) - integ(m * e, Pt, Pw)
    Mtt = integ(I, Pt, Pt)
    K2tt = Mtt.copy()
    if mesh.fidelity != "rigid":
        # average of consistent and lumped torsion mass; the lumped mass of node i is the
        # integral of I phi_i (the linear shapes sum to one only with the clamped root node, so a
        # row sum over the free coordinates would lose half of the first element's mass)
        Mtt = 0.5 * (Mtt + np.diag(Pt.T @ (I * wq)))
        K2tt = Mtt.copy()
    M += Mtt
    if added_mass is not None:
        ma, sa, ia = (f(r) for f in added_mass)
        M += integ(ma, Pw, Pw) + integ(sa, Pw, Pt) + integ(sa, Pt, Pw) + integ(ia, Pt, Pt)
    K0 = integ(EI, ddPw, ddPw) + integ(GJ, dPt, dPt)
    K2 = integ(T, dPw, dPw) + K2tt - integ(m * e * r, dPw, Pt) - integ(m * e * r, Pt, dPw)
    r0 = mesh.root_m
    K2[0, 0] += r0 * tension_per_omega2(rotor, np.array([r0]))[0]  # hub bar carries T(r0)

    L = rotor.blade_length_m
    if mesh.fidelity in ("rigid", "fem-torsion"):
        K0[1, 1] += K_FLAP_SPRING * st.mean("ei_flap_nm2") / L
    if mesh.fidelity == "rigid":
        K0[2, 2] += K_TORSION_SPRING * st.mean("gj_nm2") / L

    pm = rotor.point_mass
    if pm is not None and pm.mass_kg > 0:
        rp = np.array([pm.r_m])
        a, da, _, b, _ = mesh.shapes(rp)
        Pw1 = np.concatenate([[pm.r_m], a[0]]); dPw1 = np.concatenate([[1.0], da[0]])
        Pt1 = np.concatenate([[0.0], b[0]])
        ep = (pm.x_chord - st.at("x_ea", pm.r_m)) * st.at("chord_m", pm.r_m)
        v = Pw1 - ep * Pt1
        M += pm.mass_kg * np.outer(v, v)
        K2 += pm.mass_kg * ep**2 * np.outer(Pt1, Pt1)
        K2 -= pm.mass_kg * ep * pm.r_m * (np.outer(dPw1, Pt1) + np.outer(Pt1, dPw1))
    return M, K0, K2


def assemble(rotor: Rotor, mesh: BladeMesh, added_mass=None) -> RotorStructure:
    """Both blades and the teeter hinge, plus the lag/rotor-speed inertias."""
    Mb, K0b, K2b = blade_matrices(rotor, mesh, added_mass)
    nq = mesh.n_q
    n = 1 + 2 * nq
    M = np.zeros((n, n)); K0 = np.zeros((n, n)); K2 = np.zeros((n, n))
    for b, sign in ((0, 1.0), (1, -1.0)):
        idx = np.concatenate([[0], 1 + b * nq + np.arange(nq)])
        S = np.ones(1 + nq); S[0] = sign  # blade 1 sees -beta
        for G, B in ((M, Mb), (K0, K0b), (K2, K2b)):
            G[np.ix_(idx, idx)] += B * np.outer(S, S)
    M[0, 0] += rotor.hub_teeter_inertia_kg_m2
    K2[0, 0] += rotor.hub_teeter_inertia_kg_m2  # the hub bar's own centrifugal restoring moment
    kinds = ("teeter",) + tuple(["flap"] * mesh.n_flap + ["torsion"] * mesh.n_torsion) * 2
    blade_of = (-1,) + (0,) * nq + (1,) * nq

    st = rotor.stations
    r, wq = quadrature(rotor, mesh)
    m = st.at("mass_kg_m", r)
    r0 = mesh.root_m
    I_lag = float(np.sum(wq * m * (r - r0) ** 2))
    S_lag = float(np.sum(wq * m * r * (r - r0)))
    I_blade = float(np.sum(wq * m * r**2))
    k2_lag = float(r0 * np.sum(wq * m * (r - r0)))
    pm = rotor.point_mass
    if pm is not None:
        I_lag += pm.mass_kg * (pm.r_m - r0) ** 2
        S_lag += pm.mass_kg * pm.r_m * (pm.r_m - r0)
        I_blade += pm.mass_kg * pm.r_m**2
        k2_lag += r0 * pm.mass_kg * (pm.r_m - r0)
    k_lag = K_FLAP_SPRING * st.mean("ei_lag_nm2") / rotor.blade_length_m
    I_R = rotor.hub_polar_inertia_kg_m2 + 2.0 * I_blade
    return RotorStructure(mesh, M, K0, K2, kinds, blade_of, I_R, I_lag, S_lag, k_lag, k2_lag)
