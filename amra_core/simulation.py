"""Time marching from trim, in chunks a UI can stream, with parameters changeable between chunks.

Start (model-notes §5, §7): the trimmed state plus a small perturbation (:class:`Perturbation`).
Where no steady autorotation exists for the parameters, the run starts from the last trimmed point
of the continuation (in GJ, or in flight speed in forward flight: the end of the trim branch) with
the requested parameters switched on at t = 0; ``Simulation.start_note`` says so.

Every kernel call goes through :mod:`amra_core.kernel_guard` (shapes checked once per call), and a
parameter change re-projects the state onto the new model's layout (its modal basis can keep a
different number of modes) and recomputes the stable time step.
"""
from __future__ import annotations

import hashlib
import json
import math
import time
from dataclasses import asdict, dataclass, replace
from typing import Callable, Optional

import numpy as np

from . import __version__, kernel_guard, kernels
from .flight import FlightCondition, SettingsError, SolverSettings, _num
from .model import N_Y_FIXED, Y_OMEGA, CompiledModel, advance_ratio, compile_model, run_time_step, transfer_state
from .rotor import Rotor
from .trim import TrimResult, gj_mean_of, trim
from .verdict import Verdict, judge, judge_after_change

HISTORY_COLUMNS = kernels.HISTORY_COLUMNS
COL = {c: i for i, c in enumerate(HISTORY_COLUMNS)}
RECORD_INTERVAL_S = 0.0025  #: history sampling (400 Hz: >10 samples per period of a 35 Hz mode)
OVERSPEED_STOP = 2.0  #: the run stops when the rotor speed exceeds this multiple of trim
T_END_MAX_S = 600.0  #: longest run [s] (as ``amra simulate --t-end``): 240 000 recorded rows
#: most history rows one ``advance`` call records (100 s at the 2.5 ms recording interval): a chunk
#: allocates its history and full states up front (rows x (16 + n_y) floats, ~40 MB for the
#: fem-coupled state), so a UI stays responsive and a mistyped span cannot exhaust memory
MAX_CHUNK_ROWS = 40_000
#: a span within this fraction of a step above a whole number of steps is that number (float sums of
#: steps, see Simulation.advance)
SPAN_ROUNDING_STEPS = 1e-9
#: states that end a run; ``finished`` (t_end reached by :meth:`Simulation.run`) can be continued
#: ``not-started``: no trimmed state and no branch end existed (the verdict is ``no-autorotation``)
TERMINAL_STATUSES = ("numerical-failure", "rotor-stopped", "overspeed-stop", "not-started")


def _positive(name: str, value, hi: float, why: str = "") -> float:
    """A finite number of seconds in (0, hi], else a SettingsError naming it and the range."""
    ok = not isinstance(value, bool) and isinstance(value, (int, float, np.integer, np.floating))
    if not ok or not math.isfinite(value) or not 0.0 < value <= hi:
        raise SettingsError(f"{name} = {value!r} is not allowed: must be a number of seconds in (0, {hi:.6g}]"
                            + (f": {why}" if why else ""))
    return float(value)


@dataclass(frozen=True)
class Perturbation:
    """Initial kick applied to the trimmed state: teeter angle [rad] and elastic twist of blade 0
    [rad at the tip, linear from the root for FEM torsion, uniform for the rigid blade]. Blade 0
    alone is kicked so both the collective (rotor-speed-coupled) and cyclic (teeter-coupled)
    modes are excited."""

    teeter_rad: float = 0.01
    twist_rad: float = 0.005

    def __post_init__(self):
        _num("perturbation.teeter_rad", self.teeter_rad, -0.2, 0.2)
        _num("perturbation.twist_rad", self.twist_rad, -0.1, 0.1)


