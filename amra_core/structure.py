"""Structural matrices of the teetering two-bladed rotor (in vacuo), by Galerkin integration.

Generalised coordinates of the flap/torsion system: ``x = [beta, q_blade0, q_blade1]`` with the
teeter angle ``beta`` shared by both blades (blade 0 displaced by ``+beta r``, blade 1 by
``-beta r``) and each blade's coordinates ``q`` from :mod:`amra_core.shapes`. The equations are
``M x'' + (K0 + Omega^2 K2) x = Q`` with, per unit span (``e = (x_cg - x_ea) c`` aft positive):

* kinetic energy ``1/2 m (w' - e theta')^2 + 1/2 I_ea theta'^2`` (dots), giving the inertial
  flap-torsion coupling through the CG offset;
* elastic energy ``1/2 EI w''^2 + 1/2 GJ theta'^2`` (FEM levels) or root springs (rigid level);
* centrifugal energy ``1/2 T(r) (w'^2 + k_A^2 theta'^2)`` (the second part, tension-torsion or
  "trapeze", only at the FEM torsion levels, ``k_A^2 = I_ea/m``) with ``T = Omega^2 int_r^R m rho drho`` (stiffening;
  the rigid hub bar between the axis and the root carries ``T(r0)`` for the teeter motion, so a
  rigid teetering rotor has exactly 1/rev), the propeller moment ``1/2 Omega^2 I_ea theta^2``
  (``nu^2 = nu0^2 + 1``), and ``-Omega^2 m e r w' theta``: a coned blade with its CG aft of the
  EA is pitched nose up by centrifugal force;
* static centrifugal loads per Omega^2 ``f`` of the built-in pitch ``theta0(r)`` (incidence + twist):
  ``-int I_ea theta0 phi_t`` on torsion (the propeller moment of the static pitch) and
  ``+int m e r theta0 phi_w'`` on flap, so ``M x'' + (K0 + Omega^2 K2) x = Q + Omega^2 f``;
* the gyroscopic (Coriolis) coupling with the rotor speed, ``Omega g(x)^T x'`` in the Lagrangian with
  ``g = g0 + H x`` (the in-plane angular momentum of the deflected blade), and the polar inertia
  ``J(x) = I_R + 2 f^T x - x^T K2 x``; see ``docs/model-equations.md`` for the derivation.

Equivalent root springs of the ``rigid`` level (model-notes §2), chosen so that the uniform rigid
blade has the first non-rotating frequency of the uniform cantilever: torsion
``k_theta = (pi/2)^2 GJ/L`` (or, with ``rigid_spring = "static"``, the same load-weighted static
twist under an ``r^2`` moment); collective flap ``k_beta = 1.8751^4 EI/(3L)`` (rigid blade inertia
``m L^3/3``); lag likewise with EI_lag. GJ and EI are span averages for a non-uniform blade. The
cyclic flap (hub swinging against the blades) gets its own root spring and an effective teeter
inertia, derived from the same blade's FEM pinned-free mode (:mod:`amra_core.rigid_equivalence`).

Lag: one rigid lead-lag angle per blade about a root spring at ``r0`` (paper: Lagrange
equations), inertially coupled with rotor speed: ``[[I_R, S, S], [S, I_z, 0], [S, 0, I_z]]``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .rigid_equivalence import CyclicFlapEquivalence, apply_cyclic_flap, derive_cyclic_flap, torsion_spring_nm_rad
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
    return _outboard_integral(rotor, r, lambda rho: rho, lambda pm: pm.r_m)


def chord_moment_outboard(rotor: Rotor, r) -> np.ndarray:
    """``int_r^R m e drho`` (+ point mass ``m_p e_p``) [kg]: the chordwise first moment outboard of
    ``r`` (``e`` = CG aft of the EA), the weight of the foreshortening term in the gyroscopic
    coupling ``-int m e u'`` (see :func:`gyroscopic_terms`)."""
    st = rotor.stations

    def e(rho):
        return (st.at("x_cg", rho) - st.at("x_ea", rho)) * st.at("chord_m", rho)

    return _outboard_integral(rotor, r, e, lambda pm: _point_mass_offset(rotor))


