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

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .airfoil import compile_airfoil, load_airfoil
from .flight import FlightCondition, SolverSettings
from .rotor import Rotor
from .shapes import make_mesh
from .structure import assemble

# --- scalar parameter slots (indices into ModelArrays.p) -------------------------------------
P_RHO, P_A_SOUND, P_G, P_MASS, P_R, P_R0, P_VH, P_ALPHA_S = range(8)
P_HOLD_OMEGA, P_HOLD_VD, P_AERO, P_IR, P_ILAG, P_SLAG, P_KLAG, P_K2LAG = range(8, 16)
P_NQ, P_NST, P_NS, P_QUASI_STATIC = range(16, 20)
N_P = 20

# --- station table columns --------------------------------------------------------------------
S_R, S_W, S_C, S_XEA, S_XAC, S_THETA0, S_A = range(7)
N_S_COLS = 7

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
    st: np.ndarray  #: (n_st, N_S_COLS) station table
    phw: np.ndarray  #: (n_st, n_q) flap shape at stations
    dphw: np.ndarray  #: (n_st, n_q) flap slope at stations
    pht: np.ndarray  #: (n_st, n_q) twist shape at stations
    tip: np.ndarray  #: (2, n_q) flap and twist shapes at the tip
    lag_inv: np.ndarray  #: inverse of the [Omega, zeta0, zeta1] inertia matrix (3 x 3)
    af_alpha0: float
    af_dalpha: float
    af_cl: np.ndarray
    af_cd: np.ndarray
    af_cm: np.ndarray


@dataclass(frozen=True)
class CompiledModel:
    """Arrays plus the layout facts the Python layer needs."""

    arrays: ModelArrays
    n_q: int
    n_s: int
    n_st: int
    kinds: tuple
    structure: object
    rotor: Rotor
    flight: FlightCondition
    settings: SolverSettings

    @property
    def n_y(self) -> int:
        return N_Y_FIXED + 2 * self.n_s + 4 * self.n_st

    def x_slice(self):
        return slice(N_Y_FIXED, N_Y_FIXED + self.n_s)

    def xd_slice(self):
        return slice(N_Y_FIXED + self.n_s, N_Y_FIXED + 2 * self.n_s)

    def aero_slice(self):
        return slice(N_Y_FIXED + 2 * self.n_s, self.n_y)

    def torsion_index(self, blade: int) -> np.ndarray:
        """Positions in ``x`` of blade ``blade``'s torsion coordinates."""
        s = self.structure
        return np.array([i for i, (k, b) in enumerate(zip(s.kinds, s.blade_of)) if k == "torsion" and b == blade])

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
        return CompiledModel(self.arrays._replace(p=p), self.n_q, self.n_s, self.n_st, self.kinds,
                             self.structure, self.rotor, self.flight, self.settings)


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
                  settings: SolverSettings = SolverSettings()) -> CompiledModel:
    mesh = make_mesh(settings.fidelity, rotor.root_cutout_m, rotor.radius_m, settings.n_elements)
    rho = flight.density_kg_m3
    s = assemble(rotor, mesh, added_mass=apparent_mass(rotor, rho))
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
    p[P_NQ], p[P_NST], p[P_NS] = mesh.n_q, len(r), s.n
    lag_m = np.array([[s.I_R, s.S_lag, s.S_lag], [s.S_lag, s.I_lag, 0.0], [s.S_lag, 0.0, s.I_lag]])
    af = compile_airfoil(load_airfoil(rotor.airfoil))
    arrays = ModelArrays(
        p=p, minv=np.linalg.inv(s.M), k0=s.K0, k2=s.K2, st=st,
        phw=np.ascontiguousarray(pw), dphw=np.ascontiguousarray(dpw), pht=np.ascontiguousarray(pt),
        tip=np.vstack([tw[0], tt[0]]), lag_inv=np.linalg.inv(lag_m),
        af_alpha0=af.alpha0_rad, af_dalpha=af.dalpha_rad, af_cl=af.cl, af_cd=af.cd, af_cm=af.cm,
    )
    return CompiledModel(arrays, mesh.n_q, s.n, len(r), s.kinds, s, rotor, flight, settings)


def stable_time_step(model: CompiledModel, omega_rad_s: float) -> float:
    """Largest RK4 step [s] that keeps the stiffest structural mode and the fastest Wagner lag
    state inside the stability region with margin (|lambda dt| <= 1.5, limit 2.8), capped at 2 ms."""
    a = model.arrays
    K = a.k0 + omega_rad_s**2 * a.k2
    w2 = np.linalg.eigvals(a.minv @ K).real
    w_max = float(np.sqrt(max(w2.max(), 1.0)))
    c_min = float(a.st[:, S_C].min())
    v_tip = omega_rad_s * model.rotor.radius_m + model.flight.airspeed_m_s + 30.0
    lam_aero = 2.0 * v_tip / c_min * WAGNER_B[1] if model.settings.aero == "theodorsen" else 0.0
    return min(0.002, 1.5 / max(w_max, lam_aero, 1.0))
