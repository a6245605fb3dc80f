"""Compile a (rotor, flight, settings) description into the flat arrays the kernels use.

This is the one hop between the friendly, validated objects and the jitted kernels:
everything a kernel needs is a float64 array or scalar in :class:`ModelArrays`. Changing a
slider (GJ, EA, CG) means compiling again (a few milliseconds) and continuing from the same state
vector, whose layout depends only on the fidelity, element and station counts.

State vector ``y`` (SI): ``[psi, Omega, V_d, v0, zeta0, zeta1, zeta0', zeta1', x(n_s), x'(n_s),
wagner(2 blades x n_st x 2)]`` with ``x = [beta, q_blade0, q_blade1]`` (:mod:`amra_core.structure`),
``V_d`` the descent rate (positive down) and ``v0`` the uniform induced velocity (positive down).
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np

from .airfoil import compile_airfoil, load_airfoil
from .flight import FlightCondition, SolverSettings
from .rotor import Rotor
from .shapes import make_mesh
from .structure import assemble, torsion_stiffness

# the array layout lives in amra_core.layout (below the kernels); re-exported here for callers
from .layout import (  # noqa: F401
    L_FHORIZ, L_FVERT, L_HFORCE, L_THRUST, L_TORQUE, L_VM, ModelArrays, N_LOADS, N_P, N_S_COLS, N_Y_FIXED,
    P_AERO, P_ALPHA_S, P_A_SOUND, P_CLAG, P_FLAG, P_G, P_HOLD_OMEGA, P_HOLD_VD, P_ILAG, P_INFLOW3, P_IR,
    P_K2LAG, P_KLAG, P_MASS, P_NQ, P_NS, P_NST, P_QUASI_STATIC, P_R, P_R0, P_RHO, P_SLAG, P_UNIT_MASS, P_VACUUM, P_LAWSON,
    P_LAWSON_LAGS,
    P_VH, S_A,
    S_C, S_R, S_THETA0, S_W, S_XAC, S_XEA, WAGNER_A, WAGNER_B, Y_OMEGA, Y_PSI, Y_V0, Y_VD, Y_ZETA0, Y_ZETA1,
    Y_ZETAD0, Y_ZETAD1, station_shapes, station_vectors, with_coordinate_products)


@dataclass(frozen=True)
class CompiledModel:
    """Arrays plus the layout facts the Python layer needs."""

    arrays: ModelArrays
    n_q: int
    n_s: int  #: number of structural coordinates in the state (modal if reduced)
    n_st: int
    kinds: tuple
    structure: object
    phi: np.ndarray  #: physical x = phi @ coordinates (identity when not reduced)
    phi_pinv: np.ndarray  #: coordinates = phi_pinv @ physical x
    rotor: Rotor
    flight: FlightCondition
    settings: SolverSettings

    @property
    def n_inflow_harmonics(self) -> int:
        """2 (sine and cosine inflow states, last in the state) with the three-state model."""
        return 2 if self.settings.inflow == "three-state" else 0

    @property
    def n_y(self) -> int:
        return N_Y_FIXED + 2 * self.n_s + 4 * self.n_st + self.n_inflow_harmonics

    def inflow_harmonics_slice(self):
        """First-harmonic inflow [v_s, v_c] in m/s (empty with uniform inflow)."""
        return slice(self.n_y - self.n_inflow_harmonics, self.n_y)

    def x_slice(self):
        return slice(N_Y_FIXED, N_Y_FIXED + self.n_s)

    def xd_slice(self):
        return slice(N_Y_FIXED + self.n_s, N_Y_FIXED + 2 * self.n_s)

    def aero_slice(self):
        return slice(N_Y_FIXED + 2 * self.n_s, N_Y_FIXED + 2 * self.n_s + 4 * self.n_st)

    def torsion_index(self, blade: int) -> np.ndarray:
        """Positions in the physical ``x`` of blade ``blade``'s torsion coordinates."""
        s = self.structure
        return np.array([i for i, (k, b) in enumerate(zip(s.kinds, s.blade_of)) if k == "torsion" and b == blade])

    def physical(self, y: np.ndarray):
        """(x, x') in the physical FEM coordinates [beta, q0, q1] of state ``y``."""
        return self.phi @ y[self.x_slice()], self.phi @ y[self.xd_slice()]

    def set_physical(self, y: np.ndarray, x: np.ndarray, xd: np.ndarray) -> None:
        """Write physical (x, x') into state ``y`` (projected onto the retained modes)."""
        y[self.x_slice()] = self.phi_pinv @ x
        y[self.xd_slice()] = self.phi_pinv @ xd

    def with_controls(self, alpha_s_rad=None, airspeed_m_s=None, hold_omega=None, hold_vd=None,
                      quasi_static=None) -> "CompiledModel":
        """A copy with flight-control scalars changed (shaft tilt, airspeed, holds)."""
        p = self.arrays.p.copy()
        if alpha_s_rad is not None:
            p[P_ALPHA_S] = alpha_s_rad
        if airspeed_m_s is not None:
            p[P_VH] = airspeed_m_s
        if hold_omega is not None:
            p[P_HOLD_OMEGA] = float(hold_omega)
        if hold_vd is not None:
            p[P_HOLD_VD] = float(hold_vd)
        if quasi_static is not None:
            p[P_QUASI_STATIC] = float(quasi_static)
        return replace(self, arrays=self.arrays._replace(p=p))


