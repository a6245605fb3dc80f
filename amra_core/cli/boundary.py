"""``amra boundary``: the stability boundary map (CG x GJ) from the command line.

    amra boundary --preset paper-boundary --fidelity rigid --mu 0 --ea 0.32 \\
        [--cg 0.20:0.50:16] [--gj 30:3000] [--aero theodorsen] [--method eigen|time] \\
        [--workers N] [--scheduler ADDR] [--store FILE] [--out map.csv] [--plot map.png] [--json] [--quiet]

Prints the critical GJ per CG column with every interval of the column (stable, flutter, fold,
windmill-brake; GJ in N m^2/rad) (or, with ``--json``, an object with ``critical_gj``,
``boundaries``, ``cells``, ``cases``, ``cached_cases``, ``wall_time_s``, ...). A progress bar goes
to stderr when it is a terminal. Bad values exit with code 2 and a message naming the parameter and
its allowed range. Ctrl-C returns the partial map (exit 130).
"""
from __future__ import annotations

import json
import math
import sys
import threading

from ..flight import AERO_MODELS
from ..shapes import FIDELITIES
from .common import number, value_range


def register(sub) -> None:
    """Add the ``boundary`` sub-command to the ``amra`` parser's sub-parsers ``sub``."""
    p = sub.add_parser("boundary", help="stability boundary map over CG x GJ (paper Fig. 14)",
                       description="Stability boundary map over CG x GJ: each CG column is walked down its trim "
                                   "branch by continuation from --gj's upper end, with every stability change "
                                   "and the fold bracketed to --tol.")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--preset", help="shipped rotor preset (default paper-boundary)")
    g.add_argument("--rotor", metavar="FILE", help="a rotor TOML file of your own")
    p.add_argument("--fidelity", choices=FIDELITIES, default="rigid")
    p.add_argument("--aero", choices=AERO_MODELS, default="theodorsen")
    p.add_argument("--mu", type=number("--mu", 0.0, 0.5), default=0.0, help="advance ratio [-] (0 = axial)")
    p.add_argument("--ea", type=number("--ea", 0.0, 1.0), default=0.32, help="elastic axis [chord fraction]")
    p.add_argument("--cg", type=value_range("--cg", 0.0, 1.0, True), default=(0.20, 0.50, 16),
                   help="CG columns A:B:N [chord fraction] (default 0.20:0.50:16)")
    p.add_argument("--gj", type=value_range("--gj", 1.0, 1e6, False), default=(30.0, 3000.0),
                   help="GJ range A:B [N m^2/rad], log scale (default 30:3000)")
    p.add_argument("--tol", type=number("--tol", 1e-4, 1.0), default=0.02,
                   help="relative GJ bracket width at which bisection stops (default 0.02)")
    p.add_argument("--coarse", type=number("--coarse", 2, 200, integer=True), default=7,
                   help="GJ values of the log grid probed below a fold (default 7)")
    p.add_argument("--method", choices=("eigen", "time"), default="eigen",
                   help="eigen: linearised about trim; time: time marching from trim plus a kick")
    p.add_argument("--elements", type=number("--elements", 1, 60, integer=True), default=10,
                   help="FEM elements per blade")
    p.add_argument("--workers", type=number("--workers", 1, 512, integer=True),
                   help="local worker processes (default: the CPU count; 1 = in this process)")
    p.add_argument("--scheduler", metavar="ADDR", help="dask.distributed scheduler address (tcp://host:8786)")
    p.add_argument("--store", metavar="FILE", help="SQLite result store: reuse and keep finished cells")
    p.add_argument("--out", metavar="FILE.csv", help="write the cells as CSV")
    p.add_argument("--plot", metavar="FILE.png", help="write the map as a PNG")
    p.add_argument("--json", action="store_true", help="print the whole map as JSON")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_boundary)


