"""The equivalent rigid blade: root springs and teeter inertia of the root-spring levels, derived
from the same blade's elastic modes and flexibility instead of estimated.

The ``rigid`` level (and the flap of ``fem-torsion``) replaces the elastic blade by a rigid blade
on root springs. One spring cannot stand for both kinds of motion of a teetering rotor:

* **Collective flap** (both blades cone alike; the hub does not move): the blade is clamped at
  the root, so the spring matches the first cantilever mode, ``k = 1.8751^4 EI/(3L)``
  (:data:`amra_core.structure.K_FLAP_SPRING`).
* **Cyclic flap** (the blades flap oppositely and the teeter hinge lets the hub swing): the
  elastic blade's mode is a *pinned-free* mode (pinned at the teeter hinge, with the hub bar and
  the hub's inertia, free at the tip; node on the blade). The rigid blade's version is the hub
  swinging against the blades on the root springs, whose frequency is set by the hub teeter
  inertia, an estimate: with 1 kg m^2 it was 22 Hz against the FEM's 15 Hz at 39 rad/s, and it
  moved 29 / 22 / 15 Hz for 0.12 / 1 / 3 kg m^2 while the FEM's moved 15.2 / 14.9 / 14.0 Hz.

The rigid cyclic flap is a two-degree-of-freedom system ``[teeter beta, blade flap d]`` whose
rigid-tilt mode is exactly ``Omega`` (``K2`` has the mass matrix's teeter column). Its other
eigenvalue is therefore exactly linear in ``Omega^2`` (a Southwell line):
``omega^2 = k_d M_bb / det M + Omega^2 (M_bb K2_dd - M_bd^2) / det M``. Two parameters of the
equivalent rigid blade fix both coefficients: the **effective teeter inertia** ``M_bb`` (it sets
the slope, and goes into ``M`` and the hub bar's centrifugal moment alike, so the teeter mode
stays exactly 1/rev) and the **cyclic root spring** ``k_d`` (it sets the intercept). They are
chosen so that the line passes through the FEM's first cyclic flap frequency at rest and at the
reference rotor speed (``150 m/s / R``, the reference of the FEM's modal reduction), from the
in-vacuo flap-only FEM of the same blade (Hermite elements, hub inertia and hub bar included,
torsion held). The FEM's own frequency is close to such a line (its shape changes little with
``Omega``); between 0.6 and 1.3 x the reference speed the two differ by about 1 %.

Torsion (``rigid`` only): the root spring is the frequency match ``k = (pi/2)^2 GJ/L`` by
default (:func:`torsion_spring_nm_rad` ``"frequency"``): the uniform rigid blade has the first
non-rotating torsion frequency of the uniform cantilever. Statically it is stiffer than the
elastic blade: under a moment distributed like ``r^2`` (the dynamic pressure of a rotating blade)
the uniform cantilever's load-weighted twist ``int t theta / int t`` is ``9/14 = 0.643 M L/GJ``
(its tip twist ``0.75 M L/GJ``), the spring's ``4/pi^2 = 0.405 M L/GJ``: 1.59 times less. The
fold of the trim branch is set by this static twist, so the rigid fold GJ lies about 1.6 times
below the FEM's. ``"static"`` matches the load-weighted twist instead,
``k = (int t)^2 / int T^2/GJ`` (``T`` the torque outboard), ``14/9 GJ/L`` for a uniform blade
from the axis, computed with the blade's own GJ(r) and root cut-out.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from .shapes import TORSION_SPRINGS, make_mesh

#: fidelity levels whose flap is a rigid blade on a root spring
ROOT_FLAP_LEVELS = ("rigid", "fem-torsion")
#: FEM elements of the flap model the cyclic equivalence is derived from (the default FEM mesh)
FEM_ELEMENTS = 10
#: reference tip speed [m/s] of the frequency match (as the FEM's modal reduction)
REFERENCE_TIP_SPEED_M_S = 150.0


@dataclass(frozen=True)
class CyclicFlapEquivalence:
    """Cyclic flap of the equivalent rigid blade (module docstring).

    ``teeter_inertia_kg_m2``: effective hub teeter inertia the root-spring levels use [kg m^2]
    (the estimate is ``hub_teeter_inertia_kg_m2``); ``cyclic_spring_nm_rad``: root spring per
    blade in cyclic flap [N m/rad]; ``collective_spring_nm_rad``: root spring per blade in
    collective flap (cantilever match) [N m/rad]; ``reference_omega_rad_s``: the rotor speed of
    the rotating match [rad/s]; ``fem_hz``: the FEM's first cyclic flap frequency at rest and at
    the reference speed [Hz]; ``method``: ``"two-speed"`` (both matched) or ``"reference-speed"``
    (the FEM's slope is below what a rigid blade can have, e.g. without a root cut-out: the
    estimated hub inertia is kept and only the reference speed is matched, by the spring)."""

    teeter_inertia_kg_m2: float
    cyclic_spring_nm_rad: float
    collective_spring_nm_rad: float
    reference_omega_rad_s: float
    fem_hz: tuple
    method: str

    def to_dict(self) -> dict:
        return {"teeter_inertia_kg_m2": self.teeter_inertia_kg_m2, "cyclic_spring_nm_rad": self.cyclic_spring_nm_rad,
                "collective_spring_nm_rad": self.collective_spring_nm_rad,
                "reference_omega_rad_s": self.reference_omega_rad_s, "fem_hz": list(self.fem_hz),
                "method": self.method}


def _cyclic_flap_block(rotor, mesh, blade_matrices):
    """(M, K0, K2) of the cyclic flap system [beta, flap coordinates of blade 0] in vacuo, hub
    included, torsion held: blade 1 moves as minus blade 0, so each matrix is twice one blade's.
    ``blade_matrices``: :func:`amra_core.structure.blade_matrices` (passed in: this module sits
    below the structure assembly, which applies it)."""
    Mb, K0b, K2b = blade_matrices(rotor, mesh, added_mass=None, trapeze=False, torsion=False)
    idx = np.arange(1 + mesh.n_flap)
    M, K0, K2 = (2.0 * A[np.ix_(idx, idx)] for A in (Mb, K0b, K2b))
    M[0, 0] += rotor.hub_teeter_inertia_kg_m2
    K2[0, 0] += rotor.hub_teeter_inertia_kg_m2
    return M, K0, K2


def _elastic_eigenvalue(M, K):
    """Lowest eigenvalue [rad^2/s^2] of ``K`` on the M-orthogonal complement of the rigid tilt
    (``beta`` alone, an exact mode at every rotor speed): the first cyclic flap mode."""
    import scipy.linalg as sl
    n = M.shape[0]
    c = M[:, 0]
    # basis of {x: c^T x = 0}: x_0 = -(c_1: . x_1:) / c_0
    P = np.zeros((n, n - 1))
    P[0, :] = -c[1:] / c[0]
    P[1:, :] = np.eye(n - 1)
    return float(sl.eigh(P.T @ K @ P, P.T @ M @ P, eigvals_only=True)[0])


def derive_cyclic_flap(rotor, blade_matrices, k_flap_spring: float) -> CyclicFlapEquivalence:
    """The effective teeter inertia and the cyclic root spring of ``rotor``'s equivalent rigid
    blade (module docstring); use :func:`amra_core.structure.cyclic_flap_equivalence`.
    ``k_flap_spring``: the cantilever coefficient of the collective spring (times EI/L)."""
    return _derive(rotor.with_overrides(gj_nm2=1.0), blade_matrices, k_flap_spring)  # GJ does not enter


@functools.lru_cache(maxsize=64)
def _derive(rotor, blade_matrices, k_flap_spring: float) -> CyclicFlapEquivalence:
    r0, R = rotor.root_cutout_m, rotor.radius_m
    om_ref = REFERENCE_TIP_SPEED_M_S / R
    Mf, K0f, K2f = _cyclic_flap_block(rotor, make_mesh("fem-coupled", r0, R, FEM_ELEMENTS), blade_matrices)
    lam0 = _elastic_eigenvalue(Mf, K0f)
    lam1 = _elastic_eigenvalue(Mf, K0f + om_ref**2 * K2f)
    slope = (lam1 - lam0) / om_ref**2  # the FEM's Southwell coefficient over [0, om_ref]

    Mr, _, K2r = _cyclic_flap_block(rotor, make_mesh("rigid", r0, R, 1), blade_matrices)
    m_bd, m_dd, k2_dd = Mr[0, 1], Mr[1, 1], K2r[1, 1]
    m_bb_est = Mr[0, 0]
    k_coll = k_flap_spring * rotor.stations.mean("ei_flap_nm2") / rotor.blade_length_m
    slope_min = k2_dd / m_dd  # the slope of a rigid blade clamped to an infinitely heavy hub
    if slope > slope_min * (1.0 + 1e-6):
        m_bb = m_bd**2 * (slope - 1.0) / (slope * m_dd - k2_dd)
        det = m_bb * m_dd - m_bd**2
        k_dd = lam0 * det / m_bb
        method = "two-speed"
    else:  # keep the estimate, match the reference speed with the spring alone (never negative)
        m_bb = m_bb_est
        det = m_bb * m_dd - m_bd**2
        k_dd = max(0.0, (lam1 - om_ref**2 * (m_bb * k2_dd - m_bd**2) / det) * det / m_bb)
        method = "reference-speed"
    inertia = rotor.hub_teeter_inertia_kg_m2 + (m_bb - m_bb_est)
    hz = tuple(math.sqrt(max(v, 0.0)) / (2 * math.pi) for v in (lam0, lam1))
    return CyclicFlapEquivalence(float(inertia), float(0.5 * k_dd), float(k_coll), float(om_ref), hz, method)


def apply_cyclic_flap(eq: CyclicFlapEquivalence, rotor, mesh, M, K0, K2, flap_index) -> None:
    """Give the assembled root-spring model ``(M, K0, K2)`` over ``[beta, q0, q1]`` the equivalent
    rigid blade's cyclic flap: the effective teeter inertia (instead of the estimate already in
    ``M[0, 0]`` and ``K2[0, 0]``) and a cross-blade spring that makes the per-blade root spring
    ``k_cyc`` in cyclic and leaves ``k_coll`` in collective flap (``flap_index``: the rows of
    blade 0's and blade 1's flap angles). In place."""
    if mesh.fidelity not in ROOT_FLAP_LEVELS:
        return
    d_inertia = eq.teeter_inertia_kg_m2 - rotor.hub_teeter_inertia_kg_m2
    M[0, 0] += d_inertia
    K2[0, 0] += d_inertia
    i0, i1 = flap_index
    c = 0.5 * (eq.cyclic_spring_nm_rad - eq.collective_spring_nm_rad)
    K0[i0, i0] += c
    K0[i1, i1] += c
    K0[i0, i1] -= c
    K0[i1, i0] -= c


def torsion_spring_nm_rad(rotor, kind: str = "frequency") -> float:
    """Root torsion spring of the ``rigid`` level [N m/rad]: ``"frequency"``
    ``(pi/2)^2 mean(GJ)/L`` or ``"static"`` ``(int t)^2 / int T^2/GJ`` with ``t = r^2`` on the
    blade (module docstring)."""
    if kind == "frequency":
        return (math.pi / 2.0) ** 2 * rotor.stations.mean("gj_nm2") / rotor.blade_length_m
    if kind == "static":
        return _static_torsion_spring(rotor)
    raise ValueError(f"rigid_spring = {kind!r} is not allowed: choose one of {', '.join(TORSION_SPRINGS)}")


def static_torsion_coefficients(root_fraction: float = 0.0):
    """``(load-weighted twist, tip twist)`` of a uniform cantilever from ``r0 = root_fraction R`` to
    ``R`` under a moment ``t ~ r^2`` (r from the axis) of total ``M``, in units of ``M L/GJ``
    (closed form; 9/14 and 3/4 at ``r0 = 0``)."""
    a = root_fraction / (1.0 - root_fraction)  # r/L = a + x, x in [0, 1] from the root

    def T(x):  # torque outboard of x per (M / int t): int_x^1 (a + s)^2 ds
        return ((a + 1.0) ** 3 - (a + x) ** 3) / 3.0

    total = T(0.0)
    xs = np.polynomial.legendre.leggauss(12)
    x, w = 0.5 * (xs[0] + 1.0), 0.5 * xs[1]  # exact for these polynomials
    weighted = float(np.sum(w * T(x) ** 2)) / total**2
    tip = float(np.sum(w * T(x))) / total
    return weighted, tip


def _static_torsion_spring(rotor) -> float:
    st = rotor.stations
    r = np.union1d(np.linspace(st.r_m[0], st.r_m[-1], 4001), st.r_m)
    t = r**2
    seg = 0.5 * (t[1:] + t[:-1]) * np.diff(r)
    T = np.concatenate([np.cumsum(seg[::-1])[::-1], [0.0]])  # torque outboard of r
    f = T**2 / st.at("gj_nm2", r)
    return float(T[0] ** 2 / np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(r)))