def transfer_state(y: np.ndarray, source: "CompiledModel", target: "CompiledModel") -> np.ndarray:
    """Map a state of ``source`` onto ``target``'s layout (the modal bases, and so the number of
    structural coordinates, can differ between two stiffnesses): fixed slots are copied, the
    structure goes through the physical FEM coordinates, aerodynamic lag states are copied when
    the station layout matches and zeroed otherwise."""
    out = np.zeros(target.n_y)
    out[:N_Y_FIXED] = y[:N_Y_FIXED]
    x, xd = source.physical(y)
    target.set_physical(out, x, xd)
    if source.n_st == target.n_st:
        out[target.aero_slice()] = y[source.aero_slice()]
    if source.n_inflow_harmonics == target.n_inflow_harmonics:
        out[target.inflow_harmonics_slice()] = y[source.inflow_harmonics_slice()]
    return out


def apparent_mass(rotor: Rotor, rho: float):
    """Theodorsen's non-circulatory (apparent mass) terms per length as functions of r:
    lift ``pi rho b^2``, cross ``pi rho b^3 a``, pitch ``pi rho b^4 (1/8 + a^2)`` with
    ``b = c/2`` and ``a = 2 x_ea - 1`` (EA aft of mid-chord in semichords)."""
    st = rotor.stations

    def b(r):
        return 0.5 * st.at("chord_m", r)

    def a(r):
        return 2.0 * st.at("x_ea", r) - 1.0

    return (lambda r: np.pi * rho * b(r) ** 2,
            lambda r: np.pi * rho * b(r) ** 3 * a(r),
            lambda r: np.pi * rho * b(r) ** 4 * (0.125 + a(r) ** 2))


