#!/usr/bin/env python
"""Benchmark of the boundary map engine (issue 8 §5 targets, 16 columns at 2 %, on a 2-core machine).

Measures, and prints as JSON (each map on a local pool of ``--workers`` processes, fresh):
* ``rigid_axial``: the 16-column rigid axial map (paper-boundary, EA 0.32, GJ 30-3000, 2 %): wall
  time [s], cells, cells/s (target <= 5 s); then the same map from a store (target <= 1 s);
* ``rigid_mu0.1``: the rigid map at mu = 0.1 (target <= 30 s);
* ``fem-coupled_mu0.1`` (unless ``--no-fem``): the fem-coupled map at mu = 0.1 (target <= 120 s);
* ``fem-coupled_axial`` (only with ``--only``): the fem-coupled axial map (no target);
* ``revolutions``: revolutions marched per cell, split into trim and monodromy, from one forward
  column walked in this process (rigid, and fem-coupled unless ``--no-fem``; CG ``--rev-cg``).
Also the machine's load average before and after, since the machine is shared.

``--pool fresh`` (default) gives every map its own pool of new processes, as ``amra map`` does (on
Linux forked from this process, so they start with its imports and kernels; a spawned worker, as a
threaded parent's, imports the solver and loads its compiled kernels first: 0.6-0.9 s here); ``--pool warm``
runs every map on one pool whose workers have already computed a column, as a long-lived server's
pool would.

The Numba kernels are compiled (or loaded from the cache) in this process first, so the workers load
them from the on-disk cache; that warm-up is reported separately.

    python scripts/bench_map.py [--workers 2] [--no-fem] [--only rigid_axial,rigid_mu0.1] [--rev-cg 0.40]
                                [--pool fresh|warm]
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from amra_core.boundary import MapSpec, compute_column, solver_fingerprint  # noqa: E402
from amra_core.boundary import run_map as _run_map  # noqa: E402
from amra_core.store import CellStore  # noqa: E402


def _map_figures(bmap) -> dict:
    def fin(g):
        return None if g is None else ("inf" if not math.isfinite(g) else round(g, 1))
    return {"wall_time_s": round(bmap.wall_time_s, 3), "cells": bmap.cases, "cached_cases": bmap.cached_cases,
            "cells_per_s": round(bmap.cells_per_s, 2) if bmap.computed_cases else None,
            "verdicts": {k: v for k, v in bmap.verdict_counts().items() if v},
            "critical_gj": [[round(cg, 4), fin(g)] for cg, g in bmap.critical_gj],
            "statuses": sorted({c["status"] for c in bmap.columns}), "executor": bmap.executor,
            "intervals": {f"{c['cg']:.3f}": "; ".join(f"{iv['kind']} {iv['gj_lo_nm2']:.0f}-{iv['gj_hi_nm2']:.0f}"
                                                       for iv in c["intervals"]) for c in bmap.columns}}


def _revolutions(fidelity: str, cg: float) -> dict:
    """Walk one mu = 0.1 column in this process, counting the revolutions every kernel march covers."""
    from amra_core import kernel_guard
    from amra_core.column import walk_column
    from amra_core.model import Y_OMEGA
    counts = {"trim": 0.0, "stability": 0.0}
    real = kernel_guard.advance

    def counting(y, t0, dt, n_steps, *rest):
        caller = sys._getframe(1).f_globals.get("__name__", "")
        stability = caller.endswith((".stability", ".floquet"))  # the monodromy marches are in floquet
        counts["stability" if stability else "trim"] += n_steps * dt * float(y[Y_OMEGA]) / (2 * math.pi)
        return real(y, t0, dt, n_steps, *rest)

    kernel_guard.advance = counting
    try:
        spec = MapSpec(fidelity=fidelity, mu=0.1)
        t = time.perf_counter()
        w = walk_column(spec.base_rotor, spec.flight, spec.settings, cg, spec.gj_min, spec.gj_max,
                        rel_tol=spec.gj_rel_tol, max_step=spec.max_step, n_probe=spec.n_coarse)
        wall = time.perf_counter() - t
    finally:
        kernel_guard.advance = real
    n = max(len(w.points), 1)
    return {"cg": cg, "points": len(w.points), "trims": w.n_trims, "wall_time_s": round(wall, 2),
            "revolutions_per_cell_trim": round(counts["trim"] / n, 1),
            "revolutions_per_cell_monodromy": round(counts["stability"] / n, 1),
            "revolutions_per_cell": round((counts["trim"] + counts["stability"]) / n, 1),
            "note": "the trim revolutions include the cold trim at the top of the column"}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--no-fem", action="store_true", help="skip the fem-coupled map")
    ap.add_argument("--only", default="", help="comma-separated subset of rigid_axial, rigid_mu0.1, "
                                               "fem-coupled_mu0.1, revolutions")
    ap.add_argument("--rev-cg", type=float, default=0.40, help="CG of the column whose revolutions are counted")
    ap.add_argument("--pool", choices=("fresh", "warm"), default="fresh",
                    help="a new pool per map (as amra map) or one warmed pool for all (as a server)")
    args = ap.parse_args(argv)
    only = set(filter(None, args.only.split(",")))

    def want(k):
        return (not only or k in only) and not (args.no_fem and k.startswith("fem"))

    out = {"solver": solver_fingerprint(), "cpu_count": os.cpu_count(), "workers": args.workers,
           "load_average_before": [round(x, 2) for x in os.getloadavg()]}
    t0 = time.perf_counter()
    for fid, mu in (("rigid", 0.0), ("rigid", 0.1)) + ((("fem-coupled", 0.1),) if want("fem-coupled_mu0.1") else ()):
        spec = MapSpec(fidelity=fid, mu=mu, cg_values=(0.40,), gj_min=2500.0)
        compute_column(spec.column_task(0.40))
    out["warm_up_s"] = round(time.perf_counter() - t0, 3)
    out["pool"] = args.pool
    pool = None
    if args.pool == "warm":
        from amra_core.executor import LocalPoolExecutor
        pool = LocalPoolExecutor(args.workers)
        t0 = time.perf_counter()
        warm = MapSpec(cg_values=(0.40,), gj_min=2500.0)
        for _ in range(2 * args.workers):  # every worker imports the solver and loads its kernels
            pool.submit(compute_column, warm.column_task(0.40))
        while pool.n_pending:
            pool.wait()
        out["pool_warm_up_s"] = round(time.perf_counter() - t0, 3)

    def run_map(spec, **kw):
        return _run_map(spec, executor=pool, **kw)

    if want("rigid_axial"):
        with tempfile.TemporaryDirectory() as tmp:
            with CellStore(Path(tmp) / "cells.sqlite", solver=solver_fingerprint()) as st:
                first = run_map(MapSpec(), workers=args.workers, store=st)
                out["rigid_axial"] = _map_figures(first)
                t = time.perf_counter()
                again = run_map(MapSpec(), workers=args.workers, store=st)
                out["rigid_axial_from_store"] = {"wall_time_s": round(time.perf_counter() - t, 3),
                                                 "cells": again.cases, "cached_cases": again.cached_cases,
                                                 "same_critical_gj": again.critical_gj == first.critical_gj}
    for fid in ("rigid", "fem-coupled"):
        key = f"{fid}_mu0.1"
        if want(key):
            out[key] = _map_figures(run_map(MapSpec(fidelity=fid, mu=0.1), workers=args.workers))
    if only and "fem-coupled_axial" in only:  # not a target: only on request
        out["fem-coupled_axial"] = _map_figures(run_map(MapSpec(fidelity="fem-coupled"), workers=args.workers))
    if want("revolutions"):
        out["revolutions"] = {fid: _revolutions(fid, args.rev_cg)
                              for fid in ("rigid",) + (() if args.no_fem else ("fem-coupled",))}
    if pool is not None:
        pool.close()
    out["load_average_after"] = [round(x, 2) for x in os.getloadavg()]
    print(json.dumps(out, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