@dataclass(frozen=True)
class Case:
    """Everything that determines a run; ``key()`` identifies it for stored, shared results.
    ``t_end_s``: simulated time [s] of :meth:`Simulation.run`, in (0, 600]."""

    rotor: Rotor
    flight: FlightCondition = FlightCondition()
    settings: SolverSettings = SolverSettings()
    t_end_s: float = 10.0
    perturbation: Perturbation = Perturbation()

    def __post_init__(self):
        for name, kind in (("rotor", Rotor), ("flight", FlightCondition), ("settings", SolverSettings),
                           ("perturbation", Perturbation)):
            if not isinstance(getattr(self, name), kind):
                raise SettingsError(f"{name} = {getattr(self, name)!r} is not allowed: must be a {kind.__name__}")
        _positive("t_end_s", self.t_end_s, T_END_MAX_S)

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
        if not isinstance(case, Case):
            raise SettingsError(f"case = {case!r} is not allowed: must be a Case")
        self.case = case  #: the case now: its parameters follow every change (set_parameters)
        self.start_case = case  #: the case as the run started (a file's name and header say this one)
        self.model: CompiledModel = compile_model(case.rotor, case.flight, case.settings)
        tr = trim_result if trim_result is not None else trim(self.model)
        self.trim = tr
        if tr.ok:
            self.start_note = "started from the trimmed steady autorotation plus the perturbation"
            self.model = tr.model
        elif tr.state is not None:
            be = tr.branch_end
            if be.get("kind") == "forward-speed":
                self.start_note = _forward_start_note(be, case.flight)
                self.model = _with_controls_of(self.model, tr.model,
                                               airspeed_m_s=_requested_airspeed(be, case.flight, self.model))
            elif "gj_scale" not in be:  # no branch to follow: even the stiff start has no normal autorotation
                self.start_note = (f"{tr.reason or 'no steady autorotation for these parameters'}: started from the "
                                   f"equilibrium of that stiffer blade (mean GJ {gj_mean_of(tr.model):.0f} N m^2/rad, "
                                   f"rotor speed {tr.omega_rad_s:.2f} rad/s, descent rate {tr.descent_rate_m_s:.1f} m/s) "
                                   f"with the requested parameters switched on at t = 0")
                self.model = _with_controls_of(self.model, tr.model)
            else:
                self.start_note = (("no trim found for these parameters (the branch's last trim is already unstable)"
                                    if be.get("last_trim_unstable") else "no steady autorotation for these parameters")
                                   + f": started from the last trim of the branch followed down in GJ "
                                   f"(at GJ {be['gj_mean_nm2']:.0f} N m^2/rad span mean, {be['gj_scale']:.3g} times "
                                   f"this blade's; rotor speed {be['omega_rad_s']:.2f} rad/s) with the requested "
                                   f"parameters switched on at t = 0")
                # ("GJ x2.07, mean GJ 415" read as a riddle)
                # keep the branch-end flight controls (tilt, holds) but the requested structure
                self.model = _with_controls_of(self.model, tr.model)
        else:  # nothing to start from: a run that never starts, whose verdict is the trim's
            self._not_started(tr)
            return
        self.omega_ref = float(tr.state[Y_OMEGA])
        self.y = transfer_state(tr.state, tr.model, self.model)
        self.reference_row = self._row(self.y)
        self._apply_perturbation(case.perturbation)
        self.t = 0.0
        #: advance ratio of the run [-] (its forward step is capped by it: model.forward_run_cap_s)
        self.mu = advance_ratio(self.model, self.omega_ref)
        self.dt = case.settings.dt_s or run_time_step(self.model, 1.3 * self.omega_ref, self.mu)
        self.record_every = max(1, int(round(RECORD_INTERVAL_S / self.dt)))
        #: history sampling interval [s] of this run, kept when a parameter change alters the step
        self.record_interval_s = self.dt * self.record_every
        self.status = "running"
        self._chunks: list = []
        self._states: list = []  # (states, model whose layout they are in)
        self.wall_time_s = 0.0
        #: live parameter changes during the run: (history row where the new values start, time [s], text)
        self.changes: list = []
        self._change_trim = None  #: (number of changes, TrimResult of the latest values)

    def _not_started(self, tr: TrimResult) -> None:
        self.start_note = f"not started: no trimmed state to start from, not even a branch end ({tr.reason})"
        self.omega_ref = float("nan")
        self.y = np.zeros(self.model.n_y)
        self.reference_row = np.full(len(HISTORY_COLUMNS), np.nan)
        self.t, self.dt, self.record_every, self.record_interval_s = 0.0, RECORD_INTERVAL_S, 1, RECORD_INTERVAL_S
        self.status = "not-started"
        self._chunks, self._states, self.wall_time_s = [], [], 0.0
        self.changes, self._change_trim = [], None

    # ------------------------------------------------------------------ stepping
    def advance(self, n_steps: Optional[int] = None, span_s: Optional[float] = None) -> np.ndarray:
        """March ``n_steps`` time steps or ``span_s`` seconds (rounded up to whole recording
        intervals; neither: one interval) and return the new history rows. One call records at most
        :data:`MAX_CHUNK_ROWS` rows (100 s): longer spans raise :class:`SettingsError` (call
        ``advance`` repeatedly, or :meth:`run`), because the chunk's buffers are allocated up front.
        A run that ended (numerical failure, rotor stopped, overspeed) returns no rows."""
        if n_steps is not None and span_s is not None:
            raise SettingsError("advance: give n_steps or span_s, not both")
        max_steps = MAX_CHUNK_ROWS * self.record_every
        why = (f"one chunk records at most {MAX_CHUNK_ROWS} rows ({MAX_CHUNK_ROWS * self.record_interval_s:g} s "
               f"at the {1e3 * self.record_interval_s:g} ms recording interval); call advance repeatedly or use run()")
        if n_steps is not None:
            if isinstance(n_steps, bool) or not isinstance(n_steps, (int, np.integer)):
                raise SettingsError(f"n_steps = {n_steps!r} is not allowed: must be an integer in [1, {max_steps}]")
            if not 1 <= n_steps <= max_steps:
                raise SettingsError(f"n_steps = {n_steps!r} is not allowed: must lie in [1, {max_steps}]: {why}")
            n_steps = int(n_steps)
        elif span_s is not None:
            _positive("span_s", span_s, MAX_CHUNK_ROWS * self.record_interval_s * (1 + 1e-9), why)
            # a span that is a whole number of steps up to rounding (a chunk ending at a scripted change,
            # after times summed in other chunks) is that number, not one more: the change at 2 s of a
            # forward-flight preset landed at 2.002 s at one playback speed and at 2.000 s at another
            n_steps = min(max(1, int(math.ceil(span_s / self.dt - SPAN_ROUNDING_STEPS))), max_steps)
        else:
            n_steps = self.record_every
        if self.status in TERMINAL_STATUSES:
            return np.zeros((0, len(HISTORY_COLUMNS)))
        self.status = "running"
        n_steps = max(self.record_every, int(math.ceil(n_steps / self.record_every)) * self.record_every)
        n_rec = n_steps // self.record_every
        hist = np.empty((n_rec, len(HISTORY_COLUMNS)))
        states = np.empty((n_rec, len(self.y)))
        t0 = time.perf_counter()
        done, rows, status = kernel_guard.advance(self.y, self.t, self.dt, n_steps, self.record_every,
                                                  self.model.arrays, hist, states, 0.02 * self.omega_ref)
        self.wall_time_s += time.perf_counter() - t0
        self.t += done * self.dt
        hist, states = hist[:rows], states[:rows]
        self._chunks.append(hist)
        self._states.append((states, self.model))
        if status == 1:
            self.status = "numerical-failure"
        elif status == 2:
            self.status = "rotor-stopped"
        elif self.y[Y_OMEGA] > OVERSPEED_STOP * self.omega_ref:
            self.status = "overspeed-stop"
        return hist

    def run(self, t_end_s: Optional[float] = None, chunk_s: float = 0.5,
            progress: Optional[Callable[[float, float], None]] = None) -> "Simulation":
        """March to ``t_end_s`` [s] (default ``case.t_end_s``) in chunks of ``chunk_s`` [s]; the status
        is then ``finished`` unless the run ended earlier (see :data:`TERMINAL_STATUSES`)."""
        t_end = self.case.t_end_s if t_end_s is None else _positive("t_end_s", t_end_s, T_END_MAX_S)
        chunk = _positive("chunk_s", chunk_s, MAX_CHUNK_ROWS * self.record_interval_s)
        if self.status in TERMINAL_STATUSES:
            return self
        while self.t < t_end - 1e-9:
            self.advance(span_s=min(chunk, t_end - self.t))
            if progress:
                progress(self.t, t_end)
            if self.status != "running":
                return self
        self.status = "finished"
        return self

    def set_parameters(self, gj_nm2=None, x_ea=None, x_cg=None) -> None:
        """Change uniform GJ [N m^2/rad], EA and CG [chord fractions]; the run continues.

        The running state is re-projected into a new state vector of the new model's layout
        (:func:`amra_core.model.transfer_state`: azimuth, rotor speed, descent rate, inflow and lag
        copied; the physical structural motion projected onto the new modal basis, whose number of
        retained modes can differ, with the teeter angle and rate kept exactly; aerodynamic lag and
        inflow states copied), and the stable time
        step is recomputed for the new stiffness (the recording interval is kept, so the history
        stays uniformly sampled). A rejected value leaves the run unchanged."""
        before = self.case.rotor.stations
        rotor = self.case.rotor.with_overrides(gj_nm2=gj_nm2, x_ea=x_ea, x_cg=x_cg)
        new = _with_controls_of(compile_model(rotor, self.case.flight, self.case.settings), self.model)
        if self.status == "not-started":  # nothing runs: only the description changes
            self.case, self.model, self.y = replace(self.case, rotor=rotor), new, np.zeros(new.n_y)
            self.start_case = self.case
            return
        y = transfer_state(self.y, self.model, new)
        _keep_teeter(y, new, *(v[0] for v in self.model.physical(self.y)))
        kernel_guard.check_state(y, new.arrays)
        dt, every = self._time_step_for(new, y)
        self.case = replace(self.case, rotor=rotor)
        self.model, self.y, self.dt, self.record_every = new, y, dt, every
        if self._chunks:  # the verdict now judges the motion since this change (verdict())
            # what changed (a dashboard sends GJ, EA and CG together: "the change to GJ 300 N m^2/rad,
            # EA 32.0 % chord, CG 40.0 % chord" named two values that had not moved)
            def moved(v, old):
                return v is not None and not all(x == float(v) for x in old)
            parts = [f"GJ {gj_nm2:.4g} N m^2/rad"] if moved(gj_nm2, before.gj_nm2) else []
            parts += [f"{name} {100 * v:.1f} % chord" for name, v, old in (("EA", x_ea, before.x_ea),
                                                                           ("CG", x_cg, before.x_cg)) if moved(v, old)]
            parts = parts or ["the same values"]
            what = f"the change to {', '.join(parts)} at t = {self.t:.2f} s"
            self.changes.append((sum(len(c) for c in self._chunks), self.t, what))

    def _time_step_for(self, model: CompiledModel, y: np.ndarray):
        """(dt, record_every) for ``model``: the given ``dt_s``, else the stable step at 1.3 times the
        larger of the trim and current rotor speed, shortened to a whole fraction of the run's
        recording interval."""
        if self.case.settings.dt_s:
            return self.dt, self.record_every
        dt_stable = run_time_step(model, 1.3 * max(self.omega_ref, abs(float(y[Y_OMEGA]))), self.mu)
        every = max(1, int(math.ceil(self.record_interval_s / dt_stable - 1e-9)))
        return self.record_interval_s / every, every

    # ------------------------------------------------------------------ results
    @property
    def history(self) -> np.ndarray:
        if not self._chunks:
            return np.zeros((0, len(HISTORY_COLUMNS)))
        return np.concatenate(self._chunks)

    @property
    def states(self) -> np.ndarray:
        """Full state per history row, in the current model's layout (rows recorded before a
        parameter change are projected onto the current modal basis, as the running state was)."""
        if not self._states:
            return np.zeros((0, len(self.y)))
        return np.concatenate([_project_states(S, m, self.model) for S, m in self._states])

    def _one_revolution_s(self) -> float:
        if not self._chunks or not len(self._chunks[-1]):
            return 0.0
        return 2 * math.pi / max(self._chunks[-1][-1, COL["omega_rad_s"]], 1e-3)

    def _tail(self, span_s: float) -> tuple:
        """``(history, states)`` of the last recorded chunks that cover ``span_s`` seconds: the
        disc view asks every second, and joining the whole run's states each time cost a live
        session a growing share of its thread (17 % at eight sessions)."""
        if not self._chunks:
            return np.zeros((0, len(HISTORY_COLUMNS))), np.zeros((0, len(self.y)))
        t_last = self._chunks[-1][-1, 0] if len(self._chunks[-1]) else -math.inf
        k = len(self._chunks) - 1  # back to the newest chunk that starts at or before t_last - span_s
        while k > 0 and not (len(self._chunks[k]) and self._chunks[k][0, 0] <= t_last - span_s):
            k -= 1
        h = np.concatenate(self._chunks[k:])
        S = np.concatenate([_project_states(St, m, self.model) for St, m in self._states[k:]])
        return h, S

    def spanwise_last_revolution(self, n_azimuth: int = 36) -> dict:
        """Distributions over the last recorded revolution for disc plots: radius [m], azimuth
        of blade 0 [rad], and per (azimuth, station) torque per length [N m/m], elastic twist
        [rad] and flap displacement [m] of blade 0 (blade 1 is at azimuth + pi)."""
        h, S = self._tail(self._one_revolution_s())
        if len(h) < 2:
            return {}
        t_rev = 2 * math.pi / max(h[-1, COL["omega_rad_s"]], 1e-3)
        idx = np.nonzero(h[:, 0] >= h[-1, 0] - t_rev)[0]
        pick = idx[np.linspace(0, len(idx) - 1, min(n_azimuth, len(idx))).astype(int)]
        out = np.zeros((2, self.model.n_st, 5))
        torque, twist, flap, psi = [], [], [], []
        for k in pick:
            kernel_guard.station_loads(S[k].copy(), self.model.arrays, out)
            torque.append(out[0, :, 1].copy()); twist.append(out[0, :, 3].copy()); flap.append(out[0, :, 4].copy())
            psi.append(float(np.mod(S[k][0], 2 * math.pi)))
        return {"r_m": self.model.arrays.st[:, 0].tolist(), "azimuth_rad": psi,
                "torque_per_length_nm_m": np.array(torque).tolist(),
                "twist_rad": np.array(twist).tolist(), "flap_m": np.array(flap).tolist()}

    def verdict(self) -> Verdict:
        """Verdict on the run so far (model-notes §5); ``undetermined`` before any data. After a live
        :meth:`set_parameters`, the motion since the last change is judged, about the trim of the new
        values in axial flight (:func:`amra_core.verdict.judge_after_change`; that trim is computed
        at the first verdict after the change: 16-81 ms for McCutcheon, rigid to fem-coupled)."""
        if self.status == "not-started":
            return Verdict("no-autorotation", None, None, None,
                           explanation=self.trim.reason or "no trimmed state to start from")
        if not self._chunks or len(self.history) == 0:
            return Verdict("undetermined", None, None, None,
                           explanation="no data yet: call advance() or run() before asking for a verdict")
        scale = max(abs(self.case.perturbation.teeter_rad), abs(self.case.perturbation.twist_rad), 1e-4)
        r, fl = self.case.rotor, self.case.flight
        v_h = math.sqrt(r.vehicle_mass_kg * fl.gravity_m_s2 / (2 * fl.density_kg_m3 * r.disc_area_m2))
        if self.changes:  # after a live change the trim is no reference: judge the motion since it
            row, _, what = self.changes[-1]
            new_row = new_omega = None
            trimmed = True
            if fl.is_axial:
                tr = self._trim_after_change()
                trimmed = tr.ok
                if tr.ok:
                    new_row, new_omega = self._row(tr.state, tr.model), float(tr.state[Y_OMEGA])
            return judge_after_change(self.history, HISTORY_COLUMNS, row, what, self.omega_ref, fl.is_axial,
                                      self.status, new_row, new_omega, trimmed, scale, hover_induced_m_s=v_h)
        return judge(self.history, HISTORY_COLUMNS, self.omega_ref, fl.is_axial, self.status,
                     self.trim.ok, self.reference_row, scale, hover_induced_m_s=v_h,
                     branch=self.trim.branch if self.trim.ok else None)

    def _row(self, y: np.ndarray, model: Optional[CompiledModel] = None) -> np.ndarray:
        m = (model or self.model).arrays
        row = np.zeros(len(HISTORY_COLUMNS)); loads = np.zeros(8); dy = np.zeros_like(y)
        kernel_guard.evaluate(y, m, dy, loads)
        kernel_guard.record_row(0.0, y, m, loads, row)
        return row

    def _trim_after_change(self) -> TrimResult:
        """The trim of the values set by the last live change (computed once per change, when a
        verdict is first asked for: an axial trim takes milliseconds to a few tenths of a second)."""
        n = len(self.changes)
        if self._change_trim is None or self._change_trim[0] != n:
            self._change_trim = (n, trim(self.model))
        return self._change_trim[1]

    def to_csv(self, path, verdict=None) -> None:
        """The full-resolution history, with the case, its live changes, its start, its ``verdict``
        (a :class:`~amra_core.verdict.Verdict`) and the solver version in ``#`` header lines
        (:func:`amra_core.export.run_meta`)."""
        from .export import run_meta, table_csv
        meta = run_meta(self, verdict)
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(table_csv(HISTORY_COLUMNS, self.history, meta))

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