def _point_mass_offset(rotor: Rotor) -> float:
    """Chordwise offset of the point mass aft of the EA [m]."""
    pm, st = rotor.point_mass, rotor.stations
    return float((pm.x_chord - st.at("x_ea", pm.r_m)) * st.at("chord_m", pm.r_m))


def _outboard_integral(rotor: Rotor, r, weight, pm_weight) -> np.ndarray:
    """``int_r^R m(rho) weight(rho) drho`` plus the point mass ``m_p pm_weight`` outboard of r."""
    st = rotor.stations
    fine = np.linspace(st.r_m[0], st.r_m[-1], 4001)
    fine = np.union1d(fine, st.r_m)
    f = st.at("mass_kg_m", fine) * weight(fine)
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(fine))])
    T = cum[-1] - np.interp(r, fine, cum)
    if rotor.point_mass is not None:
        pm = rotor.point_mass
        T = T + np.where(np.asarray(r) < pm.r_m, pm.mass_kg * pm_weight(pm), 0.0)
    return T


@dataclass(frozen=True)
class RotorStructure:
    """Assembled matrices. Flap/torsion: ``M``, ``K0``, ``K2`` over ``[beta, q0, q1]``.
    Lag/rotor: polar inertia ``I_R`` [kg m^2] (undeflected), lag inertia ``I_lag``, coupling
    ``S_lag``, spring ``k_lag`` [N m/rad] and centrifugal lag stiffness per Omega^2 ``k2_lag``.
    Static pitch and rotor-speed coupling: ``f``, ``g0``, ``H`` (:func:`blade_pitch_and_gyro`)."""

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
    f: np.ndarray  #: static pitch load per Omega^2 [kg m] (see :func:`blade_pitch_and_gyro`)
    g0: np.ndarray  #: gyroscopic coupling with the rotor speed at x = 0 [kg m]
    H: np.ndarray  #: gyroscopic coupling per coordinate (symmetric) [kg m]
    f_lag: float  #: static lag moment per Omega^2 of the chordwise CG offset, r0 int m e [kg m]
    S2: np.ndarray  #: (2 blades, n, n): lag coupling S_b(x) = S_lag - 1/2 x^T S2[b] x
    I2: np.ndarray  #: (2 blades, n, n): lag inertia I_b(x) = I_lag - x^T I2[b] x
    #: (2 blades, n): lag-pivot gyroscopic coupling at x = 0, ``gl_b = gl0[b] + HL[b] x`` [kg m]:
    #: the in-plane momentum of blade b's flap/twist motion about its lag pivot (see
    #: :func:`blade_pitch_and_gyro`)
    gl0: np.ndarray = None
    HL: np.ndarray = None  #: (2 blades, n, n): blade b's part of ``H`` (``HL[0] + HL[1] = H``)

    @property
    def n(self) -> int:
        return self.M.shape[0]


def _blade_shapes(mesh: BladeMesh, r):
    """(Pw, dPw, ddPw, Pt, dPt) over ``[beta, q]`` at radii r (teeter column: ``w = beta r``)."""
    pw, dpw, ddpw, pt, dpt = mesh.shapes(r)
    n = 1 + mesh.n_q
    Pw = np.zeros((len(r), n)); Pw[:, 0] = r; Pw[:, 1:] = pw
    dPw = np.zeros_like(Pw); dPw[:, 0] = 1.0; dPw[:, 1:] = dpw
    ddPw = np.zeros_like(Pw); ddPw[:, 1:] = ddpw
    Pt = np.zeros_like(Pw); Pt[:, 1:] = pt
    dPt = np.zeros_like(Pw); dPt[:, 1:] = dpt
    return Pw, dPw, ddPw, Pt, dPt


def trapeze_radius2(rotor: Rotor, r) -> np.ndarray:
    """Squared polar radius of gyration of the tension-carrying section about the EA, ``k_A^2``
    [m^2], estimated as ``I_ea / m`` (exact for a homogeneous section; the presets' torsional
    inertia is itself the estimate m (0.25 c)^2)."""
    st = rotor.stations
    return st.at("torsional_inertia_kg_m", r) / st.at("mass_kg_m", r)


