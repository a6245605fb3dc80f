"""Stability boundary map over CG x GJ (issues 4 and 8, paper Fig. 14), computed column by column.

For a fixed rotor, fidelity, aerodynamic model, advance ratio and elastic axis, every CG column
[chord fraction] is walked down its trim branch by :func:`amra_core.column.walk_column`: from the
stiffest blade (``gj_max``) downward in log GJ by continuation (never a cold restart on the
branch, so the windmill-brake root cannot take over), with the modes at every point and every sign
change of the largest real part, and the fold, bracketed to ``gj_rel_tol``. Below a fold the column
is probed by cold starts on the ``n_coarse`` log grid. Each point becomes a cell; verdicts:
``stable``, ``flutter``, ``divergence`` (unstable, non-oscillatory), ``overspeed`` /
``no-autorotation`` (no normal-branch trim: below a fold where the rotor speed was rising /
falling), ``windmill-brake`` (an equilibrium with V_c/v_h beyond the turbulent-wake region: not
autorotation, never counted stable) and ``failed`` (a numerical failure or a crashed worker).

Progression: one task per column (the columns run in parallel on the executor); with the
in-process serial executor (``workers=1``) the cells of a column are handed out as each point is
found, with a pool when the column is finished. ``on_cell``/:func:`iter_map` hand out every cell;
a ``threading.Event`` ``cancel`` is checked between cells (and at least every 0.1 s) and a
cancelled map returns what it has. With a :class:`~amra_core.store.CellStore`, finished columns are
kept (each cell under its case key as before; the cell at ``gj_max`` also carries the column record:
the walk's GJ values and intervals), so a repeated map is read back at once; an interrupted map
resumes with the columns it had not finished (a column walk restarts from its top: continuation needs
the trimmed states, which the store does not keep). A column whose worker crashed
(``Outcome.ok`` False) or that contains a failed cell is never stored: it is shown as failed in
that run only.

Outputs (:class:`BoundaryMap`): ``cells``; ``columns``: per column ``critical_gj`` (the *upper end*
of the final bracket: the lowest computed GJ from which the column is stable all the way up to
``gj_max``; ``None`` when stable over the whole range, ``math.inf`` when unstable at ``gj_max``),
``bracket``, ``status``, ``kind``, ``fold_gj`` and ``intervals`` (every stable / flutter / fold /
windmill-brake interval); ``boundaries``: every transition between neighbouring cells with its kind.
"""
from __future__ import annotations

import csv
import functools
import hashlib
import json
import math
import threading
import time
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Callable, Iterator, Optional, Union

import numpy as np

from . import __version__
from .executor import CellExecutor, LocalPoolExecutor, Outcome, SerialExecutor
from .flight import AERO_MODELS, FlightCondition, SolverSettings
from .rotor import Rotor
from .shapes import FIDELITIES, TORSION_SPRINGS
from .stability import CellResult

VERDICTS = ("stable", "flutter", "divergence", "overspeed", "no-autorotation", "windmill-brake", "failed")
METHODS = ("eigen", "time")
DEFAULT_CG = tuple(round(float(x), 6) for x in np.linspace(0.20, 0.50, 16))

#: solver sources whose content enters the case key (with ``__version__``), so stored cells are
#: never served for a changed solver
_SOLVER_SOURCES = ("airfoil", "column", "flight", "kernels", "model", "rotor", "shapes", "simulation", "stability",
                   "structure", "trim", "verdict")


class MapSpecError(ValueError):
    """A map parameter is out of range; the message names it and the allowed range."""


@functools.lru_cache(maxsize=1)
def solver_fingerprint() -> str:
    """``<version>+<sha256 of the solver sources, 12 hex>``: part of every case key."""
    h = hashlib.sha256()
    here = Path(__file__).resolve().parent
    for name in _SOLVER_SOURCES:
        p = here / f"{name}.py"
        if p.is_file():
            h.update(name.encode())
            h.update(p.read_bytes())
    return f"{__version__}+{h.hexdigest()[:12]}"


def _gj_round(x: float) -> float:
    """GJ values to 10 significant digits, so keys do not depend on the last bit of a log grid."""
    return float(f"{x:.10g}")


