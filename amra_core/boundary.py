"""Stability boundary map over CG x GJ (issue 4, paper Fig. 14), computed progressively.

For a fixed rotor, fidelity, aerodynamic model, advance ratio and elastic axis, every cell
(CG [chord fraction], GJ [N m^2/rad]) is classified by :func:`amra_core.stability.assess_cell`
(trim by continuation in GJ, then eigenvalues/Floquet exponents, or a time-marching run with
``method='time'``). The verdicts: ``stable``, ``flutter``, ``divergence``, ``overspeed``,
``no-autorotation`` and ``failed`` (an exception or numerical failure; recorded with its reason,
the sweep carries on).

Progression: first a coarse grid (``n_coarse`` GJ values, log-spaced from ``gj_min`` to ``gj_max``,
in every CG column); then, per column, every pair of neighbouring cells in different classes
(``stable`` | ``flutter`` = trimmed but unstable | ``fold`` = no trim | ``failed``) is bisected in
log GJ until ``gj_hi / gj_lo <= 1 + gj_rel_tol``. Each bracket keeps one cell in flight, so the
columns (and several transitions of one column) proceed in parallel. A transition the coarse grid
does not see (a stable window narrower than the coarse spacing) is not found: refine ``n_coarse``.
Pairs with a failed cell are bisected too, which locates the edge of the failed region; such
transitions have kind ``unknown`` and are never ``resolved``.

Every finished cell is handed out as soon as it is known (``on_cell``, or iterate
:func:`iter_map`); a ``threading.Event`` ``cancel`` is checked between cells (and at least every
0.1 s) and a cancelled map returns what it has. With a :class:`~amra_core.store.CellStore`, cells
already computed (same case key: every parameter plus the solver fingerprint) are taken from it
and new ones are written to it, so a repeated map is read back at once and an interrupted one
resumes.

Outputs (:class:`BoundaryMap`): ``cells``; ``critical_gj``: per column ``[cg, gj]`` with ``gj`` the
*upper end* of the final bracket (the lowest computed GJ from which the column is stable all the way
up to ``gj_max``), ``None`` when the column is stable over the whole range, ``math.inf`` when it is
unstable at ``gj_max`` (``null`` in JSON; ``columns[i]['status']`` tells which); ``boundaries``:
every transition of every column with its kind -- ``flutter`` (an eigenvalue crosses on the trim
branch), ``fold`` (the trim branch ends: no autorotation) or ``unknown`` (next to a failed cell).
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
from .shapes import FIDELITIES
from .stability import CellResult

VERDICTS = ("stable", "flutter", "divergence", "overspeed", "no-autorotation", "failed")
METHODS = ("eigen", "time")
DEFAULT_CG = tuple(round(float(x), 6) for x in np.linspace(0.20, 0.50, 16))

#: solver sources whose content enters the case key (with ``__version__``), so stored cells are
#: never served for a changed solver
_SOLVER_SOURCES = ("airfoil", "flight", "kernels", "model", "rotor", "shapes", "simulation", "stability",
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
    ``n_coarse``: GJ values of the coarse grid; ``method``: ``eigen`` (linearised about trim) or
    ``time`` (time marching from trim plus a perturbation); ``n_elements``: FEM elements per blade;
    ``bisect_fold``: also bracket the fold inside the unstable region (fold <-> flutter pairs).
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

    def __post_init__(self):
        if not isinstance(self.rotor, (str, Rotor)):
            raise MapSpecError(f"rotor = {self.rotor!r} is not allowed: give a preset name or a Rotor")
        if self.fidelity not in FIDELITIES:
            raise MapSpecError(f"fidelity = {self.fidelity!r} is not allowed: choose one of {', '.join(FIDELITIES)}")
        if self.aero not in AERO_MODELS:
            raise MapSpecError(f"aero = {self.aero!r} is not allowed: choose one of {', '.join(AERO_MODELS)}")
        if self.method not in METHODS:
            raise MapSpecError(f"method = {self.method!r} is not allowed: choose one of {', '.join(METHODS)}")
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
        return SolverSettings(fidelity=self.fidelity, aero=self.aero, n_elements=self.n_elements)

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
    """``stable`` | ``flutter`` (trimmed, unstable) | ``fold`` (no trim) | ``failed``."""
    if c.verdict == "failed":
        return "failed"
    if c.stable:
        return "stable"
    return "fold" if c.boundary_kind == "fold" or c.verdict == "no-autorotation" else "flutter"


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


def _summarise(spec: MapSpec, by_col: dict, coarse_done: dict) -> tuple[list, list]:
    columns, boundaries = [], []
    tol = 1.0 + spec.gj_rel_tol * (1 + 1e-9)
    for cg in spec.cg_values:
        cells = sorted(by_col.get(cg, {}).values(), key=lambda c: c.gj_nm2)
        if not coarse_done.get(cg) or not cells:
            columns.append({"cg": cg, "critical_gj": None, "bracket": None, "status": "incomplete"})
            continue
        for lo, hi in zip(cells[:-1], cells[1:]):
            a, b = cell_class(lo), cell_class(hi)
            if a == b:
                continue
            if "failed" in (a, b):
                kind = "unknown"
            elif "stable" in (a, b):
                kind = b if a == "stable" else a
            else:
                kind = "fold"
            boundaries.append({"cg": cg, "kind": kind, "gj_lo": lo.gj_nm2, "gj_hi": hi.gj_nm2,
                               "gj": math.sqrt(lo.gj_nm2 * hi.gj_nm2), "below": lo.verdict, "above": hi.verdict,
                               "resolved": hi.gj_nm2 / lo.gj_nm2 <= tol and kind != "unknown"})
        if cell_class(cells[-1]) != "stable":
            status = "unresolved" if cell_class(cells[-1]) == "failed" else "unstable-at-gj-max"
            columns.append({"cg": cg, "critical_gj": math.inf, "bracket": None, "status": status,
                            "kind": None})
            continue
        i = len(cells) - 1
        while i > 0 and cell_class(cells[i - 1]) == "stable":
            i -= 1
        if i == 0:
            columns.append({"cg": cg, "critical_gj": None, "bracket": None, "status": "stable-throughout",
                            "kind": None})
            continue
        lo, hi = cells[i - 1], cells[i]
        ok = hi.gj_nm2 / lo.gj_nm2 <= tol and cell_class(lo) != "failed"
        columns.append({"cg": cg, "critical_gj": hi.gj_nm2, "bracket": [lo.gj_nm2, hi.gj_nm2],
                        "status": "bracketed" if ok else "unresolved",
                        "kind": cell_class(lo) if cell_class(lo) != "failed" else "unknown"})
    return columns, boundaries


# ----------------------------------------------------------------------------- the run
class MapRun:
    """Iterate to get each finished cell (:class:`CellResult`) as soon as it is known; then
    :meth:`result` gives the :class:`BoundaryMap` (partial if cancelled or stopped early)."""

    def __init__(self, spec: MapSpec, executor: Optional[CellExecutor] = None, store=None,
                 cancel: Optional[threading.Event] = None, workers: Optional[int] = None):
        self.spec = spec
        self.store = store
        self.cancel = cancel or threading.Event()
        self._own_executor = executor is None
        self._executor = executor
        self._workers = workers
        self.by_col: dict = {cg: {} for cg in spec.cg_values}
        self.coarse_done = {cg: False for cg in spec.cg_values}
        self.cached = 0
        self.done = 0
        self.in_flight = 0
        self._t0 = None
        self.wall_time_s = 0.0
        self.cancelled = False
        self.phases: dict = {}
        self._finished = False

    @property
    def estimated_total(self) -> int:
        """A rough total for progress bars: coarse cells plus an estimate of the bisection cells."""
        s = self.spec
        per = math.ceil(math.log2(max(math.log(s.gj_max / s.gj_min) / (s.n_coarse - 1) / math.log1p(s.gj_rel_tol),
                                      1.0)))
        return len(s.cg_values) * (s.n_coarse + per) + self.done - min(self.done, len(s.cg_values) * s.n_coarse)

    def _lookup(self, cg, gj):
        """(key, cached CellResult or None)."""
        key = self.spec.key(cg, gj)
        if self.store is None:
            return key, None
        d = self.store.get(key)
        return key, (None if d is None else CellResult.from_dict(d))

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
        pending_coarse = {cg: len(spec.coarse_gj) for cg in spec.cg_values}
        brackets: dict = {}  # tag -> (cg, lo_cell, hi_cell)
        ready: list = []  # cells known without computing (store), yielded in order

        def submit(cg, gj, role):
            key, hit = self._lookup(cg, gj)
            if hit is not None:
                hit = replace(hit, cg=cg, gj_nm2=gj)
                ready.append((role, hit, True, key))
                return
            ex.submit(compute_cell, spec.task(cg, gj), (role, cg, gj, key))
            self.in_flight += 1

        def start_brackets(cg):
            cells = sorted(self.by_col[cg].values(), key=lambda c: c.gj_nm2)
            for lo, hi in zip(cells[:-1], cells[1:]):
                self._maybe_bisect(cg, lo, hi, submit)

        t_phase = time.perf_counter()
        try:
            for cg in spec.cg_values:
                for gj in spec.coarse_gj:
                    submit(cg, gj, ("coarse", cg))
            while True:
                if self.cancel.is_set():
                    self.cancelled = True
                    break
                if ready:
                    batch, ready[:] = list(ready), []
                    outcomes = [(role, cell, cached, key) for role, cell, cached, key in batch]
                elif self.in_flight:
                    outcomes = []
                    for out in ex.wait(timeout=0.1):
                        self.in_flight -= 1
                        role, cg, gj, key = out.tag
                        cell = out.value if out.ok else failed_cell(cg, gj, f"worker: {out.reason}")
                        outcomes.append((role, cell, False, key if out.ok else None))  # no answer: never stored
                else:
                    break
                for role, cell, cached, key in outcomes:
                    cg = cell.cg
                    self.by_col[cg][cell.gj_nm2] = cell
                    self.done += 1
                    if cached:
                        self.cached += 1
                    elif self.store is not None and key is not None:
                        self._put(key, spec.case_params(cg, cell.gj_nm2), cell)
                    if role[0] == "coarse":
                        pending_coarse[cg] -= 1
                        if pending_coarse[cg] == 0:
                            self.coarse_done[cg] = True
                            if all(self.coarse_done.values()) and "coarse_s" not in self.phases:
                                self.phases["coarse_s"] = time.perf_counter() - t_phase
                            start_brackets(cg)
                    else:
                        _, _, lo, hi = role
                        for a, b in ((lo, cell), (cell, hi)):
                            self._maybe_bisect(cg, a, b, submit)
                    yield cell
                    if self.cancel.is_set():
                        self.cancelled = True
                        break
                if self.cancelled:
                    break
        finally:
            if self.cancelled or self.in_flight:
                ex.cancel_pending()
                self.in_flight = 0
            if self._own_executor:
                ex.close()
            self.wall_time_s = time.perf_counter() - self._t0
            self._finished = True

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

    def _maybe_bisect(self, cg, lo: CellResult, hi: CellResult, submit) -> None:
        a, b = cell_class(lo), cell_class(hi)
        if a == b:
            return
        if not self.spec.bisect_fold and "stable" not in (a, b) and "failed" not in (a, b):
            return
        if hi.gj_nm2 / lo.gj_nm2 <= 1.0 + self.spec.gj_rel_tol:
            return
        mid = _gj_round(math.sqrt(lo.gj_nm2 * hi.gj_nm2))
        if mid in self.by_col[cg] or not lo.gj_nm2 < mid < hi.gj_nm2:
            return
        submit(cg, mid, ("bisect", cg, lo, hi))

    def result(self) -> BoundaryMap:
        if not self._finished:
            for _ in self:
                pass
        columns, boundaries = _summarise(self.spec, self.by_col, self.coarse_done)
        cells = [c for cg in self.spec.cg_values for c in sorted(self.by_col[cg].values(), key=lambda c: c.gj_nm2)]
        if self.cancelled:
            for col in columns:  # a cancelled map's brackets may be wider than the tolerance
                if col["status"] == "bracketed" and col["bracket"][1] / col["bracket"][0] > 1 + self.spec.gj_rel_tol:
                    col["status"] = "unresolved"
        return BoundaryMap(self.spec, cells, columns, boundaries, len(cells), self.cached, self.wall_time_s,
                           self.cancelled, getattr(self, "_ex_name", ""), dict(self.phases))


def iter_map(spec: MapSpec, executor: Optional[CellExecutor] = None, store=None,
             cancel: Optional[threading.Event] = None, workers: Optional[int] = None) -> MapRun:
    """The map as an iterator of finished cells; ``.result()`` afterwards gives the map."""
    return MapRun(spec, executor, store, cancel, workers)


def run_map(spec: MapSpec, executor: Optional[CellExecutor] = None, store=None,
            on_cell: Optional[Callable[[CellResult], None]] = None,
            cancel: Optional[threading.Event] = None, workers: Optional[int] = None) -> BoundaryMap:
    """Compute the map (see the module docstring). ``executor``: where cells run (default: a local
    pool of ``workers`` processes, closed at the end; ``workers=1``: in this process); ``store``:
    a :class:`~amra_core.store.CellStore` (or a path to one); ``on_cell(cell)``: called with every
    finished cell; ``cancel``: a ``threading.Event`` -- when set, the partial map is returned."""
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