def blade_matrices(rotor: Rotor, mesh: BladeMesh, added_mass=None, trapeze: bool = True, torsion: bool = True):
    """(M, K0, K2) of one blade over ``[beta, q]`` (blade displaced by ``+beta r``).

    ``torsion=False``: K0 without the torsional stiffness (GJ), which
    :func:`blade_torsion_stiffness` gives on its own (K0 is linear in GJ, and GJ enters nothing else).

    ``added_mass``: optional (m_a, s_a, i_a) callables of r for the aerodynamic apparent mass
    per length: lift ``m_a w''``, cross ``s_a``, pitch ``i_a`` (see :mod:`amra_core.model`).
    ``trapeze``: include the tension-torsion stiffness ``int T k_A^2 theta'^2`` (FEM torsion only:
    the rigid blade's twist is uniform, so the term is zero there)."""
    st = rotor.stations
    r, wq = quadrature(rotor, mesh)
    Pw, dPw, ddPw, Pt, dPt = _blade_shapes(mesh, r)

    c = st.at("chord_m", r)
    m = st.at("mass_kg_m", r)
    e = (st.at("x_cg", r) - st.at("x_ea", r)) * c
    I = st.at("torsional_inertia_kg_m", r)
    EI = st.at("ei_flap_nm2", r)
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
    K0 = integ(EI, ddPw, ddPw)
    if torsion:
        K0 += _blade_torsion_stiffness(rotor, mesh, r, wq, dPt)
    K2 = integ(T, dPw, dPw) + K2tt - integ(m * e * r, dPw, Pt) - integ(m * e * r, Pt, dPw)
    if trapeze:
        K2 += integ(T * trapeze_radius2(rotor, r), dPt, dPt)
    r0 = mesh.root_m
    K2[0, 0] += r0 * tension_per_omega2(rotor, np.array([r0]))[0]  # hub bar carries T(r0)

    L = rotor.blade_length_m
    if mesh.fidelity in ("rigid", "fem-torsion"):
        K0[1, 1] += K_FLAP_SPRING * st.mean("ei_flap_nm2") / L

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


def _blade_torsion_stiffness(rotor: Rotor, mesh: BladeMesh, r, wq, dPt) -> np.ndarray:
    """One blade's torsional stiffness over ``[beta, q]``: ``int GJ theta'^2`` (FEM levels) or the
    rigid level's root spring (``mesh.torsion_spring``: ``frequency`` ``k_theta = (pi/2)^2 GJ/L``,
    or ``static``, :func:`amra_core.rigid_equivalence.torsion_spring_nm_rad`)."""
    if mesh.fidelity == "rigid":
        K = np.zeros((1 + mesh.n_q, 1 + mesh.n_q))
        K[2, 2] = torsion_spring_nm_rad(rotor, mesh.torsion_spring)
        return K
    GJ = rotor.stations.at("gj_nm2", r)
    return (dPt * (GJ * wq)[:, None]).T @ dPt


def blade_torsion_stiffness(rotor: Rotor, mesh: BladeMesh) -> np.ndarray:
    """One blade's torsional stiffness over ``[beta, q]`` [N m/rad per coordinate]. The rigid
    level's root spring needs no quadrature (a map compiles a model per GJ it visits)."""
    if mesh.fidelity == "rigid":
        return _blade_torsion_stiffness(rotor, mesh, None, None, None)
    r, wq = quadrature(rotor, mesh)
    _, _, _, _, dPt = _blade_shapes(mesh, r)
    return _blade_torsion_stiffness(rotor, mesh, r, wq, dPt)