def _num(name, v, lo, hi, lo_open=False):
    if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) or not math.isfinite(v):
        raise MapSpecError(f"{name} = {v!r} is not allowed: must be a finite number in "
                           f"{'(' if lo_open else '['}{lo}, {hi}]")
    if v < lo or v > hi or (lo_open and v == lo):
        raise MapSpecError(f"{name} = {v!r} is out of range: allowed {'(' if lo_open else '['}{lo}, {hi}]")
    return float(v)


@dataclass(frozen=True)
class MapSpec:
    """What to map.

    ``rotor``: a preset name (``paper-boundary``, ``mccutcheon``) or a :class:`Rotor`;
    ``fidelity``: ``rigid`` | ``fem-torsion`` | ``fem-coupled``; ``aero``: ``theodorsen`` |
    ``quasi-steady``; ``mu``: advance ratio [-] (0 = axial autorotation, eigenvalues; > 0 forward
    flight, Floquet); ``ea``: elastic axis [chord fraction]; ``cg_values``: CG columns [chord
    fraction], default 16 from 0.20 to 0.50; ``gj_min``, ``gj_max``: GJ range [N m^2/rad] (log
    scale); ``gj_rel_tol``: bracket width ``gj_hi/gj_lo - 1`` at which bisection stops [-];
    ``n_coarse``: GJ values of the log grid on which a column is probed by cold starts below a fold
    (and the largest walk step is at most its spacing); ``method``: ``eigen`` (linearised about trim)
    or ``time`` (the walk's points judged by time marching from their trim plus a perturbation);
    ``n_elements``: FEM elements per blade; ``bisect_fold``: kept for compatibility (the walk
    always brackets the fold).
    """

    rotor: Union[str, Rotor] = "paper-boundary"
    fidelity: str = "rigid"
    aero: str = "theodorsen"
    mu: float = 0.0
    ea: float = 0.32
    cg_values: tuple = DEFAULT_CG
    gj_min: float = 30.0
    gj_max: float = 3000.0
    gj_rel_tol: float = 0.02
    n_coarse: int = 7
    method: str = "eigen"
    n_elements: int = 10
    bisect_fold: bool = True
    rigid_spring: str = "frequency"  #: the rigid level's root torsion spring (SolverSettings.rigid_spring)

    def __post_init__(self):
        if not isinstance(self.rotor, (str, Rotor)):
            raise MapSpecError(f"rotor = {self.rotor!r} is not allowed: give a preset name or a Rotor")
        if self.fidelity not in FIDELITIES:
            raise MapSpecError(f"fidelity = {self.fidelity!r} is not allowed: choose one of {', '.join(FIDELITIES)}")
        if self.aero not in AERO_MODELS:
            raise MapSpecError(f"aero = {self.aero!r} is not allowed: choose one of {', '.join(AERO_MODELS)}")
        if self.method not in METHODS:
            raise MapSpecError(f"method = {self.method!r} is not allowed: choose one of {', '.join(METHODS)}")
        if self.rigid_spring not in TORSION_SPRINGS:
            raise MapSpecError(f"rigid_spring = {self.rigid_spring!r} is not allowed: choose one of "
                               f"{', '.join(TORSION_SPRINGS)}")
        _num("mu", self.mu, 0.0, 0.5)
        _num("ea", self.ea, 0.0, 1.0)
        cgs = tuple(self.cg_values) if not isinstance(self.cg_values, (str, bytes)) else None
        if not cgs:
            raise MapSpecError(f"cg_values = {self.cg_values!r} is not allowed: give at least one CG in [0, 1]")
        cgs = tuple(round(_num("cg", c, 0.0, 1.0), 6) for c in cgs)
        if len(set(cgs)) != len(cgs):
            raise MapSpecError(f"cg_values = {cgs!r} is not allowed: the CG values must be distinct")
        object.__setattr__(self, "cg_values", tuple(sorted(cgs)))
        _num("gj_min", self.gj_min, 1.0, 1e6)
        _num("gj_max", self.gj_max, 1.0, 1e6)
        if not self.gj_max > self.gj_min:
            raise MapSpecError(f"gj_max = {self.gj_max!r} is not allowed: must exceed gj_min = {self.gj_min!r}")
        _num("gj_rel_tol", self.gj_rel_tol, 1e-4, 1.0)
        if isinstance(self.n_coarse, bool) or not isinstance(self.n_coarse, int) or not 2 <= self.n_coarse <= 200:
            raise MapSpecError(f"n_coarse = {self.n_coarse!r} is not allowed: must be an integer in [2, 200]")
        if isinstance(self.n_elements, bool) or not isinstance(self.n_elements, int) or not 1 <= self.n_elements <= 60:
            raise MapSpecError(f"n_elements = {self.n_elements!r} is not allowed: must be an integer in [1, 60]")

    # -------------------------------------------------------------- derived objects
    @functools.cached_property
    def base_rotor(self) -> Rotor:
        """The rotor with the map's uniform EA (CG and GJ are set per cell)."""
        from .rotor_io import load_preset
        r = load_preset(self.rotor) if isinstance(self.rotor, str) else self.rotor
        return r.with_overrides(x_ea=self.ea, x_cg=self.cg_values[0])  # a valid section; cells set their CG

    @property
    def flight(self) -> FlightCondition:
        return FlightCondition(mu=self.mu) if self.mu > 0 else FlightCondition()

    @property
    def settings(self) -> SolverSettings:
        return SolverSettings(fidelity=self.fidelity, aero=self.aero, n_elements=self.n_elements,
                              rigid_spring=self.rigid_spring)

    @property
    def coarse_gj(self) -> tuple:
        return tuple(_gj_round(g) for g in np.geomspace(self.gj_min, self.gj_max, self.n_coarse))

    def rotor_name(self) -> str:
        return self.rotor if isinstance(self.rotor, str) else self.rotor.name

    def to_dict(self) -> dict:
        d = {k: getattr(self, k) for k in self.__dataclass_fields__ if k != "rotor"}
        d["rotor"] = self.rotor_name()
        d["cg_values"] = list(self.cg_values)
        return d

    # -------------------------------------------------------------- cases
    def case_params(self, cg: float, gj: float) -> dict:
        """Every parameter that determines cell (cg, gj), plus the solver fingerprint."""
        rot = self.base_rotor.with_overrides(gj_nm2=gj, x_cg=cg).to_dict()
        rot.pop("sources", None)
        return {"kind": "map-cell", "rotor": rot, "flight": asdict(self.flight), "settings": asdict(self.settings),
                "method": self.method, "cg": cg, "gj_nm2": gj, "solver": solver_fingerprint()}

    def key(self, cg: float, gj: float) -> str:
        """Case key of cell (cg, gj): sha256 of :meth:`case_params` (24 hex)."""
        blob = json.dumps(self.case_params(cg, gj), sort_keys=True, default=float)
        return hashlib.sha256(blob.encode()).hexdigest()[:24]

    def column_params(self, cg: float) -> dict:
        """Every parameter that determines the walk of column ``cg`` (a stored column record)."""
        rot = self.base_rotor.with_overrides(x_cg=cg).to_dict()
        rot.pop("sources", None)
        return {"kind": "map-column", "rotor": rot, "flight": asdict(self.flight), "settings": asdict(self.settings),
                "method": self.method, "cg": cg, "gj_min": self.gj_min, "gj_max": self.gj_max,
                "gj_rel_tol": self.gj_rel_tol, "n_coarse": self.n_coarse, "solver": solver_fingerprint()}

    def column_key(self, cg: float) -> str:
        blob = json.dumps(self.column_params(cg), sort_keys=True, default=float)
        return "col-" + hashlib.sha256(blob.encode()).hexdigest()[:24]

    @property
    def max_step(self) -> float:
        """Largest GJ ratio of one walk step: the column walk's default, or the probe grid spacing."""
        from .column import MAX_STEP
        return min(MAX_STEP, (self.gj_max / self.gj_min) ** (1.0 / (self.n_coarse - 1)))

    def column_task(self, cg: float) -> "ColumnTask":
        return ColumnTask(cg, self.base_rotor, self.flight, self.settings, self.method, self.gj_min, self.gj_max,
                          self.gj_rel_tol, self.n_coarse, self.max_step)

    def task(self, cg: float, gj: float) -> "CellTask":
        return CellTask(cg, gj, self.base_rotor.with_overrides(gj_nm2=gj, x_cg=cg), self.flight, self.settings,
                        self.method)