def _with_controls_of(model: CompiledModel, source: CompiledModel, airspeed_m_s=None) -> CompiledModel:
    from .model import P_ALPHA_S, P_HOLD_OMEGA, P_HOLD_VD, P_VH
    ps = source.arrays.p
    return model.with_controls(alpha_s_rad=ps[P_ALPHA_S], airspeed_m_s=ps[P_VH] if airspeed_m_s is None else airspeed_m_s,
                               hold_omega=ps[P_HOLD_OMEGA] > 0.5, hold_vd=ps[P_HOLD_VD] > 0.5,
                               quasi_static=False)


def _requested_airspeed(be: dict, flight: FlightCondition, model: CompiledModel) -> float:
    """Airspeed [m/s] of the requested condition, for a run started at a forward branch end: the
    given airspeed, or the requested advance ratio at the branch end's rotor speed and shaft tilt."""
    if flight.mu is None:
        return float(flight.airspeed_m_s)
    return float(flight.mu * be["omega_rad_s"] * model.rotor.radius_m / math.cos(be["disk_tilt_rad"]))


def _forward_start_note(be: dict, flight: FlightCondition) -> str:
    req = f"mu {flight.mu:g}" if flight.mu is not None else f"airspeed {flight.airspeed_m_s:g} m/s"
    return (f"no steady autorotation found at {req}: started from the nearest trimmed condition, the end of the "
            f"forward-flight trim branch (mu {be['mu']:.3g}, airspeed {be['airspeed_m_s']:.1f} m/s, rotor speed "
            f"{be['omega_rad_s']:.2f} rad/s, descent rate {be['descent_rate_m_s']:.2f} m/s, shaft tilt "
            f"{math.degrees(be['disk_tilt_rad']):.2f} deg, mean GJ {be.get('gj_mean_nm2', float('nan')):.0f} "
            f"N m^2/rad), with the requested {req} and parameters switched on at t = 0")