def torsion_stiffness(rotor: Rotor, mesh: BladeMesh) -> np.ndarray:
    """Both blades' torsional stiffness over ``[beta, q0, q1]``: the GJ part of K0 of :func:`assemble`
    (``assemble(..., torsion=False).K0 + torsion_stiffness(...)`` is ``assemble(...).K0``)."""
    Kb = blade_torsion_stiffness(rotor, mesh)
    K = np.zeros((1 + 2 * mesh.n_q, 1 + 2 * mesh.n_q))
    for _, idx, S in _blade_slots(mesh.n_q):
        K[np.ix_(idx, idx)] += Kb * np.outer(S, S)
    return K


def cyclic_flap_equivalence(rotor: Rotor) -> CyclicFlapEquivalence:
    """Effective teeter inertia and cyclic root spring of ``rotor``'s equivalent rigid blade, derived
    from its FEM pinned-free (cyclic flap) mode (:mod:`amra_core.rigid_equivalence`)."""
    return derive_cyclic_flap(rotor, blade_matrices, K_FLAP_SPRING)


def _blade_slots(nq: int):
    """Per blade b: (b, its rows in [beta, q0, q1], the signs of its coordinates: blade 1 sees -beta)."""
    for b, sign in ((0, 1.0), (1, -1.0)):
        S = np.ones(1 + nq); S[0] = sign
        yield b, np.concatenate([[0], 1 + b * nq + np.arange(nq)]), S


def blade_pitch_and_gyro(rotor: Rotor, mesh: BladeMesh, trapeze: bool = True, lag_pivot: bool = False):
    """(f, g0, H) of one blade over ``[beta, q]``: the terms that the static pitch and the rotor
    speed add to the Lagrangian (derivation: ``docs/model-equations.md``).

    * ``f`` [kg m]: static centrifugal load per Omega^2 of the built-in pitch
      ``theta0 = incidence + twist``: ``int m e r theta0 phi_w' - int I_ea theta0 phi_t``; it is
      also the linear part of the polar inertia ``J(x) = J0 + 2 f^T x - x^T K2 x``;
    * ``g0 + H x`` [kg m]: the blade's in-plane angular momentum per unit coordinate rate,
      ``G = (g0 + H x)^T x'`` = ``d/dt F(x)`` with
      ``F = int [m e r theta0 theta - m e u + I_ea (theta0 + theta) w']`` (the second-order
      ``m e r theta^2/2`` is left out, see the comment below),
      ``u = 1/2 int_0^r (w'^2 + k_A^2 theta'^2)`` the foreshortening (hub bar included), so
      ``g0 = int (m e r theta0 phi_t + I_ea theta0 phi_w')`` and ``H`` = the Hessian of F.

    ``lag_pivot=True``: the same momentum about the blade's lag pivot at ``r0`` instead of the
    shaft, ``int [(X - r0) Y' - Y X'] dm`` (the coupling with the lag rate ``zeta_b'``): the arm
    ``r`` of the ``m e r theta0`` term becomes ``r - r0``; ``Y X'`` does not depend on the pivot, so
    ``H`` is the same. It is third order (lag rate x pitch x deflection rate) but kept: without it
    the twist's in-plane momentum acts on the rotor speed alone, whose inertia with both blades
    free to lag is the small ``J - sum S^2/I_z`` (1.9 kg m^2), and a fast twist oscillation swung
    the rotor speed by +-25 % (docs/model-equations.md section 2)."""
    st = rotor.stations
    r, wq = quadrature(rotor, mesh)
    _, dPw, _, Pt, dPt = _blade_shapes(mesh, r)
    m = st.at("mass_kg_m", r)
    e = (st.at("x_cg", r) - st.at("x_ea", r)) * st.at("chord_m", r)
    I = st.at("torsional_inertia_kg_m", r)
    th0 = rotor.incidence_rad + st.at("twist_rad", r)
    Te = chord_moment_outboard(rotor, r)

    def integ(a, A, B):
        return (A * (a * wq)[:, None]).T @ B

    def vec(a, A):
        return A.T @ (a * wq)

    f = vec(m * e * r * th0, dPw) - vec(I * th0, Pt)
    arm = r - mesh.root_m if lag_pivot else r
    g0 = vec(m * e * arm * th0, Pt) + vec(I * th0, dPw)
    # The in-plane momentum of the pitching CG, m e r theta_e theta_e' (a ``m e r theta_e^2/2`` in F),
    # is left out: its lag counterpart (the same motion about the lag pivot) is not modelled, and
    # with the small rotor-speed inertia of blades free to lag (J - sum S^2/I_z ~ 2 kg m^2) the
    # pair (theta, Omega) alone has an indefinite mass matrix once m e r theta_e is ~0.5 rad
    # worth (a GJ 1 -> 1e6 slider jump ran into it). docs/model-equations.md section 2.
    H = -integ(Te, dPw, dPw) + integ(I, Pt, dPw) + integ(I, dPw, Pt)
    if trapeze:
        H -= integ(Te * trapeze_radius2(rotor, r), dPt, dPt)
    r0 = mesh.root_m
    H[0, 0] -= r0 * chord_moment_outboard(rotor, np.array([r0]))[0]  # hub bar foreshortening
    pm = rotor.point_mass
    if pm is not None and pm.mass_kg > 0:
        _, dPw1, _, Pt1, _ = (a[0] for a in _blade_shapes(mesh, np.array([pm.r_m])))
        ep = _point_mass_offset(rotor)
        th0p = rotor.incidence_rad + float(st.at("twist_rad", pm.r_m))
        mp = pm.mass_kg
        f += mp * (pm.r_m * ep * th0p * dPw1 - ep**2 * th0p * Pt1)
        g0 += mp * ((pm.r_m - (r0 if lag_pivot else 0.0)) * ep * th0p * Pt1 + ep**2 * th0p * dPw1)
        H += mp * ep**2 * (np.outer(Pt1, dPw1) + np.outer(dPw1, Pt1))
    return f, g0, H


