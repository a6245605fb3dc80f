#!/usr/bin/env python
"""Benchmark of the boundary map engine (issue 4 targets on a 2-core machine).

Measures, and prints as JSON:
* the 16-column rigid axial map (paper-boundary, EA 0.32, GJ 30-3000, 2 %) on a local pool of
  ``--workers`` processes with a fresh store: wall time [s], cells, cells/s (target <= 60 s);
* the same map repeated from the store: wall time [s] (target <= 1 s);
* eigen vs time marching on the same cells (the rigid coarse grid of a few CG columns, in this
  process): cells/s of each and the speed-up of the eigen path, plus the boundaries of both on
  those columns;
* unless ``--no-fem``: the 16-column fem-coupled map (target <= 10 min).

The Numba kernels are compiled (or loaded from the cache) in this process first, so the workers load
them from the on-disk cache; that warm-up is reported separately.

    python scripts/bench_map.py [--workers 2] [--no-fem] [--time-columns 0.36,0.42]
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from amra_core.boundary import MapSpec, compute_cell, run_map, solver_fingerprint  # noqa: E402
from amra_core.store import CellStore  # noqa: E402


def _map_figures(bmap) -> dict:
    return {"wall_time_s": round(bmap.wall_time_s, 3), "cells": bmap.cases, "cached_cases": bmap.cached_cases,
            "cells_per_s": round(bmap.cells_per_s, 2) if bmap.computed_cases else None,
            "coarse_phase_s": round(bmap.phases.get("coarse_s", float("nan")), 3),
            "verdicts": {k: v for k, v in bmap.verdict_counts().items() if v},
            "critical_gj": [[round(cg, 4), None if g is None else (round(g, 1) if g != float("inf") else "inf")]
                            for cg, g in bmap.critical_gj],
            "statuses": sorted({c["status"] for c in bmap.columns}), "executor": bmap.executor}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--no-fem", action="store_true", help="skip the fem-coupled map")
    ap.add_argument("--time-columns", default="0.36,0.42", help="CG columns for eigen vs time marching")
    args = ap.parse_args(argv)
    out = {"solver": solver_fingerprint(), "cpu_count": os.cpu_count(), "workers": args.workers}

    t0 = time.perf_counter()
    for fid in ("rigid",) + (() if args.no_fem else ("fem-coupled",)):
        spec = MapSpec(fidelity=fid)
        compute_cell(spec.task(0.40, 1500.0))
    compute_cell(MapSpec(method="time").task(0.40, 1500.0))
    out["warm_up_s"] = round(time.perf_counter() - t0, 3)

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "cells.sqlite"
        with CellStore(path, solver=solver_fingerprint()) as st:
            first = run_map(MapSpec(), workers=args.workers, store=st)
            out["rigid_axial_16col"] = _map_figures(first)
            t = time.perf_counter()
            again = run_map(MapSpec(), workers=args.workers, store=st)
            out["rigid_axial_16col_from_store"] = {"wall_time_s": round(time.perf_counter() - t, 3),
                                                   "cells": again.cases, "cached_cases": again.cached_cases,
                                                   "same_critical_gj": again.critical_gj == first.critical_gj}

    cgs = tuple(float(x) for x in args.time_columns.split(","))
    cmp = {}
    for method in ("eigen", "time"):
        spec = MapSpec(cg_values=cgs, method=method)
        t = time.perf_counter()
        for cg in cgs:
            for gj in spec.coarse_gj:
                compute_cell(spec.task(cg, gj))
        n = len(cgs) * len(spec.coarse_gj)
        cells_per_s = n / (time.perf_counter() - t)
        bm = run_map(spec, workers=args.workers)
        cmp[method] = {"serial_cells_per_s": round(cells_per_s, 2), "map_wall_time_s": round(bm.wall_time_s, 3),
                       "map_cells": bm.cases, "critical_gj": [[cg, g] for cg, g in bm.critical_gj],
                       "kinds": [c.get("kind") for c in bm.columns]}
    cmp["eigen_speedup_per_cell"] = round(cmp["eigen"]["serial_cells_per_s"] / cmp["time"]["serial_cells_per_s"], 1)
    cmp["critical_gj_time_over_eigen"] = [
        round(gt / ge, 4) if ge and gt and ge != float("inf") and gt != float("inf") else None
        for (_, ge), (_, gt) in zip(cmp["eigen"]["critical_gj"], cmp["time"]["critical_gj"])]
    out["eigen_vs_time"] = cmp

    if not args.no_fem:
        fem = run_map(MapSpec(fidelity="fem-coupled"), workers=args.workers)
        out["fem_coupled_axial_16col"] = _map_figures(fem)
    print(json.dumps(out, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
