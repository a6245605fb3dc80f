"""Time marching from trim, in chunks a UI can stream, with parameters changeable between chunks.

Start (model-notes §5, §7): the trimmed state plus a small perturbation (:class:`Perturbation`).
Where no steady autorotation exists for the parameters, the run starts from the last trimmed point
of the continuation in GJ (the end of the trim branch) with the requested parameters switched on at
t = 0; ``Simulation.start_note`` says so.
"""
from __future__ import annotations

import hashlib
import json
import math
import time
from dataclasses import asdict, dataclass, replace
from typing import Callable, Optional

import numpy as np

from . import __version__, kernels
from .flight import FlightCondition, SolverSettings
from .model import Y_OMEGA, CompiledModel, compile_model, stable_time_step, transfer_state
from .rotor import Rotor
from .trim import TrimResult, trim
from .verdict import Verdict, judge

HISTORY_COLUMNS = kernels.HISTORY_COLUMNS
COL = {c: i for i, c in enumerate(HISTORY_COLUMNS)}
RECORD_INTERVAL_S = 0.0025  #: history sampling (400 Hz: >10 samples per period of a 35 Hz mode)
OVERSPEED_STOP = 2.0  #: the run stops when the rotor speed exceeds this multiple of trim


@dataclass(frozen=True)
class Perturbation:
    """Initial kick applied to the trimmed state: teeter angle [rad] and elastic twist of blade 0
    [rad at the tip, linear from the root for FEM torsion, uniform for the rigid blade]. Blade 0
    alone is kicked so both the collective (rotor-speed-coupled) and cyclic (teeter-coupled)
    modes are excited."""

    teeter_rad: float = 0.01
    twist_rad: float = 0.005


@dataclass(frozen=True)
class Case:
    """Everything that determines a run; ``key()`` identifies it for stored, shared results."""

    rotor: Rotor
    flight: FlightCondition = FlightCondition()
    settings: SolverSettings = SolverSettings()
    t_end_s: float = 10.0
    perturbation: Perturbation = Perturbation()

    def to_dict(self) -> dict:
        return {"rotor": self.rotor.to_dict() | {"sources": None}, "flight": asdict(self.flight),
                "settings": asdict(self.settings), "t_end_s": self.t_end_s,
                "perturbation": asdict(self.perturbation), "solver_version": __version__}

    def key(self) -> str:
        blob = json.dumps(self.to_dict(), sort_keys=True, default=float)
        return hashlib.sha256(blob.encode()).hexdigest()[:20]