def blade_lag_geometry(rotor: Rotor, mesh: BladeMesh):
    """(S2, I2) of one blade over ``[beta, q]``: how flapping (and teeter) shortens the blade's
    lag arm. With the foreshortening ``u(r) = 1/2 (r0 beta^2 + int_r0^r w'^2)`` the horizontal
    radius is ``r - u`` and the lag pivot sits at ``r0 - u(r0)``, so the lag coupling and lag
    inertia are ``S(x) = int m (r - u)(r - r0 - u + u(r0)) = S0 - 1/2 x^T S2 x`` and
    ``I_z(x) = I_z0 - x^T I2 x`` to second order, with ``S2 = r0 int m (r - r0) e_beta e_beta^T
    + int T_S w'w'^T``, ``T_S(s) = int_s^R m (2r - r0)``, and ``I2 = int T_I w'w'^T``,
    ``T_I(s) = int_s^R m (r - r0)``. They keep the rotor-speed inertia of the blades free to lag,
    ``J - sum S^2/I_z``, independent of coning (exactly so for a rigid flap), and give the
    classical flap-lag Coriolis forces."""
    st = rotor.stations
    r, wq = quadrature(rotor, mesh)
    _, dPw, _, _, _ = _blade_shapes(mesh, r)
    r0 = mesh.root_m
    TS = _outboard_integral(rotor, r, lambda rho: 2.0 * rho - r0, lambda pm: 2.0 * pm.r_m - r0)
    TI = _outboard_integral(rotor, r, lambda rho: rho - r0, lambda pm: pm.r_m - r0)

    def integ(a, A, B):
        return (A * (a * wq)[:, None]).T @ B

    S2 = integ(TS, dPw, dPw)
    S2[0, 0] += r0 * float(_outboard_integral(rotor, np.array([r0]), lambda rho: rho - r0,
                                                  lambda pm: pm.r_m - r0)[0])
    return S2, integ(TI, dPw, dPw)