@dataclass(frozen=True)
class CellTask:
    """One cell to compute (picklable: what a worker receives)."""

    cg: float
    gj_nm2: float
    rotor: Rotor
    flight: FlightCondition
    settings: SolverSettings
    method: str


def compute_cell(task: CellTask) -> CellResult:
    """Worker entry point: classify one cell; any exception or non-finite result becomes a
    ``failed`` cell with the reason (never raises)."""
    from .stability import assess_cell
    try:
        with np.errstate(all="ignore"):
            res = assess_cell(task.rotor, task.flight, task.settings, method=task.method)
        bad = [k for k in ("growth_rate_per_s", "frequency_hz", "omega_trim_rad_s")
               if getattr(res, k) is not None and not math.isfinite(getattr(res, k))]
        if bad and res.verdict == "stable":
            res = failed_cell(task.cg, task.gj_nm2, f"numerical failure: non-finite {', '.join(bad)}")
        res = replace(res, cg=task.cg, gj_nm2=task.gj_nm2)
        if res.verdict == "numerical-failure":
            res = replace(res, verdict="failed", stable=False, boundary_kind="",
                          reason=f"numerical failure: {res.reason}")
        return res
    except Exception as exc:  # noqa: BLE001 - a failed case is a result, not a crash
        return failed_cell(task.cg, task.gj_nm2, f"{type(exc).__name__}: {exc}")