class Simulation:
    """A run stepped in chunks: ``advance(n_steps=...)`` or ``advance(span_s=...)`` returns the new
    history rows (columns :data:`HISTORY_COLUMNS`, SI units); ``set_parameters`` changes GJ, EA,
    CG between chunks and the run continues from the current state."""

    def __init__(self, case: Case, trim_result: Optional[TrimResult] = None):
        self.case = case
        self.model: CompiledModel = compile_model(case.rotor, case.flight, case.settings)
        tr = trim_result if trim_result is not None else trim(self.model)
        self.trim = tr
        if tr.ok:
            self.start_note = "started from the trimmed steady autorotation plus the perturbation"
            self.model = tr.model
        elif tr.state is not None:
            be = tr.branch_end
            self.start_note = (f"no steady autorotation for these parameters: started from the end of the trim "
                               f"branch (GJ x{be.get('gj_scale', float('nan')):.3g}, mean GJ "
                               f"{be.get('gj_mean_nm2', float('nan')):.0f} N m^2/rad, rotor speed "
                               f"{be.get('omega_rad_s', float('nan')):.2f} rad/s) with the requested parameters "
                               f"switched on at t = 0")
            # keep the branch-end flight controls (tilt, holds) but the requested structure
            self.model = _with_controls_of(self.model, tr.model)
        else:
            raise RuntimeError(f"no trimmed state to start from: {tr.reason}")
        self.omega_ref = float(tr.state[Y_OMEGA])
        self.y = transfer_state(tr.state, tr.model, self.model)
        self.reference_row = self._row(self.y)
        self._apply_perturbation(case.perturbation)
        self.t = 0.0
        self.dt = case.settings.dt_s or stable_time_step(self.model, 1.3 * self.omega_ref)
        self.record_every = max(1, int(round(RECORD_INTERVAL_S / self.dt)))
        self.status = "running"
        self._chunks: list = []
        self._states: list = []
        self.wall_time_s = 0.0

    # ------------------------------------------------------------------ stepping
    def advance(self, n_steps: Optional[int] = None, span_s: Optional[float] = None) -> np.ndarray:
        """March ``n_steps`` steps or ``span_s`` seconds (rounded to whole recording intervals)."""
        if self.status != "running":
            return np.zeros((0, len(HISTORY_COLUMNS)))
        if n_steps is None:
            n_steps = int(math.ceil((span_s or 0.0) / self.dt))
        n_steps = max(self.record_every, int(math.ceil(n_steps / self.record_every)) * self.record_every)
        n_rec = n_steps // self.record_every
        hist = np.empty((n_rec, len(HISTORY_COLUMNS)))
        states = np.empty((n_rec, len(self.y)))
        t0 = time.perf_counter()
        done, rows, status = kernels.advance(self.y, self.t, self.dt, n_steps, self.record_every,
                                             self.model.arrays, hist, states, 0.02 * self.omega_ref)
        self.wall_time_s += time.perf_counter() - t0
        self.t += done * self.dt
        hist, states = hist[:rows], states[:rows]
        self._chunks.append(hist)
        self._states.append(states)
        if status == 1:
            self.status = "numerical-failure"
        elif status == 2:
            self.status = "rotor-stopped"
        elif self.y[Y_OMEGA] > OVERSPEED_STOP * self.omega_ref:
            self.status = "overspeed-stop"
        return hist

    def run(self, t_end_s: Optional[float] = None, chunk_s: float = 0.5,
            progress: Optional[Callable[[float, float], None]] = None) -> "Simulation":
        t_end = self.case.t_end_s if t_end_s is None else t_end_s
        while self.status == "running" and self.t < t_end - 1e-9:
            self.advance(span_s=min(chunk_s, t_end - self.t))
            if progress:
                progress(self.t, t_end)
        return self

    def set_parameters(self, gj_nm2=None, x_ea=None, x_cg=None) -> None:
        """Change uniform GJ [N m^2/rad], EA and CG [chord fractions]; the run continues."""
        rotor = self.case.rotor.with_overrides(gj_nm2=gj_nm2, x_ea=x_ea, x_cg=x_cg)
        self.case = replace(self.case, rotor=rotor)
        new = _with_controls_of(compile_model(rotor, self.case.flight, self.case.settings), self.model)
        x, xd = self.model.physical(self.y)  # carry the motion over to the new modal basis
        new.set_physical(self.y, x, xd)
        self.model = new

    # ------------------------------------------------------------------ results
    @property
    def history(self) -> np.ndarray:
        if not self._chunks:
            return np.zeros((0, len(HISTORY_COLUMNS)))
        return np.concatenate(self._chunks)

    @property
    def states(self) -> np.ndarray:
        return np.concatenate(self._states) if self._states else np.zeros((0, len(self.y)))

    def spanwise_last_revolution(self, n_azimuth: int = 36) -> dict:
        """Distributions over the last recorded revolution for disc plots: radius [m], azimuth
        of blade 0 [rad], and per (azimuth, station) torque per length [N m/m], elastic twist
        [rad] and flap displacement [m] of blade 0 (blade 1 is at azimuth + pi)."""
        h, S = self.history, self.states
        if len(h) < 2:
            return {}
        t_rev = 2 * math.pi / max(h[-1, COL["omega_rad_s"]], 1e-3)
        idx = np.nonzero(h[:, 0] >= h[-1, 0] - t_rev)[0]
        pick = idx[np.linspace(0, len(idx) - 1, min(n_azimuth, len(idx))).astype(int)]
        out = np.zeros((2, self.model.n_st, 5))
        torque, twist, flap, psi = [], [], [], []
        for k in pick:
            kernels.station_loads(S[k].copy(), self.model.arrays, out)
            torque.append(out[0, :, 1].copy()); twist.append(out[0, :, 3].copy()); flap.append(out[0, :, 4].copy())
            psi.append(float(np.mod(S[k][0], 2 * math.pi)))
        return {"r_m": self.model.arrays.st[:, 0].tolist(), "azimuth_rad": psi,
                "torque_per_length_nm_m": np.array(torque).tolist(),
                "twist_rad": np.array(twist).tolist(), "flap_m": np.array(flap).tolist()}

    def verdict(self) -> Verdict:
        """Verdict on the run so far (model-notes §5)."""
        scale = max(abs(self.case.perturbation.teeter_rad), abs(self.case.perturbation.twist_rad), 1e-4)
        return judge(self.history, HISTORY_COLUMNS, self.omega_ref, self.case.flight.is_axial, self.status,
                     self.trim.ok, self.reference_row, scale)

    def _row(self, y: np.ndarray) -> np.ndarray:
        row = np.zeros(len(HISTORY_COLUMNS)); loads = np.zeros(8); dy = np.zeros_like(y)
        kernels.evaluate(y, self.model.arrays, dy, loads)
        kernels.record_row(0.0, y, self.model.arrays, loads, row)
        return row

    def to_csv(self, path) -> None:
        np.savetxt(path, self.history, delimiter=",", header=",".join(HISTORY_COLUMNS), comments="")

    def _apply_perturbation(self, p: Perturbation) -> None:
        x, xd = self.model.physical(self.y)
        x[0] += p.teeter_rad
        tors = self.model.torsion_index(0)
        nodes = np.asarray(self.model.structure.mesh.nodes_m)
        if len(tors) == 1:
            x[tors[0]] += p.twist_rad
        else:
            x[tors] += p.twist_rad * (nodes[1:] - nodes[0]) / (nodes[-1] - nodes[0])
        self.model.set_physical(self.y, x, xd)


def _with_controls_of(model: CompiledModel, source: CompiledModel) -> CompiledModel:
    from .model import P_ALPHA_S, P_HOLD_OMEGA, P_HOLD_VD, P_VH
    ps = source.arrays.p
    return model.with_controls(alpha_s_rad=ps[P_ALPHA_S], airspeed_m_s=ps[P_VH],
                               hold_omega=ps[P_HOLD_OMEGA] > 0.5, hold_vd=ps[P_HOLD_VD] > 0.5,
                               quasi_static=False)