def assemble(rotor: Rotor, mesh: BladeMesh, added_mass=None, trapeze: bool = True,
             torsion: bool = True) -> RotorStructure:
    """Both blades and the teeter hinge, plus the lag/rotor-speed inertias. ``torsion=False``: K0
    without its GJ part (:func:`torsion_stiffness`), the only part that depends on GJ, so a GJ
    sweep assembles the rest once (:func:`amra_core.model.compile_model`)."""
    Mb, K0b, K2b = blade_matrices(rotor, mesh, added_mass, trapeze, torsion)
    fb, g0b, Hb = blade_pitch_and_gyro(rotor, mesh, trapeze)
    _, gl0b, _ = blade_pitch_and_gyro(rotor, mesh, trapeze, lag_pivot=True)
    S2b, I2b = blade_lag_geometry(rotor, mesh)
    nq = mesh.n_q
    n = 1 + 2 * nq
    S2 = np.zeros((2, n, n)); I2 = np.zeros((2, n, n)); HL = np.zeros((2, n, n)); gl0 = np.zeros((2, n))
    M = np.zeros((n, n)); K0 = np.zeros((n, n)); K2 = np.zeros((n, n)); H = np.zeros((n, n))
    f = np.zeros(n); g0 = np.zeros(n)
    for b, idx, S in _blade_slots(nq):
        for G, B in ((M, Mb), (K0, K0b), (K2, K2b), (H, Hb)):
            G[np.ix_(idx, idx)] += B * np.outer(S, S)
        f[idx] += fb * S
        g0[idx] += g0b * S
        gl0[b][idx] = gl0b * S
        HL[b][np.ix_(idx, idx)] = Hb * np.outer(S, S)
        S2[b][np.ix_(idx, idx)] = S2b * np.outer(S, S)
        I2[b][np.ix_(idx, idx)] = I2b * np.outer(S, S)
    M[0, 0] += rotor.hub_teeter_inertia_kg_m2
    K2[0, 0] += rotor.hub_teeter_inertia_kg_m2  # the hub bar's own centrifugal restoring moment
    if mesh.fidelity in ("rigid", "fem-torsion"):  # the equivalent rigid blade's cyclic flap
        apply_cyclic_flap(cyclic_flap_equivalence(rotor), rotor, mesh, M, K0, K2, (1, 1 + nq))
    kinds = ("teeter",) + tuple(["flap"] * mesh.n_flap + ["torsion"] * mesh.n_torsion) * 2
    blade_of = (-1,) + (0,) * nq + (1,) * nq

    st = rotor.stations
    r, wq = quadrature(rotor, mesh)
    m = st.at("mass_kg_m", r)
    r0 = mesh.root_m
    # chordwise second moment of the section (thin section: the torsional inertia about the EA)
    # adds to the polar and lag inertias; the chordwise first moment m e gives a static lag
    # moment Omega^2 r0 int m e (a CG aft of the lag pivot line is pulled forwards)
    i_sec = float(np.sum(wq * st.at("torsional_inertia_kg_m", r)))
    me = float(np.sum(wq * m * (st.at("x_cg", r) - st.at("x_ea", r)) * st.at("chord_m", r)))
    I_lag = float(np.sum(wq * m * (r - r0) ** 2)) + i_sec
    S_lag = float(np.sum(wq * m * r * (r - r0))) + i_sec
    I_blade = float(np.sum(wq * m * r**2)) + i_sec
    k2_lag = float(r0 * np.sum(wq * m * (r - r0)))
    f_lag = r0 * me
    pm = rotor.point_mass
    if pm is not None:
        ep = _point_mass_offset(rotor)
        I_lag += pm.mass_kg * ((pm.r_m - r0) ** 2 + ep**2)
        S_lag += pm.mass_kg * (pm.r_m * (pm.r_m - r0) + ep**2)
        I_blade += pm.mass_kg * (pm.r_m**2 + ep**2)
        k2_lag += r0 * pm.mass_kg * (pm.r_m - r0)
        f_lag += r0 * pm.mass_kg * ep
    k_lag = K_FLAP_SPRING * st.mean("ei_lag_nm2") / rotor.blade_length_m
    I_R = rotor.hub_polar_inertia_kg_m2 + 2.0 * I_blade
    return RotorStructure(mesh, M, K0, K2, kinds, blade_of, I_R, I_lag, S_lag, k_lag, k2_lag, f, g0, H, f_lag, S2, I2,
                          gl0, HL)
