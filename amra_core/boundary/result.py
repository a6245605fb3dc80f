"""A finished (or partial) boundary map: cells, per-column summaries, transitions, JSON and CSV."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from ..stability import CellResult
from .spec import VERDICTS, MapSpec, solver_fingerprint
from .intervals import classify
from .tasks import cell_class


@dataclass
class BoundaryMap:
    """A (possibly partial) map. ``cells`` sorted by CG then GJ; ``columns``: per CG column its
    ``fold_gj`` (no normal autorotation below), ``flutter_gj`` (top of the highest *strong*
    flutter interval), ``critical_gj`` (the larger; weak windows never move it) [N m^2/rad], see
    :mod:`amra_core.boundary.intervals`; ``intervals`` (each flutter interval with ``strength``,
    ``peak_growth_rate_1_s``, ``damping_ratio``, ``frequency_hz``, ``mode``, ``participation``,
    ``fold_approach``), final ``bracket`` and ``status`` (``stable-throughout``,
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
            "fold_gj": [[c["cg"], fin(c.get("fold_gj"))] for c in self.columns],
            "flutter_gj": [[c["cg"], fin(c.get("flutter_gj"))] for c in self.columns],
            "critical_gj_definition": "the larger of fold_gj (no normal autorotation below; the lowest computed GJ "
                                      "above it) and flutter_gj (the lowest computed GJ above the highest strong "
                                      "flutter interval); weak flutter windows (damping ratio above -weak_damping and a 20 s run "
                                      "within weak_amplitude_deg of twist and teeter) "
                                      "never move it; null: see columns[].status",
            "weak_damping": self.spec.weak_damping,
            "weak_amplitude_deg": self.spec.weak_amplitude_deg,
            "columns": [{**c, "critical_gj": fin(c["critical_gj"]), "fold_gj": fin(c.get("fold_gj")),
                         "flutter_gj": fin(c.get("flutter_gj")), "branch_end_gj": fin(c.get("branch_end_gj"))}
                        for c in self.columns],
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
        """One row per cell: cg [chord fraction], gj_nm2, verdict, stable, boundary_kind,
        growth_rate_per_s [1/s], frequency_hz [Hz], omega_trim_rad_s [rad/s], reason; above them
        ``#`` lines with the map's case (rotor, fidelity, mu, EA, GJ grid) and whether it is complete,
        as the dashboard's map export has (:func:`amra_core.export.table_csv`)."""
        from ..export import table_csv
        sp = self.spec
        meta = {"complete": "yes" if self.complete else "NO: cancelled or unfinished", **sp.grid_meta(),
                "ea_chord_fraction": sp.ea, "cg_columns_chord_fraction": " ".join(f"{c:g}" for c in sp.cg_values)}
        cols = list(CellResult.__dataclass_fields__)
        rows = [["" if getattr(c, k) is None else getattr(c, k) for k in cols] for c in self.cells]
        with open(path, "w", newline="") as f:
            f.write(table_csv(cols, rows, meta))


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
        c = classify(col.get("intervals", []), spec.gj_max, spec.weak_damping, spec.weak_amplitude_deg)
        base = {"cg": cg, "fold_gj": c["fold_gj"], "flutter_gj": c["flutter_gj"], "branch_end_gj": c["branch_end_gj"],
                "weak_damping": spec.weak_damping, "weak_amplitude_deg": spec.weak_amplitude_deg,
                "intervals": c["intervals"]}
        if col.get("failed") or col.get("cancelled"):
            columns.append({**base, "critical_gj": None, "bracket": None,
                            "status": "incomplete" if col.get("cancelled") else "unresolved", "kind": None})
            continue
        top = c["intervals"][-1] if c["intervals"] else None
        if cell_class(cells[-1]) == "failed":
            columns.append({**base, "critical_gj": math.inf, "bracket": None, "status": "unresolved", "kind": None})
            continue
        top_weak = top is not None and top["kind"] == "flutter" and top.get("strength") == "weak" \
            and not top.get("fold_approach")
        if cell_class(cells[-1]) != "stable" and not top_weak:
            columns.append({**base, "critical_gj": math.inf, "bracket": None, "status": "unstable-at-gj-max",
                            "kind": top["kind"] if top is not None else None})
            continue
        crit = c["critical_gj"]
        if crit is None:
            columns.append({**base, "critical_gj": None, "bracket": None, "status": "stable-throughout", "kind": None})
            continue
        below = [x.gj_nm2 for x in cells if x.gj_nm2 < crit]
        lo = max(below) if below else None
        ok = lo is not None and crit / lo <= tol and cell_class(next(x for x in cells if x.gj_nm2 == lo)) != "failed"
        columns.append({**base, "critical_gj": crit, "bracket": [lo, crit] if lo is not None else None,
                        "status": "bracketed" if ok else "unresolved", "kind": c["kind"]})
    return columns, boundaries