def compile_model(rotor: Rotor, flight: FlightCondition = FlightCondition(),
                  settings: SolverSettings = SolverSettings(), vacuum: bool = False) -> CompiledModel:
    """Compile a case. ``vacuum=True`` (conservation tests): no aerodynamic loads and no apparent
    mass, descent rate and inflow frozen, so only the rotor's own mechanics remain (with the rotor
    speed free, total energy and angular momentum about the shaft are then conserved, see
    :func:`mechanical_energy`).

    GJ enters only the torsional stiffness, so everything else (the structure without it, the
    stations, the shapes, the airfoil) is compiled once per rotor-without-GJ and reused
    (:func:`_gj_free_parts`, a small per-process cache): a column walk or a GJ slider compiles
    only the stiffness, its reduction and the projections. Every array handed to the kernels is
    the model's own."""
    parts = _gj_free_parts(rotor.with_overrides(gj_nm2=1.0), flight, settings, vacuum)
    mesh, s0 = parts.mesh, parts.structure
    s = replace(s0, K0=s0.K0 + torsion_stiffness(rotor, mesh))
    R = rotor.radius_m
    zeta = rotor.structural_damping_ratio
    omega_ref = 150.0 / R  #: the reduction's reference rotor speed [rad/s]
    phi, phi_pinv, minv, k0, k2 = _reduction(s, settings, omega_ref_rad_s=omega_ref)
    shw, shd, sht = parts.shw @ phi, parts.shd @ phi, parts.sht @ phi
    tip, teeter = parts.tip @ phi, parts.teeter @ phi
    af = parts.airfoil
    own = np.array  # a fresh, writable, contiguous copy: nothing a kernel gets is shared
    p = own(parts.p)
    p[P_NS] = phi.shape[1]
    p[P_UNIT_MASS] = float(np.array_equal(minv, np.eye(phi.shape[1])))
    # a reduced basis diagonalises K0 + Omega_ref^2 K2: its oscillators are integrated exactly
    p[P_LAWSON] = float(bool(p[P_UNIT_MASS]) and settings.integrator == "lawson")
    # and the Wagner states' decay too, in axial flight (the kernel checks the airspeed), where that
    # lengthens the step at 1.3 x the reference speed (below)
    p[P_LAWSON_LAGS] = float(settings.integrator == "lawson" and settings.aero == "theodorsen" and flight.is_axial)
    c = phi.T @ structural_damping(s, zeta) @ phi
    arrays = ModelArrays(
        p=p, minv=own(minv), k0=own(k0), k2=own(k2), c=c,
        st=own(parts.st), shw=own(shw), shd=own(shd), sht=own(sht), tip=own(tip), teeter=own(teeter),
        lag_inv=own(parts.lag_inv), af_alpha0=af.alpha0_rad, af_dalpha=af.dalpha_rad, af_cl=own(af.cl),
        af_cd=own(af.cd), af_cm=own(af.cm),
        sf=np.ascontiguousarray(phi.T @ s.f), gy0=np.ascontiguousarray(phi.T @ s.g0),
        gyh=np.ascontiguousarray(phi.T @ s.H @ phi), ugy0=np.ascontiguousarray(minv @ (phi.T @ s.g0)),
        ugyh=np.ascontiguousarray(minv @ (phi.T @ s.H @ phi)),
        ls2=np.ascontiguousarray(np.array([phi.T @ s.S2[b] @ phi for b in range(2)])),
        li2=np.ascontiguousarray(np.array([phi.T @ s.I2[b] @ phi for b in range(2)])),
        gl0=np.ascontiguousarray(np.array([phi.T @ s.gl0[b] for b in range(2)])),
        glh=np.ascontiguousarray(np.array([phi.T @ s.HL[b] @ phi for b in range(2)])),
        ugl0=np.ascontiguousarray(np.array([minv @ (phi.T @ s.gl0[b]) for b in range(2)])),
        uglh=np.ascontiguousarray(np.array([minv @ (phi.T @ s.HL[b] @ phi) for b in range(2)])),
        sv=station_vectors(parts.st), xq=None, xqd=None, kin=station_shapes(shw, shd, sht),
    )
    arrays = with_coordinate_products(arrays)
    model = CompiledModel(arrays, mesh.n_q, phi.shape[1], parts.st.shape[0], s.kinds, s, phi, phi_pinv, rotor,
                          flight, settings)
    if p[P_LAWSON_LAGS] > 0.5:  # only where it lengthens the step (fem-coupled: the rest sets it)
        exact, plain = _step_rules(model, 1.3 * omega_ref)
        p[P_LAWSON_LAGS] = float(exact > plain)
    return model


class _GjFreeParts(NamedTuple):
    """What :func:`compile_model` needs that does not depend on GJ (read-only: shared by models)."""

    mesh: object
    structure: object  #: :class:`~amra_core.structure.RotorStructure` without the torsional stiffness
    st: np.ndarray
    p: np.ndarray
    shw: np.ndarray
    shd: np.ndarray
    sht: np.ndarray
    tip: np.ndarray
    teeter: np.ndarray
    lag_inv: np.ndarray
    airfoil: object


