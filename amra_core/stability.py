"""Linearised stability about the trimmed state, and the classification of one map cell.

* Axial flight is time-invariant: the Jacobian ``A = df/dy`` of the full nonlinear model (central
  differences of the jitted right-hand side) at the trim gives eigenvalues directly (its collective
  and cyclic blocks apart, :mod:`amra_core.blade_symmetry`).
* Forward flight is periodic: the monodromy matrix (the state transition over one revolution,
  central differences of perturbed one-revolution marches of the full nonlinear model) gives
  Floquet multipliers ``z``; exponents ``ln(z)/T``. The frequency of a Floquet exponent is only
  defined modulo the rotor frequency; the principal value is reported.

The azimuth ``psi`` is the time-like coordinate and is left out of the linearisation (in axial
flight nothing depends on it; in forward flight it is the phase along the periodic orbit).
Each mode is labelled by its participation: teeter, flap, torsion, lag, rotor speed, inflow,
descent, or aero lag (the Wagner states).
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Optional

import numpy as np

from . import kernel_guard, kernels
from .blade_symmetry import eig_axial
from .flight import FlightCondition, SolverSettings
from .floquet import (FD_STEP_CENTRAL, FD_STEP_FORWARD, KRYLOV_MAX_DIM, KRYLOV_MODES, KRYLOV_TOL,  # noqa: F401
                      UNSTABLE_REAL_PART, _largest, _one_revolution, floquet_krylov, harmonics, monodromy)
from .model import (N_Y_FIXED, Y_OMEGA, Y_V0, Y_VD, Y_ZETA0, Y_ZETAD0, CompiledModel, compile_model,
                    stable_time_step)
from .rotor import Rotor
from .trim import TrimResult, trim

#: modes decaying faster than this [1/s] are labelled 'aero lag' (Wagner states decay at 2 b_k V/c,
#: 30-700 1/s; the aerodynamically damped structural modes seen here decay at under ~40 1/s)
AERO_LAG_DECAY = 60.0
MIN_FLUTTER_HZ = 0.3


@dataclass
class Mode:
    label: str
    frequency_hz: float
    damping_ratio: float
    real_part_per_s: float
    participation: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        d = asdict(self)
        d["participation"] = {k: round(v, 3) for k, v in self.participation.items()}
        return d


@dataclass
class StabilityResult:
    stable: bool
    modes: list
    trim: TrimResult
    method: str  #: 'eigenvalues' (axial) or 'floquet' (forward)

    @property
    def critical(self) -> Optional[Mode]:
        return max(self.modes, key=lambda m: m.real_part_per_s) if self.modes else None

    def to_dict(self, include_aero_lag: bool = False) -> dict:
        modes = [m.to_dict() for m in self.modes if include_aero_lag or m.label != "aero lag"]
        return {"stable": self.stable, "method": self.method, "trim": self.trim.to_dict(), "modes": modes}


#: the groups of the blades' own motion (the others: the equilibrium's rotor speed, descent, inflow)
BLADE_GROUPS = ("lag", "teeter", "flap", "torsion")


def _signal_rows(model: CompiledModel, omega: float) -> dict:
    """Per physical group, its signals as rows of a matrix on the state without psi, sized as
    :func:`_participation_all` sizes them (speeds by the tip speed, flap and twist per blade,
    halved). Displacements only: over a revolution each is seen through its whole cycle, and a
    rate (times its frequency) favoured the higher of two harmonics in the choice of a mode's
    frequency (a flutter mode whose twist moves at 6.4 and 10.9 Hz, 1.0 to 0.8 in a run's
    spectrum, was put at 10.7 Hz)."""
    a = model.arrays
    R = model.rotor.radius_m
    vt = omega * R
    n = model.n_y - 1
    xs = slice(model.x_slice().start - 1, model.x_slice().stop - 1)
    hs = model.inflow_harmonics_slice()

    def unit(i, size):
        r = np.zeros(n)
        r[i] = size
        return r

    def structural(weights, size=1.0):
        r = np.zeros(n)
        r[xs] = size * weights
        return r

    return {
        "rotor speed": np.array([unit(Y_OMEGA - 1, 1.0 / omega)]),
        "descent": np.array([unit(Y_VD - 1, 10.0 / vt)]),
        "inflow": np.array([unit(Y_V0 - 1, 10.0 / vt)] + [unit(i - 1, 10.0 / vt) for i in range(hs.start, hs.stop)]),
        "lag": np.array([unit(Y_ZETA0 - 1, 1.0), unit(Y_ZETA0, 1.0)]),
        "teeter": np.array([structural(a.teeter)]),
        "flap": np.array([structural((a.tip[b, 0] - (1 - 2 * b) * R * a.teeter) / R, 0.5) for b in (0, 1)]),
        "torsion": np.array([structural(a.tip[b, 1], 0.5) for b in (0, 1)]),
    }


def _floquet_identities(rows: dict, lam: np.ndarray, paths: np.ndarray, times: np.ndarray, T: float,
                        omega: float):
    """``(exponents, participations)``: each Floquet exponent ``lam`` (principal) moved to its mode's
    own frequency, and the share of each physical group in its motion over the whole revolution.

    A mode of the periodic system moves at ``Im(lam) + h Omega`` for every ``h`` at once
    (:func:`amra_core.floquet.harmonics`); the group that carries most of the motion over the
    revolution names the mode, and the strongest harmonic of the group that moves most gives its
    frequency (Bauchau & Nikishkov 2001): of the blade's groups if they carry half the motion or more,
    else of the equilibrium's. The motion at the orbit's start alone named a rotor-speed mode "torsion", and
    the unfolding by the nearest eigenvalue of the averaged Jacobian (its match decided by the
    real parts, the shift being free) put the flutter pair of a fem-coupled blade at mu 0.1 at
    54.45 Hz where a run shows 6.5 Hz. A multiplier under 1e-8 (decayed to round-off within the
    revolution: its path is noise) or a positive real one (a real mode) keeps its principal value and
    no participation (None: the vector's own).

    ``rows``: :func:`_signal_rows`; ``paths`` (``len(times)``, signals, exponents): those signals, in
    that order, along each exponent's eigenvector marched over the revolution (the linearised motion
    the monodromy's marches give), at ``times`` [s] in [0, T)."""
    names = list(rows)
    h, C = harmonics(lam, paths, times, T, omega)
    ends = np.cumsum([len(rows[g]) for g in names])
    energy = {g: (np.abs(C[:, e - len(rows[g]):e, :]) ** 2).sum(axis=1) for g, e in zip(names, ends)}
    rms = np.array([np.sqrt(energy[g].sum(axis=0)) for g in names])  # (groups, exponents)
    out, parts = lam.copy(), []
    for j in range(len(lam)):
        # a positive real multiplier: a real mode (its harmonics come in +-h pairs), left real (an
        # aero-lag state put at 23.6 Hz read "torsion"); a negative one moves at (h + 1/2) Omega
        real = abs(lam[j].imag) * T < 1e-9
        if real or not abs(np.exp(lam[j] * T)) >= 1e-8 or not rms[:, j].sum() > 0:
            parts.append(None)
            continue
        # the frequency of the blade's motion if the blade carries at least half the mode, else of the
        # equilibrium's (the heavily damped 1/rev teeter mode at mu 0.1, inflow 0.36 and teeter 0.20,
        # was put at the inflow's 0.9 Hz)
        blade = [i for i, g in enumerate(names) if g in BLADE_GROUPS]
        own = blade if rms[blade, j].sum() >= 0.5 * rms[:, j].sum() else [i for i in range(len(names)) if i not in blade]
        top = names[max(own, key=lambda i: rms[i, j])]
        out[j] = lam[j] + 1j * omega * h[int(np.argmax(energy[top][:, j]))]
        parts.append({g: float(rms[i, j] / rms[:, j].sum()) for i, g in enumerate(names)})
    return out, parts


def _participation_all(model: CompiledModel, V: np.ndarray, omega: float, real_mode: np.ndarray) -> list:
    """Share of each physical group in each column of ``V`` (eigenvectors, the state without psi),
    with rates scaled by the rotor speed and speeds by the tip speed so angles, rates and speeds
    compare; a non-oscillatory column dominated by the Wagner lag states is ``{"aero lag": 1}``."""
    a = model.arrays
    R = model.rotor.radius_m
    n_fixed = N_Y_FIXED - 1  # V has no psi row
    xs = slice(model.x_slice().start - 1, model.x_slice().stop - 1)
    xds = slice(model.xd_slice().start - 1, model.xd_slice().stop - 1)
    aero = slice(model.aero_slice().start - 1, model.aero_slice().stop - 1)
    hs = model.inflow_harmonics_slice()
    hs = slice(hs.start - 1, hs.stop - 1)
    q, qd = V[xs], V[xds]
    vt = omega * R
    A = np.abs(V[:n_fixed])
    tq, tqd = a.teeter @ q, a.teeter @ qd
    g = {
        "rotor speed": A[Y_OMEGA - 1] / omega,
        "descent": A[Y_VD - 1] / vt * 10.0,
        "inflow": (A[Y_V0 - 1] + np.abs(V[hs]).sum(axis=0)) / vt * 10.0,
        "lag": np.hypot(A[Y_ZETA0 - 1] + A[Y_ZETA0], (A[Y_ZETAD0 - 1] + A[Y_ZETAD0]) / omega),
        "teeter": np.hypot(np.abs(tq), np.abs(tqd) / omega),
    }
    fl = sum(np.hypot(np.abs(a.tip[b, 0] @ q - (1 - 2 * b) * R * tq), np.abs(a.tip[b, 0] @ qd - (1 - 2 * b) * R * tqd)
                      / omega) for b in (0, 1)) / R
    tw = sum(np.hypot(np.abs(a.tip[b, 1] @ q), np.abs(a.tip[b, 1] @ qd) / omega) for b in (0, 1))
    g["flap"] = 0.5 * fl
    g["torsion"] = 0.5 * tw
    tot = sum(g.values())
    aero_w = np.abs(V[aero]).sum(axis=0) / vt
    out = []
    for k in range(V.shape[1]):
        if real_mode[k] and tot[k] < aero_w[k]:
            out.append({"aero lag": 1.0})
        else:
            out.append({name: float(val[k] / tot[k]) for name, val in g.items()})
    return out


def _modes_from_exponents(model, lam, vecs, omega, periodic_parts=None) -> list:
    """The modes of exponents ``lam`` and vectors ``vecs``, labelled by the largest group of their
    participation: ``periodic_parts`` (forward flight, over the revolution: :func:`_floquet_identities`)
    where given and not None, else the vector's own (:func:`_participation_all`)."""
    modes = []
    # each complex pair once; an exponent without its conjugate (a real negative Floquet multiplier,
    # unfolded to one branch) is a mode of its own whichever sign its branch has
    has_conjugate = np.any(np.abs(lam[:, None] - np.conj(lam)[None, :]) <= 1e-9 * (1 + np.abs(lam))[:, None], axis=1)
    paired = (lam.imag < -1e-9) & has_conjugate
    keep = np.nonzero(~paired)[0]
    parts = _participation_all(model, vecs[:, keep], omega, np.abs(lam[keep].imag) < 1e-6)
    if periodic_parts is not None:  # an aero-lag state stays one (the Wagner states are not a group)
        parts = [p if "aero lag" in p or periodic_parts[k] is None else periodic_parts[k] for k, p in zip(keep, parts)]
    for k, part in zip(keep, parts):
        label = "aero lag" if lam[k].real < -AERO_LAG_DECAY else max(part, key=part.get)
        w = abs(lam[k])
        modes.append(Mode(label, float(abs(lam[k].imag) / (2 * math.pi)),
                          float(-lam[k].real / w) if w > 0 else 0.0, float(lam[k].real), part))
    modes.sort(key=lambda m: (m.label == "aero lag", m.frequency_hz))
    return modes


def jacobian(model: CompiledModel, y0: np.ndarray) -> np.ndarray:
    """df/dy without the azimuth row/column, by central differences (relative step 1e-6), in one
    kernel call: the shapes are checked once, not per column (measured on a rigid axial column
    walk: the per-evaluation checks cost 3 times the right-hand sides themselves)."""
    n = len(y0)
    J = np.zeros((n - 1, n - 1))
    kernel_guard.jacobian(np.ascontiguousarray(y0, dtype=float), model.arrays, J)
    return J


def floquet_modes(m: CompiledModel, y0: np.ndarray, scheme: str = "forward"):
    """``(exponents, vectors, participations)`` of the periodic orbit through ``y0``: the Floquet
    exponents, each at its mode's own frequency, with their eigenvectors (columns, the state without
    psi, at the orbit's start) and their groups' shares over the revolution
    (:func:`_floquet_identities`); ``scheme`` as :func:`analyse`'s (``"krylov"``: the resolved ones)."""
    omega = float(y0[Y_OMEGA])
    dt = stable_time_step(m, 1.3 * omega)
    rows = _signal_rows(m, omega)
    G = np.vstack(list(rows.values()))  # the groups' signals are all the harmonics need of the marches
    converged = False
    if scheme == "krylov":
        z, vecs, T, _, n_resolved, converged, paths, times = floquet_krylov(m, y0, dt, observe=G)
    if not converged:  # the full matrix (also when Arnoldi did not resolve its modes)
        Phi, T, phi_t, times = monodromy(m, y0, dt, "forward" if scheme == "krylov" else scheme, observe=G)
        z, vecs = np.linalg.eig(Phi)
        n_resolved = len(z)
        paths = phi_t @ vecs
    lam, parts = _floquet_identities(rows, np.log(z[:n_resolved].astype(complex)) / T, paths[:, :, :n_resolved],
                                     times, T, omega)
    return lam, vecs[:, :n_resolved], parts


def analyse(model: CompiledModel, trim_result: Optional[TrimResult] = None,
            monodromy_scheme: str = "forward") -> StabilityResult:
    """Eigenvalues (axial) or Floquet exponents (forward; monodromy by ``monodromy_scheme``
    differences, see :func:`monodromy`) about the trim of ``model``. ``"krylov"`` reports only the
    ``KRYLOV_MODES`` least damped exponents (a complex pair counts twice), enough to decide
    stability and all the map's column walk reads: in forward flight they are resolved by Arnoldi
    (:func:`floquet_krylov`, about half the revolutions), in axial flight picked from all the
    eigenvalues (the participations of the others are not computed)."""
    tr = trim_result if trim_result is not None else trim(model)
    if not tr.ok:
        return StabilityResult(False, [], tr, "none")
    m = tr.model
    y0 = tr.state
    omega = float(y0[Y_OMEGA])
    if model.flight.is_axial:
        lam, vecs = eig_axial(m, jacobian(m, y0))  # collective and cyclic blocks apart
        if monodromy_scheme == "krylov":
            keep = _largest(np.exp(np.clip(lam.real, -700.0, 700.0)), KRYLOV_MODES)
            lam, vecs = lam[keep], vecs[:, keep]
        method, periodic_parts = "eigenvalues", None
    else:
        lam, vecs, periodic_parts = floquet_modes(m, y0, monodromy_scheme)
        method = "floquet"
    modes = _modes_from_exponents(m, lam, vecs, omega, periodic_parts)
    stable = all(md.real_part_per_s < UNSTABLE_REAL_PART for md in modes)
    return StabilityResult(stable, modes, tr, method)


# ----------------------------------------------------------------------------- map cells
@dataclass
class CellResult:
    cg: float
    gj_nm2: float
    verdict: str  #: stable | flutter | divergence | overspeed | no-autorotation | windmill-brake | failed
    stable: bool
    #: 'flutter' (eigenvalue crossing on the branch), 'fold' (no trim), 'overspeed' (the normal branch
    #: overspeeding), 'windmill-brake' (a windmill-brake root), '' if stable
    boundary_kind: str
    growth_rate_per_s: Optional[float]
    frequency_hz: Optional[float]
    omega_trim_rad_s: Optional[float]
    reason: str = ""
    branch: str = ""  #: trim branch: normal | overspeed | windmill-brake | none ('' when not known)
    descent_rate_m_s: Optional[float] = None  #: of the equilibrium [m/s], None without one

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> "CellResult":
        return cls(**{k: d[k] for k in cls.__dataclass_fields__ if k in d})


def assess_cell(rotor: Rotor, flight: FlightCondition, settings: SolverSettings, method: str = "eigen") -> CellResult:
    """Classify one (CG, GJ) cell; ``rotor`` already carries the overrides (uniform CG and GJ)."""
    cg = float(np.mean(rotor.stations.x_cg)); gj = float(np.mean(rotor.stations.gj_nm2))
    model = compile_model(rotor, flight, settings)
    if method == "time":
        from .simulation import Case, Simulation
        sim = Simulation(Case(rotor, flight, settings, t_end_s=8.0)).run()
        v = sim.verdict()
        kind = "" if not v.unstable else ("fold" if not sim.trim.ok else "flutter")
        return CellResult(cg, gj, v.verdict, v.verdict == "stable", kind, v.growth_rate_per_s, v.frequency_hz,
                          sim.trim.omega_rad_s if sim.trim.ok else None, v.explanation)
    res = analyse(model)
    if not res.trim.ok:
        be = res.trim.branch_end
        why = res.trim.reason + (f" (branch ended at mean GJ {be['gj_mean_nm2']:.0f} N m^2/rad)" if be else "")
        verdict = "overspeed" if be.get("runaway") == "overspeed" else "no-autorotation"
        return CellResult(cg, gj, verdict, False, "fold", None, None, None, why, "none")
    if res.trim.branch == "windmill-brake":  # an equilibrium, but not autorotation: never stable
        return CellResult(cg, gj, "windmill-brake", False, "windmill-brake", None, None, res.trim.omega_rad_s,
                          f"equilibrium on the windmill-brake side: descent rate {res.trim.descent_rate_m_s:.1f} m/s "
                          f"({res.trim.descent_ratio:.2f} v_h), not autorotation", "windmill-brake",
                          float(res.trim.descent_rate_m_s))
    if res.trim.branch == "overspeed" and res.stable:  # the normal branch beyond 2 v_h, rotor speed risen
        crit = res.critical
        return CellResult(cg, gj, "overspeed", False, "overspeed", crit.real_part_per_s if crit else None,
                          crit.frequency_hz if crit else None, res.trim.omega_rad_s,
                          f"the normal branch overspeeding: rotor speed {res.trim.omega_rad_s:.1f} rad/s, descent rate "
                          f"{res.trim.descent_rate_m_s:.1f} m/s ({res.trim.descent_ratio:.2f} v_h)", "overspeed",
                          float(res.trim.descent_rate_m_s))
    return cell_from_modes(cg, gj, res.trim, res.modes)


def verdict_of_trim(tr: TrimResult, modes: list) -> str:
    """The word a map's cell uses (:func:`amra_core.boundary.cells_of_walk`) for a trim and its
    modes: ``no-autorotation`` without a trim or on the windmill-brake root, ``flutter`` or
    ``divergence`` where a mode grows, ``overspeed`` on the normal branch overspeeding, else
    ``stable``. ``amra stability`` said only "stable: False" where the map said flutter."""
    if not tr.ok or tr.branch == "windmill-brake":
        return "no-autorotation"
    if modes and not all(m.real_part_per_s < UNSTABLE_REAL_PART for m in modes):
        return cell_from_modes(float("nan"), float("nan"), tr, modes).verdict
    return "overspeed" if tr.branch == "overspeed" else "stable"


def cell_from_modes(cg: float, gj: float, tr: TrimResult, modes: list) -> CellResult:
    """The cell of a normal-branch trim ``tr`` with its ``modes``."""
    crit = max(modes, key=lambda m: m.real_part_per_s)
    vd = float(tr.descent_rate_m_s)
    if all(m.real_part_per_s < UNSTABLE_REAL_PART for m in modes):
        return CellResult(cg, gj, "stable", True, "", crit.real_part_per_s, crit.frequency_hz,
                          tr.omega_rad_s, f"least damped: {crit.label}", "normal", vd)
    oscill = crit.frequency_hz >= MIN_FLUTTER_HZ
    verdict = "flutter" if oscill else "divergence"
    return CellResult(cg, gj, verdict, False, "flutter", crit.real_part_per_s, crit.frequency_hz,
                      tr.omega_rad_s, f"unstable {crit.label} mode", "normal", vd)