def _keep_teeter(y: np.ndarray, model: CompiledModel, beta: float, beta_dot: float) -> None:
    """Correct the modal coordinates of ``y`` so the teeter angle and rate are exactly ``beta`` and
    ``beta_dot``: the smallest change in the (M-orthonormal) modal coordinates, i.e. in kinetic
    energy norm, along the teeter row ``t`` (``q += (beta - t.q) t / t.t``). The M-orthogonal
    projection alone moves the teeter angle by the truncated modes' share (1.1e-4 rad of a 1.9e-3 rad
    angle measured for fem-torsion GJ 1 -> 1e6, where every torsion mode lies above the cut-off)."""
    t = model.arrays.teeter
    tt = float(t @ t)
    if tt <= 0.0:
        return
    for sl, target in ((model.x_slice(), beta), (model.xd_slice(), beta_dot)):
        q = y[sl]
        y[sl] = q + (target - float(t @ q)) * t / tt


def _project_states(S: np.ndarray, src: CompiledModel, dst: CompiledModel) -> np.ndarray:
    """Rows of states in ``src``'s layout mapped onto ``dst``'s (vectorised :func:`transfer_state`)."""
    if src is dst or (src.phi.shape == dst.phi.shape and np.array_equal(src.phi, dst.phi)
                      and src.n_y == dst.n_y):
        return S
    out = np.zeros((S.shape[0], dst.n_y))
    out[:, :N_Y_FIXED] = S[:, :N_Y_FIXED]
    out[:, dst.x_slice()] = S[:, src.x_slice()] @ src.phi.T @ dst.phi_pinv.T
    out[:, dst.xd_slice()] = S[:, src.xd_slice()] @ src.phi.T @ dst.phi_pinv.T
    if src.n_st == dst.n_st:
        out[:, dst.aero_slice()] = S[:, src.aero_slice()]
    if src.n_inflow_harmonics == dst.n_inflow_harmonics:
        out[:, dst.inflow_harmonics_slice()] = S[:, src.inflow_harmonics_slice()]
    return out