@functools.lru_cache(maxsize=16)
def _gj_free_parts(rotor: Rotor, flight: FlightCondition, settings: SolverSettings, vacuum: bool) -> _GjFreeParts:
    """The GJ-independent parts of a compiled model, for a rotor whose GJ does not matter (the
    caller passes it with GJ 1). Measured on a rigid axial column walk (paper-boundary, 40 trims):
    the structure assembly and the airfoil resampling were 43 % of the walk's time."""
    mesh = make_mesh(settings.fidelity, rotor.root_cutout_m, rotor.radius_m, settings.n_elements,
                     settings.rigid_spring)
    rho = flight.density_kg_m3
    s = assemble(rotor, mesh, added_mass=None if vacuum else apparent_mass(rotor, rho), torsion=False)
    st_ = rotor.stations

    gx, gw = np.polynomial.legendre.leggauss(settings.n_stations)
    r0, R = rotor.root_cutout_m, rotor.radius_m
    r = r0 + 0.5 * (gx + 1.0) * (R - r0)
    w = 0.5 * gw * (R - r0)
    st = np.zeros((len(r), N_S_COLS))
    st[:, S_R] = r
    st[:, S_W] = w
    st[:, S_C] = st_.at("chord_m", r)
    st[:, S_XEA] = st_.at("x_ea", r)
    st[:, S_XAC] = st_.at("x_ac", r)
    st[:, S_THETA0] = rotor.incidence_rad + st_.at("twist_rad", r)
    st[:, S_A] = 2.0 * st[:, S_XEA] - 1.0
    pw, dpw, _, pt, _ = mesh.shapes(r)
    tw, _, _, tt, _ = mesh.shapes(np.array([R]))
    nq, n_full = mesh.n_q, s.n
    shw = np.zeros((2, len(r), n_full)); shd = np.zeros_like(shw); sht = np.zeros_like(shw)
    tip = np.zeros((2, 2, n_full))
    for b, sgn in ((0, 1.0), (1, -1.0)):
        cols = slice(1 + b * nq, 1 + (b + 1) * nq)
        shw[b, :, 0] = sgn * r; shd[b, :, 0] = sgn
        shw[b, :, cols] = pw; shd[b, :, cols] = dpw; sht[b, :, cols] = pt
        tip[b, 0, 0] = sgn * R
        tip[b, 0, cols] = tw[0]; tip[b, 1, cols] = tt[0]
    teeter = np.zeros(n_full); teeter[0] = 1.0

    p = np.zeros(N_P)
    p[P_RHO] = rho
    p[P_A_SOUND] = flight.speed_of_sound_m_s
    p[P_G] = flight.gravity_m_s2
    p[P_MASS] = rotor.vehicle_mass_kg
    p[P_R] = R
    p[P_R0] = r0
    p[P_VH] = flight.airspeed_m_s
    p[P_AERO] = 1.0 if settings.aero == "theodorsen" else 0.0
    p[P_IR], p[P_ILAG], p[P_SLAG], p[P_KLAG], p[P_K2LAG] = s.I_R, s.I_lag, s.S_lag, s.k_lag, s.k2_lag
    p[P_NQ], p[P_NST] = mesh.n_q, len(r)
    zeta = rotor.structural_damping_ratio
    p[P_INFLOW3] = 1.0 if settings.inflow == "three-state" else 0.0
    p[P_VACUUM] = 1.0 if vacuum else 0.0
    p[P_FLAG] = s.f_lag
    p[P_CLAG] = 2.0 * zeta * np.sqrt(s.k_lag * s.I_lag)  # blade lag mode clamped at the hub
    lag_m = np.array([[s.I_R, s.S_lag, s.S_lag], [s.S_lag, s.I_lag, 0.0], [s.S_lag, 0.0, s.I_lag]])
    af = compile_airfoil(load_airfoil(rotor.airfoil))
    parts = _GjFreeParts(mesh, s, st, p, shw, shd, sht, tip, teeter, np.linalg.inv(lag_m), af)
    for a in (st, p, shw, shd, sht, tip, teeter, parts.lag_inv, af.cl, af.cd, af.cm, *(
            v for v in vars(s).values() if isinstance(v, np.ndarray))):
        a.flags.writeable = False  # shared by every model of this rotor: copied, never changed
    return parts