def failed_cell(cg: float, gj: float, reason: str) -> CellResult:
    return CellResult(cg, gj, "failed", False, "", None, None, None, reason)


def cell_class(c: CellResult) -> str:
    """``stable`` | ``flutter`` (trimmed, unstable) | ``fold`` (no trim) | ``windmill-brake`` | ``failed``."""
    if c.verdict == "failed":
        return "failed"
    if c.verdict == "windmill-brake":
        return "windmill-brake"
    if c.stable:
        return "stable"
    return "fold" if c.boundary_kind == "fold" or c.verdict in ("no-autorotation", "overspeed") else "flutter"


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
    """The map cells of a column walk's points (GJ ascending)."""
    from .stability import cell_from_modes
    pts = sorted(points, key=lambda p: p.gj_nm2)
    if top_omega is None:
        tops = [p for p in pts if p.branch == "normal"]
        top_omega = tops[-1].trim.omega_rad_s if tops else None
    cells = []
    for i, p in enumerate(pts):
        kind = p.kind
        if kind in ("stable", "flutter"):
            c = cell_from_modes(cg, p.gj_nm2, p.trim, p.modes)
        elif kind == "windmill-brake":
            c = CellResult(cg, p.gj_nm2, "windmill-brake", False, "windmill-brake", None, None,
                           float(p.trim.omega_rad_s), p.reason, "windmill-brake", float(p.trim.descent_rate_m_s))
        elif kind == "fold":
            above = next((q for q in pts[i + 1:] if q.branch == "normal"), None)
            rising = above is not None and top_omega is not None and above.trim.omega_rad_s > top_omega
            c = CellResult(cg, p.gj_nm2, "overspeed" if rising else "no-autorotation", False, "fold", None, None,
                           None, p.reason or "no trim on the normal branch", "none")
        else:
            c = failed_cell(cg, p.gj_nm2, f"numerical failure: {p.reason}")
        cells.append(c)
    return cells


def _time_cells(task: ColumnTask, points: list, cells: list) -> list:
    """``method='time'``: the walk's normal-branch points judged by time marching from their trim."""
    from .simulation import Case, Simulation
    out = []
    for p, c in zip(sorted(points, key=lambda p: p.gj_nm2), cells):
        if p.branch != "normal":
            out.append(c)
            continue
        rotor = task.rotor.with_overrides(gj_nm2=p.gj_nm2, x_cg=task.cg)
        sim = Simulation(Case(rotor, task.flight, task.settings, t_end_s=8.0), trim_result=p.trim).run()
        v = sim.verdict()
        out.append(CellResult(task.cg, p.gj_nm2, v.verdict, v.verdict == "stable",
                              "" if not v.unstable else "flutter", v.growth_rate_per_s, v.frequency_hz,
                              p.trim.omega_rad_s, v.explanation, "normal", float(p.trim.descent_rate_m_s)))
    return out