def _spec(args):
    import numpy as np
    from ..boundary import MapSpec
    from ..rotor_io import load_rotor_file
    a, b, n = args.cg
    cgs = tuple(float(x) for x in np.linspace(a, b, n)) if n > 1 else (a,)
    rotor = load_rotor_file(args.rotor) if args.rotor else (args.preset or "paper-boundary")
    if isinstance(rotor, str):
        from ..rotor_io import load_preset
        load_preset(rotor)  # a bad preset name fails here, naming the choices
    return MapSpec(rotor=rotor, fidelity=args.fidelity, aero=args.aero, mu=args.mu, ea=args.ea, cg_values=cgs,
                   gj_min=args.gj[0], gj_max=args.gj[1], gj_rel_tol=args.tol, n_coarse=args.coarse,
                   method=args.method, n_elements=args.elements)


def cmd_boundary(args) -> int:
    from ..boundary import iter_map, solver_fingerprint
    from ..executor import make_executor
    spec = _spec(args)
    if args.scheduler and args.workers:
        raise ValueError("--workers and --scheduler are both given: the dask cluster sets its own workers")
    store = None
    if args.store:
        import warnings
        from ..store import CellStore, StoreWarning
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", StoreWarning)
            store = CellStore(args.store, solver=solver_fingerprint())
        if store.notice:
            print(f"amra boundary: warning: {store.notice}", file=sys.stderr)
    try:
        executor = make_executor(workers=args.workers, scheduler=args.scheduler)
    except ImportError as exc:
        raise ValueError(f"--scheduler: {exc}") from None
    tty = sys.stderr.isatty() and not args.quiet
    cancel = threading.Event()
    run = iter_map(spec, executor=executor, store=store, cancel=cancel)
    interrupted = False
    try:
        try:
            for cell in run:
                if tty:
                    total = max(run.estimated_total, run.done)
                    k = int(30 * run.done / total)
                    sys.stderr.write(f"\r[{'#' * k}{'.' * (30 - k)}] {run.done} cells ({run.cached} from store), "
                                     f"CG {cell.cg:.3f} GJ {cell.gj_nm2:8.1f}: {cell.verdict:15s}")
                    sys.stderr.flush()
        except KeyboardInterrupt:
            cancel.set()
            interrupted = True
        bmap = run.result()
    finally:
        executor.close()
        if store is not None:
            store.close()
    if tty:
        sys.stderr.write("\n")
    out = bmap.to_dict()
    if args.out:
        bmap.to_csv(args.out)
        out["csv"] = args.out
    if args.plot:
        from ..map_plot import PAPER_AXIAL_POINTS, plot_map
        marks = PAPER_AXIAL_POINTS.get(spec.fidelity, []) if spec.mu == 0 and abs(spec.ea - 0.32) < 1e-9 else []
        plot_map(bmap, args.plot, marks=marks)
        out["plot"] = args.plot
    if args.json:
        print(json.dumps(out, indent=2))
    else:
        print(f"{spec.rotor_name()}, {spec.fidelity}, {spec.aero}, mu {spec.mu:g}, EA {spec.ea:g}, method {spec.method}: "
              f"{bmap.cases} cells ({bmap.cached_cases} from store) in {bmap.wall_time_s:.2f} s"
              + (" -- interrupted, partial map" if bmap.cancelled else ""))
        print(f"{'CG [c]':>8s} {'critical GJ [N m^2/rad]':>24s} {'bracket':>22s}  status")
        for col in bmap.columns:
            g = col["critical_gj"]
            gs = "-" if g is None else ("> GJ max" if not math.isfinite(g) else f"{g:.1f}")
            br = "" if not col["bracket"] else f"[{col['bracket'][0]:.1f}, {col['bracket'][1]:.1f}]"
            print(f"{col['cg']:8.3f} {gs:>24s} {br:>22s}  {col['status']}" + (f" ({col['kind']})" if col.get("kind") else ""))
            ivs = col.get("intervals") or []
            if ivs:
                print(" " * 10 + "; ".join(f"{iv['kind']} {iv['gj_lo_nm2']:.0f}-{iv['gj_hi_nm2']:.0f}"
                                           + ("" if iv.get("resolved", True) else " (edge from the probe grid)")
                                           for iv in ivs))
        for k in ("csv", "plot"):
            if k in out:
                print(f"{k}: {out[k]}")
    return 130 if interrupted else 0