def polar_inertia(model: CompiledModel, y: np.ndarray) -> float:
    """Polar inertia of the deflected rotor about the shaft [kg m^2]:
    ``J = I_R + 2 f^T x - x^T K2 x + 2 f_lag (zeta0 + zeta1) - k2_lag (zeta0^2 + zeta1^2)``
    (docs/model-equations.md)."""
    a = model.arrays
    x = y[model.x_slice()]
    z = y[Y_ZETA0:Y_ZETA0 + 2]
    return float(a.p[P_IR] + 2.0 * a.sf @ x - x @ a.k2 @ x + 2.0 * a.p[P_FLAG] * z.sum()
                 - a.p[P_K2LAG] * (z @ z))


def lag_inertias(model: CompiledModel, y: np.ndarray):
    """Per blade (lag coupling S_b, lag inertia I_b) [kg m^2] of the deflected blade."""
    a = model.arrays
    x = y[model.x_slice()]
    S = np.array([a.p[P_SLAG] - 0.5 * x @ a.ls2[b] @ x for b in range(2)])
    I = np.array([a.p[P_ILAG] - x @ a.li2[b] @ x for b in range(2)])
    return S, I


def angular_momentum(model: CompiledModel, y: np.ndarray) -> float:
    """Angular momentum of the rotor about the shaft [kg m^2/s]:
    ``Omega J(x) + sum_b S_b(x) zeta_b' + (g0 + H x)^T x'``."""
    a = model.arrays
    x, xd = y[model.x_slice()], y[model.xd_slice()]
    g = a.gy0 + a.gyh @ x
    S, _ = lag_inertias(model, y)
    return float(y[Y_OMEGA] * polar_inertia(model, y) + S @ y[Y_ZETAD0:Y_ZETAD0 + 2] + g @ xd)


def mechanical_energy(model: CompiledModel, y: np.ndarray) -> float:
    """Total mechanical energy of the rotor [J] (kinetic, in the inertial frame, plus strain):
    ``1/2 x'^T M x' + 1/2 sum I_b zeta_b'^2 + 1/2 Omega^2 J + Omega (sum S_b zeta_b' + g^T x')
    + sum zeta_b' gl_b^T x' + 1/2 x^T K0 x + 1/2 k_lag |zeta|^2`` (``gl_b = gl0_b + HL_b x``, the
    lag-pivot coupling). The structural mass is recovered from ``minv``, so the
    value is the mechanical energy only for a ``vacuum`` model (no apparent mass)."""
    a = model.arrays
    x, xd = y[model.x_slice()], y[model.xd_slice()]
    z, zd = y[Y_ZETA0:Y_ZETA0 + 2], y[Y_ZETAD0:Y_ZETAD0 + 2]
    om = y[Y_OMEGA]
    M = np.linalg.inv(a.minv)
    g = a.gy0 + a.gyh @ x
    S, I = lag_inertias(model, y)
    gl = np.array([a.gl0[b] + a.glh[b] @ x for b in range(2)])
    kin = 0.5 * xd @ M @ xd + 0.5 * I @ zd**2 + 0.5 * om**2 * polar_inertia(model, y) \
        + om * (S @ zd + g @ xd) + zd @ (gl @ xd)
    return float(kin + 0.5 * x @ a.k0 @ x + 0.5 * a.p[P_KLAG] * (z @ z))