def compute_column(task: ColumnTask, on_point=None, cancel=None) -> ColumnResult:
    """Worker entry point: walk one column; an exception becomes a ``failed`` column (never raises)."""
    from .column import summarise, walk_column
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
        if task.method == "time":
            intervals, crit = _summary_of_cells(cells, task)
        return ColumnResult(task.cg, cells, intervals, crit, w.fold_gj_nm2, w.n_trims, w.wall_time_s,
                            any(c.verdict == "failed" for c in cells), w.cancelled)
    except Exception as exc:  # noqa: BLE001 - a failed column is a result, not a crash
        return ColumnResult(task.cg, [failed_cell(task.cg, task.gj_max, f"{type(exc).__name__}: {exc}")], [], None,
                            None, failed=True)


def _summary_of_cells(cells: list, task: ColumnTask):
    """(intervals, critical GJ) from cells (used when the cells' classes are not the walk's)."""
    from .column import summarise

    class _P:  # the two attributes summarise reads
        def __init__(self, c):
            self.gj_nm2, self.kind = c.gj_nm2, cell_class(c)
    return summarise([_P(c) for c in cells], task.gj_min, task.gj_max, task.rel_tol)


# ----------------------------------------------------------------------------- results
@dataclass
class BoundaryMap:
    """A (possibly partial) map. ``cells`` sorted by CG then GJ; ``columns``: per CG column its
    ``critical_gj`` [N m^2/rad], final ``bracket`` and ``status`` (``stable-throughout``,
    ``bracketed``, ``unstable-at-gj-max``, ``unresolved`` (a failed cell at the boundary or the
    bracket not yet at tolerance), ``incomplete`` (cancelled before its coarse cells were done));
    ``boundaries``: every transition; ``cases``: cells in the map; ``cached_cases``: of them read
    from the store; ``wall_time_s``: [s]."""

    spec: MapSpec
    cells: list
    columns: list
    boundaries: list
    cases: int
    cached_cases: int
    wall_time_s: float
    cancelled: bool = False
    executor: str = ""
    phases: dict = field(default_factory=dict)

    @property
    def critical_gj(self) -> list:
        return [[c["cg"], c["critical_gj"]] for c in self.columns]

    @property
    def computed_cases(self) -> int:
        return self.cases - self.cached_cases

    @property
    def complete(self) -> bool:
        return not self.cancelled and all(c["status"] != "incomplete" for c in self.columns)

    @property
    def cells_per_s(self) -> float:
        return self.computed_cases / self.wall_time_s if self.wall_time_s > 0 else float("nan")

    def verdict_counts(self) -> dict:
        out = {v: 0 for v in VERDICTS}
        for c in self.cells:
            out[c.verdict] = out.get(c.verdict, 0) + 1
        return out

    def to_dict(self) -> dict:
        def fin(x):
            return None if x is None or (isinstance(x, float) and not math.isfinite(x)) else x
        return {
            "spec": self.spec.to_dict(),
            "solver": solver_fingerprint(),
            "critical_gj": [[cg, fin(g)] for cg, g in self.critical_gj],
            "critical_gj_definition": "upper end of the final bracket (lowest computed GJ stable up to gj_max); "
                                      "null: see columns[].status",
            "columns": [{**c, "critical_gj": fin(c["critical_gj"])} for c in self.columns],
            "boundaries": self.boundaries,
            "cells": [{k: fin(v) for k, v in c.to_dict().items()} for c in self.cells],
            "verdict_counts": self.verdict_counts(),
            "cases": self.cases,
            "cached_cases": self.cached_cases,
            "computed_cases": self.computed_cases,
            "wall_time_s": self.wall_time_s,
            "cells_per_s": fin(self.cells_per_s),
            "cancelled": self.cancelled,
            "complete": self.complete,
            "executor": self.executor,
        }

    def to_csv(self, path) -> None:
        """One row per cell: cg, gj_nm2, verdict, stable, boundary_kind, growth_rate_per_s [1/s],
        frequency_hz [Hz], omega_trim_rad_s [rad/s], reason."""
        cols = list(CellResult.__dataclass_fields__)
        with open(path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(cols)
            for c in self.cells:
                w.writerow(["" if getattr(c, k) is None else getattr(c, k) for k in cols])


def _summarise(spec: MapSpec, by_col: dict, info: dict) -> tuple[list, list]:
    """Per column: critical GJ, bracket, status, kind, fold GJ, intervals; and every transition."""
    columns, boundaries = [], []
    tol = 1.0 + spec.gj_rel_tol * (1 + 1e-9)
    for cg in spec.cg_values:
        cells = sorted(by_col.get(cg, {}).values(), key=lambda c: c.gj_nm2)
        col = info.get(cg)
        if col is None or not cells:
            columns.append({"cg": cg, "critical_gj": None, "bracket": None, "status": "incomplete", "kind": None,
                            "fold_gj": None, "intervals": []})
            continue
        for lo, hi in zip(cells[:-1], cells[1:]):
            a, b = cell_class(lo), cell_class(hi)
            if a == b:
                continue
            if "failed" in (a, b):
                kind = "unknown"
            elif "stable" in (a, b):
                kind = b if a == "stable" else a
            elif "fold" in (a, b):
                kind = "fold"
            else:
                kind = a
            boundaries.append({"cg": cg, "kind": kind, "gj_lo": lo.gj_nm2, "gj_hi": hi.gj_nm2,
                               "gj": math.sqrt(lo.gj_nm2 * hi.gj_nm2), "below": lo.verdict, "above": hi.verdict,
                               "resolved": hi.gj_nm2 / lo.gj_nm2 <= tol and kind != "unknown"})
        base = {"cg": cg, "fold_gj": col.get("fold_gj"), "intervals": col.get("intervals", [])}
        if col.get("failed") or col.get("cancelled"):
            columns.append({**base, "critical_gj": None, "bracket": None,
                            "status": "incomplete" if col.get("cancelled") else "unresolved", "kind": None})
            continue
        if cell_class(cells[-1]) != "stable":
            status = "unresolved" if cell_class(cells[-1]) == "failed" else "unstable-at-gj-max"
            columns.append({**base, "critical_gj": math.inf, "bracket": None, "status": status, "kind": None})
            continue
        i = len(cells) - 1
        while i > 0 and cell_class(cells[i - 1]) == "stable":
            i -= 1
        if i == 0:
            columns.append({**base, "critical_gj": None, "bracket": None, "status": "stable-throughout", "kind": None})
            continue
        lo, hi = cells[i - 1], cells[i]
        ok = hi.gj_nm2 / lo.gj_nm2 <= tol and cell_class(lo) != "failed"
        columns.append({**base, "critical_gj": hi.gj_nm2, "bracket": [lo.gj_nm2, hi.gj_nm2],
                        "status": "bracketed" if ok else "unresolved",
                        "kind": cell_class(lo) if cell_class(lo) != "failed" else "unknown"})
    return columns, boundaries


# ----------------------------------------------------------------------------- the run
#: cells per column assumed by the progress estimate until a column is finished
CELLS_PER_COLUMN_GUESS = 30


class MapRun:
    """Iterate to get each finished cell (:class:`CellResult`) as soon as it is known; then
    :meth:`result` gives the :class:`BoundaryMap` (partial if cancelled or stopped early).
    ``done``: cells handed out so far; ``estimated_total``: a rough total for progress bars."""

    def __init__(self, spec: MapSpec, executor: Optional[CellExecutor] = None, store=None,
                 cancel: Optional[threading.Event] = None, workers: Optional[int] = None):
        self.spec = spec
        self.store = store
        self.cancel = cancel or threading.Event()
        self._own_executor = executor is None
        self._executor = executor
        self._workers = workers
        self.by_col: dict = {cg: {} for cg in spec.cg_values}
        self.info: dict = {}
        self.cached = 0
        self.done = 0
        self.in_flight = 0
        self._t0 = None
        self.wall_time_s = 0.0
        self.cancelled = False
        self.phases: dict = {}
        self._finished = False
        self.n_trims = 0

    @property
    def estimated_total(self) -> int:
        open_cols = [cg for cg in self.spec.cg_values if cg not in self.info]
        partial = sum(len(self.by_col[cg]) for cg in open_cols)
        return self.done - partial + sum(max(CELLS_PER_COLUMN_GUESS, len(self.by_col[cg]) + 1) for cg in open_cols)

    def _cached_column(self, cg) -> Optional[ColumnResult]:
        """A finished column from the store: its record rides on the cell at ``gj_max`` (always part
        of a walk), so the store holds one row per cell; None if absent or for another range/tolerance."""
        if self.store is None:
            return None
        spec = self.spec
        top = self.store.get(spec.key(cg, _gj_round(spec.gj_max)))
        rec = None if top is None else top.get("column")
        if not isinstance(rec, dict) or rec.get("key") != spec.column_key(cg):
            return None
        keys = [spec.key(cg, g) for g in rec.get("gj", [])]
        got = self.store.get_many(keys) if hasattr(self.store, "get_many") else {k: self.store.get(k) for k in keys}
        if not keys or any(got.get(k) is None for k in keys):
            return None
        cells = [replace(CellResult.from_dict(got[k]), cg=cg, gj_nm2=g) for k, g in zip(keys, rec["gj"])]
        crit = rec.get("critical_gj")
        crit = math.inf if crit == "inf" else crit
        return ColumnResult(cg, cells, rec.get("intervals", []), crit, rec.get("fold_gj"))

    def _store_column(self, col: ColumnResult) -> None:
        if self.store is None or col.failed or col.cancelled:
            return
        spec = self.spec
        top_gj = _gj_round(spec.gj_max)
        crit = "inf" if col.critical_gj is not None and math.isinf(col.critical_gj) else col.critical_gj
        record = {"key": spec.column_key(col.cg), "gj": [c.gj_nm2 for c in col.cells], "intervals": col.intervals,
                  "critical_gj": crit, "fold_gj": col.fold_gj}
        top = None
        for c in col.cells:  # the top cell last: its column record says the column is complete
            if c.gj_nm2 == top_gj:
                top = c
                continue
            self._put(spec.key(col.cg, c.gj_nm2), spec.case_params(col.cg, c.gj_nm2), c)
            if self.store is None:
                return
        if top is not None:
            self._put(spec.key(col.cg, top_gj), spec.case_params(col.cg, top_gj), {**top.to_dict(), "column": record})

    def _finish_column(self, col: ColumnResult, cached: bool, streamed: bool):
        """Record a finished column; yields the cells not handed out yet."""
        self.info[col.cg] = {"intervals": col.intervals, "critical_gj": col.critical_gj, "fold_gj": col.fold_gj,
                             "failed": col.failed, "cancelled": col.cancelled}
        self.n_trims += col.n_trims
        if streamed:  # cells already handed out point by point: take the final (time-judged) versions
            self.by_col[col.cg] = {c.gj_nm2: c for c in col.cells}
            return []
        out = []
        for c in col.cells:
            self.by_col[col.cg][c.gj_nm2] = c
            self.done += 1
            self.cached += bool(cached)
            out.append(c)
        return out

    def _crashed_column(self, cg: float, reason: str) -> ColumnResult:
        """A column whose worker died: failed cells on the probe grid, shown in this run only."""
        cells = [failed_cell(cg, _gj_round(g), f"worker: {reason}") for g in self.spec.coarse_gj]
        return ColumnResult(cg, cells, [], None, None, failed=True)

    def __iter__(self) -> Iterator[CellResult]:
        if self._finished:
            return
        spec = self.spec
        self._t0 = time.perf_counter()
        if self._executor is None:
            w = self._workers
            self._executor = SerialExecutor() if w == 1 else LocalPoolExecutor(w)
        ex = self._executor
        self._ex_name = ex.describe()
        try:
            todo = []
            for cg in spec.cg_values:
                hit = self._cached_column(cg)
                if hit is not None:
                    for c in self._finish_column(hit, True, False):
                        yield c
                        if self.cancel.is_set():
                            self.cancelled = True
                            return
                else:
                    todo.append(cg)
            if isinstance(ex, SerialExecutor):
                yield from self._run_inline(todo)
                return
            for cg in todo:
                ex.submit(compute_column, spec.column_task(cg), cg)
                self.in_flight += 1
            while self.in_flight:
                if self.cancel.is_set():
                    self.cancelled = True
                    return
                for out in ex.wait(timeout=0.1):
                    self.in_flight -= 1
                    col = out.value if out.ok else self._crashed_column(out.tag, out.reason)
                    if out.ok:
                        self._store_column(col)
                    for c in self._finish_column(col, False, False):
                        yield c
                        if self.cancel.is_set():
                            self.cancelled = True
                            return
        finally:
            if self.cancelled or self.in_flight:
                ex.cancel_pending()
                self.in_flight = 0
            if self._own_executor:
                ex.close()
            self.wall_time_s = time.perf_counter() - self._t0
            self._finished = True

    def _run_inline(self, todo: list) -> Iterator[CellResult]:
        """Serial execution in this process: the column walks in a helper thread and every point is
        handed out as it is found (the dashboard's progressive map)."""
        import queue
        spec = self.spec
        for cg in todo:
            q: queue.Queue = queue.Queue()
            task = spec.column_task(cg)
            col_cancel = threading.Event()

            def on_point(p, q=q):
                q.put(("point", p))

            def work(task=task, q=q, col_cancel=col_cancel):
                try:
                    q.put(("done", compute_column(task, on_point=on_point, cancel=col_cancel)))
                except BaseException as exc:  # noqa: BLE001 - reported as a crashed column
                    q.put(("crash", f"{type(exc).__name__}: {exc}"))

            th = threading.Thread(target=work, name=f"amra-column-{cg}", daemon=True)
            th.start()
            top_omega = None
            try:
                while True:
                    if self.cancel.is_set():
                        self.cancelled = True
                        return
                    try:
                        kind, item = q.get(timeout=0.1)
                    except queue.Empty:
                        continue
                    if kind == "point":
                        if item.branch == "normal" and top_omega is None:
                            top_omega = item.trim.omega_rad_s
                        cell = cells_of_walk(cg, [item], top_omega)[0]
                        if spec.method == "time":
                            continue  # judged by time marching at the end of the column
                        self.by_col[cg][cell.gj_nm2] = cell
                        self.done += 1
                        yield cell
                        if self.cancel.is_set():
                            self.cancelled = True
                            return
                        continue
                    col = item if kind == "done" else self._crashed_column(cg, item)
                    if kind == "done":
                        self._store_column(col)
                    streamed = spec.method != "time" and kind == "done"
                    for c in self._finish_column(col, False, streamed):
                        yield c
                    break
            finally:
                col_cancel.set()  # a walk still running (cancelled, or the consumer stopped) ends at its next point
                th.join(timeout=30.0)

    def _put(self, key, params, cell) -> None:
        """Store a finished cell; a store that fails while writing (disk full, locked for longer
        than its busy timeout) is reported once and the map carries on without it."""
        try:
            self.store.put(key, params, cell)
        except Exception as exc:  # noqa: BLE001 - the map is worth more than its cache
            import warnings
            self.store_error = f"result store write failed ({type(exc).__name__}: {exc}); continuing without it"
            warnings.warn(self.store_error, RuntimeWarning, stacklevel=2)
            self.store = None

    def result(self) -> BoundaryMap:
        if not self._finished:
            for _ in self:
                pass
        columns, boundaries = _summarise(self.spec, self.by_col, self.info)
        cells = [c for cg in self.spec.cg_values for c in sorted(self.by_col[cg].values(), key=lambda c: c.gj_nm2)]
        return BoundaryMap(self.spec, cells, columns, boundaries, len(cells), self.cached, self.wall_time_s,
                           self.cancelled, getattr(self, "_ex_name", ""), dict(self.phases))


def iter_map(spec: MapSpec, executor: Optional[CellExecutor] = None, store=None,
             cancel: Optional[threading.Event] = None, workers: Optional[int] = None) -> MapRun:
    """The map as an iterator of finished cells; ``.result()`` afterwards gives the map."""
    return MapRun(spec, executor, store, cancel, workers)


def run_map(spec: MapSpec, executor: Optional[CellExecutor] = None, store=None,
            on_cell: Optional[Callable[[CellResult], None]] = None,
            cancel: Optional[threading.Event] = None, workers: Optional[int] = None) -> BoundaryMap:
    """Compute the map (see the module docstring). ``executor``: where columns run (default: a local
    pool of ``workers`` processes, closed at the end; ``workers=1``: in this process, cells handed
    out point by point); ``store``: a :class:`~amra_core.store.CellStore` (or a path to one);
    ``on_cell(cell)``: called with every finished cell; ``cancel``: a ``threading.Event`` -- when
    set, the partial map is returned."""
    own_store = False
    if store is not None and not hasattr(store, "get"):
        from .store import CellStore
        store = CellStore(store, solver=solver_fingerprint())
        own_store = True
    try:
        run = MapRun(spec, executor, store, cancel, workers)
        for cell in run:
            if on_cell is not None:
                on_cell(cell)
        return run.result()
    finally:
        if own_store:
            store.close()
