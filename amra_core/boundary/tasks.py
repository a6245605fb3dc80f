"""The work of a map: one task per CG column (picklable, what a worker receives), the cells of a
column walk, and the worker entry point :func:`compute_column` (never raises)."""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Optional

import numpy as np

from ..flight import FlightCondition, SolverSettings
from ..rotor import Rotor
from ..stability import CellResult

def failed_cell(cg: float, gj: float, reason: str) -> CellResult:
    return CellResult(cg, gj, "failed", False, "", None, None, None, reason)


def cell_class(c: CellResult) -> str:
    """``stable`` | ``flutter`` (trimmed on the normal branch, unstable) | ``fold`` (no normal
    autorotation: no trim, or the normal branch overspeeding, whether or not a mode grows there: the
    column's intervals call that stretch ``overspeed``, and the fold line is drawn above it) |
    ``windmill-brake`` (a windmill-brake equilibrium) | ``failed``. An overspeeding cell keeps the
    verdict a run from it gives first (``flutter``, ``divergence``: :func:`cells_of_walk`); drawn as
    flutter it read as flutter below the fold line (fem-coupled axial, CG 40 %: GJ 82-412 red under
    the fold at 664)."""
    if c.verdict == "failed":
        return "failed"
    if c.verdict == "windmill-brake" or c.branch == "windmill-brake":
        return "windmill-brake"
    if c.stable:
        return "stable"
    return "fold" if c.boundary_kind in ("fold", "overspeed") or c.verdict in ("no-autorotation", "overspeed") \
        or c.branch == "overspeed" else "flutter"


# ----------------------------------------------------------------------------- columns
@dataclass(frozen=True)
class ColumnTask:
    """One CG column to walk (picklable: what a worker receives)."""

    cg: float
    rotor: Rotor  #: carries the map's EA
    flight: FlightCondition
    settings: SolverSettings
    method: str
    gj_min: float
    gj_max: float
    rel_tol: float
    n_probe: int
    max_step: float


@dataclass
class ColumnResult:
    """What a worker returns for a column (light: no models or states). ``failed``: the walk raised."""

    cg: float
    cells: list
    intervals: list
    critical_gj: Optional[float]
    fold_gj: Optional[float]
    n_trims: int = 0
    wall_time_s: float = 0.0
    failed: bool = False
    cancelled: bool = False


def cells_of_walk(cg: float, points: list, top_omega: Optional[float] = None) -> list:
    """The map cells of a column walk's points (GJ ascending). Verdicts use the words of a run's
    verdict (:data:`amra_core.verdict.VERDICTS`) so a cell and ``amra simulate`` of it can agree:
    a windmill-brake root below a fold is ``no-autorotation`` (a run started there from the branch
    end descends into that state; the cell keeps ``branch`` and ``boundary_kind`` windmill-brake),
    the normal branch overspeeding is ``overspeed`` unless a mode grows there (then ``flutter`` or
    ``divergence``, as a run from it would say first)."""
    from ..stability import MIN_FLUTTER_HZ, UNSTABLE_REAL_PART, cell_from_modes
    pts = sorted(points, key=lambda p: p.gj_nm2)
    on_branch = ("normal", "overspeed")
    if top_omega is None:
        tops = [p for p in pts if p.branch in on_branch]
        top_omega = tops[-1].trim.omega_rad_s if tops else None
    cells = []
    for i, p in enumerate(pts):
        kind = p.kind
        if kind in ("stable", "flutter"):
            c = cell_from_modes(cg, p.gj_nm2, p.trim, p.modes)
        elif kind == "overspeed" and p.modes and not all(m.real_part_per_s < UNSTABLE_REAL_PART for m in p.modes):
            c = replace(cell_from_modes(cg, p.gj_nm2, p.trim, p.modes), branch="overspeed")  # growing: flutter first
            c = replace(c, reason=f"{c.reason} on the overspeeding branch: {p.reason}")
        elif kind == "overspeed":
            crit = p.critical
            c = CellResult(cg, p.gj_nm2, "overspeed", False, "overspeed",
                           None if crit is None else crit.real_part_per_s, None if crit is None else crit.frequency_hz,
                           float(p.trim.omega_rad_s), p.reason, "overspeed", float(p.trim.descent_rate_m_s))
        elif kind == "windmill-brake":
            c = CellResult(cg, p.gj_nm2, "no-autorotation", False, "windmill-brake", None, None,
                           float(p.trim.omega_rad_s), "no normal autorotation; " + p.reason, "windmill-brake",
                           float(p.trim.descent_rate_m_s))
        elif kind == "fold":
            above = next((q for q in pts[i + 1:] if q.branch in on_branch), None)
            rising = above is not None and top_omega is not None and above.trim.omega_rad_s > top_omega
            why = p.reason or "no trim on the normal branch"
            fluttering = [m for m in (above.modes or ()) if m.real_part_per_s >= UNSTABLE_REAL_PART
                          and m.frequency_hz >= MIN_FLUTTER_HZ] if above is not None and not rising else []
            if fluttering:  # as amra_core.trim._branch_end says of the same end
                crit = max(fluttering, key=lambda m: m.real_part_per_s)
                why = (f"no trim found below GJ {above.gj_nm2:.0f} N m^2/rad, where the autorotation already "
                       f"flutters ({crit.label}, {crit.real_part_per_s:+.3g} 1/s): not shown to be a fold, an "
                       f"unstable autorotation may go on below")
            c = CellResult(cg, p.gj_nm2, "overspeed" if rising else "no-autorotation", False, "fold", None, None,
                           None, why, "none")
        else:
            c = failed_cell(cg, p.gj_nm2, f"numerical failure: {p.reason}")
        cells.append(c)
    return cells