def structural_damping(s, zeta: float) -> np.ndarray:
    """Viscous damping ``C = M Phi diag(2 zeta omega_i) Phi^T M`` in the physical coordinates
    [beta, q0, q1]: every in-vacuo mode of the non-rotating blade (``K0``, ``M`` mass-normalised
    ``Phi``) gets the damping ratio ``zeta``; the teeter mode (zero frequency at rest) gets none.
    Centrifugal stiffening leaves C unchanged, so a mode's ratio falls as the rotor speeds up."""
    if zeta <= 0.0:
        return np.zeros_like(s.M)
    import scipy.linalg as sl
    w2, V = sl.eigh(s.K0, s.M)
    omega = np.sqrt(np.clip(w2, 0.0, None))
    MV = s.M @ V
    return MV @ np.diag(2.0 * zeta * omega) @ MV.T


def _reduction(s, settings: SolverSettings, omega_ref_rad_s: float):
    """Ritz reduction of the FEM structure onto its modes below ``settings.max_mode_hz`` at the
    reference rotor speed (mass-normalised, apparent mass included), or none.

    The projected ``K0 + Omega^2 K2`` stays exact within the retained subspace at every rotor
    speed; what is dropped is the response of modes above the cut-off, which would otherwise set
    the explicit time step (the stiffest FEM mode of 10 Hermite elements is ~2 kHz). The rigid
    level is never reduced. Convergence in ``max_mode_hz`` is tested."""
    n = s.n
    if settings.fidelity == "rigid" or settings.max_mode_hz is None:
        eye = np.eye(n)
        return eye, eye, np.linalg.inv(s.M), s.K0, s.K2
    import scipy.linalg as sl
    w2, V = sl.eigh(s.K0 + omega_ref_rad_s**2 * s.K2, s.M)
    keep = np.sqrt(np.maximum(w2, 0.0)) / (2 * np.pi) <= settings.max_mode_hz
    keep[:3] = True
    phi = V[:, keep]  # M-orthonormal: phi.T M phi = I
    return phi, phi.T @ s.M, np.eye(phi.shape[1]), phi.T @ s.K0 @ phi, phi.T @ s.K2 @ phi


#: longest step [s] when the Wagner states' decay is integrated exactly (stable_time_step)
STEP_CAP_S = 0.004
RK4_LAG_STEP_CAP_S = 0.003  #: longest step [s] when RK4 integrates the Wagner states (stable_time_step)
LAWSON_REST_STEP = 0.75  #: dt w_rest of the Lawson step (see stable_time_step)


def stable_time_step(model: CompiledModel, omega_rad_s: float) -> float:
    """Largest RK4 step [s] that keeps the stiffest structural mode (imaginary eigenvalue,
    |lambda dt| <= 1.5 against the limit 2.83) and the fastest Wagner lag state (real negative
    eigenvalue, |lambda dt| <= 2.0 against 2.79) inside the stability region, capped at
    :data:`RK4_LAG_STEP_CAP_S` (3 ms: >= 9 steps per period of a 35 Hz torsion mode; dt convergence
    is tested).

    In axial flight the default integrator (``p[P_LAWSON_LAGS]``, :func:`amra_core.kernels.advance`)
    integrates the Wagner states' decay at the rotation's section speed ``Omega r`` exactly; RK4 keeps
    only the rest, the section speed beyond the rotation's (descent and inflow through the disc, the
    lag rate: 30 m/s allowed, as above). The step is then set by the collective lag mode (3.69 ms for
    McCutcheon at 1.3 Omega, rigid; 3.71 ms fem-torsion), capped at :data:`STEP_CAP_S`: 4 ms, >= 7
    steps per period of the rigid level's 34 Hz torsion mode (McCutcheon, 1.3 Omega), where RK4's
    numerical damping ratio ``(w dt)^5 / 144`` is 2.1e-3 at 3.69 ms. ``amra bench``'s accuracy
    against plain RK4 at 1/8 of the step: tip twist 0.87 % (rigid) and 0.37 % (fem-torsion) of its
    excursion, bound 2 %. :func:`compile_model` keeps the exact decay only where it lengthens this
    step at 1.3 times the reference speed (not for fem-coupled, whose step the rest of the modal
    stiffness sets: there it only cost 2 % of a step). In forward flight the Wagner states stay with
    RK4 and its rule: there ``Omega r`` is not the section speed (the free stream adds
    ``mu Omega R sin psi``), and at mu 0.5 the McCutcheon trims of ``tests/core/test_trim_work.py``
    moved by 3 % in descent rate.

    Only the undamped ``M^-1 K`` is used: the velocity-dependent terms (structural and lag damping,
    the Coriolis coupling ``2 Omega f`` / ``2 Omega f_lag`` with the rotor speed) and the inertial
    couplings with the rotor speed and lag (``g0``, ``gl0``, ``S``) change the step of the full
    first-order system by -0.0 .. +0.71 % (never shorter) for both presets, every fidelity, GJ
    1..1e6 and 10..52 rad/s (``tests/core/test_time_step.py`` computes both and holds the bound).

    With the Lawson step (``p[P_LAWSON]``, :func:`amra_core.kernels.advance`) the oscillators
    ``diag(K(Omega))`` are integrated exactly; RK4 must resolve the rest, ``K(Omega) - diag(K(Omega))``:
    the reduction diagonalises ``K`` at its reference speed only, so the rest grows with
    ``|Omega^2 - Omega_ref^2|`` and is largest at an end of the run's range 0 .. ``omega_rad_s``
    (a rotor-speed collapse passes 0). The step keeps ``dt w_rest <= 0.75``, ``w_rest^2`` the largest
    eigenvalue magnitude of the rest there. The amplification of the full linearised mechanics
    (``tests/core/test_lawson.py``) stays within 1 at every rotor speed 0.5 .. 1.3 Omega; its first
    unstable step is 1.47 .. 2.43 times this one (both presets, both FEM levels, GJ 1..1e6).
    This is the step of trims and Floquet analyses in forward flight too, at every level: they march
    periodic orbits, not a kick. (Until 2026-12-07 the Lawson step was capped at 2 ms in forward flight,
    trims included: at 3 ms its largest error over a kicked run was 3.2e-4 of the rotor speed,
    fem-torsion, mu 0.1. A kicked run keeps that cap, :func:`run_time_step`.) Against trims marched at
    0.25 ms (McCutcheon, ``tests/core/test_lawson.py``): fem-torsion mu 0.3 at 2.97 ms, rotor speed
    4e-5 of itself, descent rate 0.23 %, the three largest Floquet multipliers within 1e-3; mu 0.1 and
    fem-coupled (2.44 ms) closer still. The 16-column fem-coupled mu 0.1 map keeps its critical GJ
    within 0.12 % in every column (the map's bracket is 2 %) in 29.4 s instead of 32.9 s."""
    exact, plain = _step_rules(model, omega_rad_s)
    return exact if model.arrays.p[P_LAWSON_LAGS] > 0.5 else plain


def _step_rules(model: CompiledModel, omega_rad_s: float) -> tuple:
    """(the step with the Wagner states' decay integrated exactly, the step with RK4 integrating
    them) [s] of :func:`stable_time_step`; in forward flight both are RK4's (as ``advance`` decides)."""
    a = model.arrays
    if a.p[P_LAWSON] > 0.5:
        w2 = [0.0]
        for om in (0.0, omega_rad_s):
            K = a.k0 + om**2 * a.k2
            w2.append(np.abs(np.linalg.eigvals(K - np.diag(np.diag(K)))).max())
        w_max = float(np.sqrt(max(max(w2), 1.0))) * 1.5 / LAWSON_REST_STEP
    else:
        K = a.k0 + omega_rad_s**2 * a.k2
        w2 = np.linalg.eigvals(a.minv @ K).real
        w_max = float(np.sqrt(max(w2.max(), 1.0)))
    st_ = model.structure  # collective lag against the free rotor: effective inertia I_z - 2 S^2 / I_R
    i_eff = max(st_.I_lag - 2.0 * st_.S_lag**2 / st_.I_R, 1e-6 * st_.I_lag)
    w_max = max(w_max, float(np.sqrt((st_.k_lag + omega_rad_s**2 * st_.k2_lag) / i_eff)))
    structural = 1.5 / max(w_max, 1.0)
    forward = _forward(model)
    c_min = float(a.st[:, S_C].min())
    theo = model.settings.aero == "theodorsen"
    v_rest = model.flight.airspeed_m_s + 30.0  # the section speed RK4 resolves beyond the rotation's [m/s]

    def wagner(v_m_s: float) -> float:  # the fastest lag state at section speed v within RK4's limits
        return 2.0 / max(2.0 * v_m_s / c_min * WAGNER_B[1] if theo else 0.0, 1.0)
    plain = min(RK4_LAG_STEP_CAP_S, structural, wagner(omega_rad_s * model.rotor.radius_m + v_rest))
    return (plain if forward else min(STEP_CAP_S, structural, wagner(v_rest))), plain