def _time_cells(task: ColumnTask, points: list, cells: list) -> list:
    """``method='time'``: the walk's normal-branch points judged by time marching from their trim."""
    from ..simulation import Case, Simulation
    out = []
    for p, c in zip(sorted(points, key=lambda p: p.gj_nm2), cells):
        if p.branch not in ("normal", "overspeed"):
            out.append(c)
            continue
        rotor = task.rotor.with_overrides(gj_nm2=p.gj_nm2, x_cg=task.cg)
        sim = Simulation(Case(rotor, task.flight, task.settings, t_end_s=8.0), trim_result=p.trim).run()
        v = sim.verdict()
        kind = "" if not v.unstable else ("overspeed" if v.verdict == "overspeed" else "flutter")
        out.append(CellResult(task.cg, p.gj_nm2, v.verdict, v.verdict == "stable", kind, v.growth_rate_per_s,
                              v.frequency_hz, p.trim.omega_rad_s, v.explanation, p.branch,
                              float(p.trim.descent_rate_m_s)))
    return out


#: simulated time [s] of the run that measures what a flutter interval's instability leads to
OUTCOME_RUN_S = 20.0


def interval_outcomes(task: ColumnTask, points: list, intervals: list, cancel=None) -> None:
    """For every flutter interval: a run from the trim of its most unstable point (the default kick,
    ``OUTCOME_RUN_S``) says what the instability leads to (issue 21 §1): ``run_outcome`` (decays,
    bounded-oscillation, rotor-speed-collapse, runaway), ``run_verdict`` and ``run_amplitude``
    (half peak-to-peak over the run's last third: twist and teeter [deg], rotor speed [rad/s]).
    Written into the interval dicts; a failed run leaves them out (the strength then follows the
    damping ratio alone)."""
    from ..simulation import HISTORY_COLUMNS, Case, Simulation
    from ..verdict import oscillation_amplitudes
    for iv in intervals:
        if iv["kind"] != "flutter" or (cancel is not None and cancel.is_set()):
            continue
        inside = [p for p in points if p.kind == "flutter" and p.trim is not None
                  and iv.get("gj_lo_point_nm2", iv["gj_lo_nm2"]) <= p.gj_nm2 <= iv.get("gj_hi_point_nm2", iv["gj_hi_nm2"])]
        if not inside:
            continue
        p = max(inside, key=lambda q: q.max_real_part_per_s)
        try:
            rotor = task.rotor.with_overrides(gj_nm2=p.gj_nm2, x_cg=task.cg)
            sim = Simulation(Case(rotor, task.flight, task.settings, t_end_s=OUTCOME_RUN_S), trim_result=p.trim).run()
            v = sim.verdict()
            amp = oscillation_amplitudes(sim.history, HISTORY_COLUMNS, sim.omega_ref, task.flight.is_axial,
                                         sim.reference_row, max(abs(sim.case.perturbation.teeter_rad),
                                                                abs(sim.case.perturbation.twist_rad)))
        except Exception:  # noqa: BLE001 - the interval keeps its eigen classification
            continue
        iv.update({"run_gj_nm2": p.gj_nm2, "run_verdict": v.verdict, "run_outcome": v.outcome, "run_amplitude": amp})