#: longest step [s] of a kicked run in forward flight, at every level, up to :data:`FORWARD_RUN_CAP_MU`:
#: the kick's transient reaches the rotor speed through the n/rev inertial coupling, and at the rigid
#: level's (plain RK4) 3 ms cap the largest error over a kicked run was 2.1e-4 of the rotor speed
#: (mu 0.1; 8.8e-5 at 2.4 ms, 4.3e-5 at 2 ms: fourth order), beyond ``amra bench``'s bound of 1e-4;
#: the FEM levels' Lawson step erred by 3.2e-4 at 3 ms (fem-torsion, mu 0.1; 2.0e-5 at 1.5 ms).
FORWARD_RUN_CAP_S = 0.002
#: advance ratio up to which :data:`FORWARD_RUN_CAP_S` holds; above it the cap shrinks as
#: ``1/sqrt(mu)`` (:func:`forward_run_cap_s`)
FORWARD_RUN_CAP_MU = 0.1


def forward_run_cap_s(mu: float) -> float:
    """Longest step [s] of a kicked run at advance ratio ``mu``: :data:`FORWARD_RUN_CAP_S` up to
    :data:`FORWARD_RUN_CAP_MU`, then ``FORWARD_RUN_CAP_S * sqrt(0.1 / mu)``. The kick's largest
    rotor-speed error grows about as ``mu^2 dt^4`` (McCutcheon, at 2 ms: rigid 4.3e-5 at mu 0.1 and 4.0e-4
    at mu 0.3; fem-torsion 6.7e-5 and 8.4e-4; fem-coupled 8.9e-5 and 8.6e-4 of the rotor speed), so
    this cap keeps it where it is at mu 0.1: at mu 0.3 (1.15 ms) rigid 4.4e-5, fem-torsion 9.3e-5,
    fem-coupled 9.4e-5, within ``amra bench``'s bound of 1e-4 (``tests/core/test_bench.py``)."""
    return FORWARD_RUN_CAP_S * math.sqrt(FORWARD_RUN_CAP_MU / max(float(mu), FORWARD_RUN_CAP_MU))


def advance_ratio(model: CompiledModel, omega_rad_s: float) -> float:
    """The advance ratio [-] of ``model`` at rotor speed ``omega_rad_s``: the flight condition's own,
    else the airspeed in the arrays over the tip speed (0 in axial flight)."""
    if model.flight.mu is not None:
        return float(model.flight.mu)
    return float(model.arrays.p[P_VH]) / max(omega_rad_s * model.rotor.radius_m, 1e-9)


def run_time_step(model: CompiledModel, omega_rad_s: float, mu: float = 0.0) -> float:
    """The step [s] of a time-marching run (:class:`amra_core.simulation.Simulation`): the stable
    step, capped in forward flight at :func:`forward_run_cap_s` of the run's advance ratio ``mu``.
    Trims and Floquet analyses march a periodic orbit, not a kick (once the kick has died out, a
    3 ms run differs from one at 1/8 of the step by 7.5e-7 of the rotor speed), and keep
    :func:`stable_time_step`."""
    dt = stable_time_step(model, omega_rad_s)
    return min(dt, forward_run_cap_s(mu)) if _forward(model) else dt


def _forward(model: CompiledModel) -> bool:
    """True in forward flight: an airspeed in the arrays (a live change) or in the flight condition."""
    return model.arrays.p[P_VH] > 0.0 or not model.flight.is_axial