def compute_column(task: ColumnTask, on_point=None, cancel=None) -> ColumnResult:
    """Worker entry point: walk one column; an exception becomes a ``failed`` column (never raises)."""
    from ..column import walk_column
    try:
        with np.errstate(all="ignore"):
            w = walk_column(task.rotor, task.flight, task.settings, task.cg, task.gj_min, task.gj_max,
                            rel_tol=task.rel_tol, on_point=on_point, cancel=cancel, max_step=task.max_step,
                            n_probe=task.n_probe)
            cells = cells_of_walk(task.cg, w.points)
            if task.method == "time":
                cells = _time_cells(task, w.points, cells)
        intervals = w.intervals
        crit = w.critical_gj_nm2
        if task.method != "time" and not w.cancelled:
            with np.errstate(all="ignore"):
                interval_outcomes(task, w.points, intervals, cancel)
        if task.method == "time":
            intervals, crit = _summary_of_cells(cells, task)
            with np.errstate(all="ignore"):
                _time_interval_strength(task, w.points, cells, intervals, cancel)
        return ColumnResult(task.cg, cells, intervals, crit, w.fold_gj_nm2, w.n_trims, w.wall_time_s,
                            any(c.verdict == "failed" for c in cells), w.cancelled)
    except Exception as exc:  # noqa: BLE001 - a failed column is a result, not a crash
        return ColumnResult(task.cg, [failed_cell(task.cg, task.gj_max, f"{type(exc).__name__}: {exc}")], [], None,
                            None, failed=True)


def _time_interval_strength(task: ColumnTask, points: list, cells: list, intervals: list, cancel=None) -> None:
    """``method='time'``: what the eigen-analysis gives a flutter interval, from its time-judged cells,
    so that :func:`amra_core.boundary.intervals.strength_of` applies the same weak/strong rule:
    ``peak_growth_rate_1_s`` (the largest fitted envelope growth [1/s]), ``damping_ratio`` of that
    oscillation (-sigma / sqrt(sigma^2 + (2 pi f)^2); None if it does not oscillate: then strong),
    and the 20 s run from its most unstable point (:func:`interval_outcomes`)."""
    from types import SimpleNamespace
    by_gj = {p.gj_nm2: p for p in points}
    unstable = []
    for c in cells:
        p = by_gj.get(c.gj_nm2)
        if cell_class(c) == "flutter" and c.growth_rate_per_s is not None and p is not None and p.trim is not None:
            unstable.append((c, p))
    for iv in intervals:
        if iv["kind"] != "flutter":
            continue
        lo, hi = iv.get("gj_lo_point_nm2", iv["gj_lo_nm2"]), iv.get("gj_hi_point_nm2", iv["gj_hi_nm2"])
        inside = [(c, p) for c, p in unstable if lo <= c.gj_nm2 <= hi]
        if not inside:
            continue
        c, _ = max(inside, key=lambda cp: cp[0].growth_rate_per_s)
        sigma, f = float(c.growth_rate_per_s), c.frequency_hz
        iv["peak_growth_rate_1_s"] = sigma
        iv["damping_ratio"] = (-sigma / math.hypot(sigma, 2 * math.pi * f)) if f else None
    pseudo = [SimpleNamespace(kind="flutter", trim=p.trim, gj_nm2=c.gj_nm2, max_real_part_per_s=c.growth_rate_per_s)
              for c, p in unstable]
    interval_outcomes(task, pseudo, intervals, cancel)


def _summary_of_cells(cells: list, task: ColumnTask):
    """(intervals, critical GJ) from cells (used when the cells' classes are not the walk's)."""
    from ..column import summarise

    class _P:  # the two attributes summarise reads
        def __init__(self, c):
            self.gj_nm2, self.kind = c.gj_nm2, cell_class(c)
    return summarise([_P(c) for c in cells], task.gj_min, task.gj_max, task.rel_tol)
