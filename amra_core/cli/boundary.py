"""``amra boundary``: the stability boundary map (CG x GJ) from the command line.

    amra boundary --preset paper-boundary --fidelity rigid --mu 0 --ea 0.32 \\
        [--cg 0.20:0.50:16] [--gj 30:3000] [--aero theodorsen] [--method eigen|time] \\
        [--weak-damping 0.02] [--weak-amplitude 1] [--workers N] [--scheduler ADDR] [--store FILE] [--out map.csv] [--plot map.png] [--json] [--quiet]

Prints per CG column the fold GJ (no normal autorotation below), the flutter GJ (top of the highest
strong instability) and the critical GJ (the larger), with every interval of the column (stable,
flutter with its strength and mode, fold, overspeed, windmill-brake; GJ in N m^2/rad);
``--weak-damping`` sets the damping ratio below which a flutter interval is strong (or, with
``--json``, an object with ``fold_gj``, ``flutter_gj``, ``critical_gj``, ``columns``,
``boundaries``, ``cells``, ``cases``, ``cached_cases``, ``wall_time_s``, ...). A progress bar goes
to stderr when it is a terminal. Bad values exit with code 2 and a message naming the parameter and
its allowed range. Ctrl-C (SIGINT) or SIGTERM cancels the map cleanly: the workers are stopped, the
cells already finished stay in the store, and the partial map is reported (exit 130 / 143).
Output paths and the store are checked before any cell is computed.

``--scheduler``: Dask deserialises (unpickles) what it receives, so a scheduler must belong to a
cluster you trust; ``tls://host:port`` encrypts and authenticates (certificates from
``AMRA_DASK_TLS_CA``/``AMRA_DASK_TLS_CERT``/``AMRA_DASK_TLS_KEY`` or the Dask configuration).
"""
from __future__ import annotations

import math
import signal
import sys
import threading
import warnings

from ..boundary.intervals import WEAK_AMPLITUDE_DEG, WEAK_DAMPING
from .common import column_case_args, dumps_strict, number, value_range


def register(sub) -> None:
    """Add the ``boundary`` sub-command to the ``amra`` parser's sub-parsers ``sub``."""
    p = sub.add_parser("boundary", help="stability boundary map over CG x GJ (paper Fig. 14)",
                       description="Stability boundary map over CG x GJ: each CG column is walked down its trim "
                                   "branch by continuation from --gj's upper end, with every stability change "
                                   "and the fold bracketed to --tol.")
    column_case_args(p)
    p.add_argument("--cg", type=value_range("--cg", 0.0, 1.0, True), default=(0.20, 0.50, 16),
                   help="CG columns A:B:N, or one column A [chord fraction] (default 0.20:0.50:16)")
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
    p.add_argument("--weak-damping", type=number("--weak-damping", 0.0, 1.0), default=WEAK_DAMPING,
                   help=f"flutter intervals whose most unstable oscillating mode has a damping ratio above minus "
                        f"this are weak: shown and exported, but they do not move the critical GJ "
                        f"(default {WEAK_DAMPING:g}; 0: every instability is strong), if also a 20 s run from "
                        f"the window stays within --weak-amplitude")
    p.add_argument("--weak-amplitude", type=number("--weak-amplitude", 0.0, 90.0), default=WEAK_AMPLITUDE_DEG,
                   help=f"largest twist and teeter amplitude [deg] of a weak window's 20 s run from the default kick "
                        f"(default {WEAK_AMPLITUDE_DEG:g})")
    p.add_argument("--workers", type=number("--workers", 1, 512, integer=True),
                   help="local worker processes (default: the CPU count; 1 = in this process; "
                        "at most 4 per CPU core, more are capped with a message)")
    p.add_argument("--scheduler", metavar="ADDR",
                   help="dask.distributed scheduler address (tcp://host:8786, or tls://host:8786 with the "
                        "certificates in AMRA_DASK_TLS_CA/_CERT/_KEY or the Dask config). Dask deserialises "
                        "(unpickles) what it receives: use a trusted cluster only")
    p.add_argument("--store", metavar="FILE",
                   help="SQLite result store: reuse and keep finished cells (a file that is not an AMRA store "
                        "is refused, never overwritten; a read-only store is used read-only)")
    p.add_argument("--out", metavar="FILE.csv", help="write the cells as CSV")
    p.add_argument("--plot", metavar="FILE.png", help="write the map as a PNG")
    p.add_argument("--json", action="store_true",
                   help="print the whole map as strict JSON (numbers that are not finite are null)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_boundary)


def _spec(args):
    import numpy as np
    from ..boundary import MapSpec
    from ..rotor_io import load_rotor_file
    a, b, n = args.cg
    cgs = tuple(float(x) for x in np.linspace(a, b, n)) if n > 1 else (a,)
    rotor = (load_rotor_file(args.rotor) if args.rotor is not None
             else ("paper-boundary" if args.preset is None else args.preset))
    from ..rotor_io import load_preset
    base = load_preset(rotor) if isinstance(rotor, str) else rotor  # a bad preset name fails here
    for cg in cgs:  # every column must be a physical section with this EA (torsional inertia bound)
        base.with_overrides(x_ea=args.ea, x_cg=cg)
    return MapSpec(rotor=rotor, fidelity=args.fidelity, aero=args.aero, mu=args.mu, ea=args.ea, cg_values=cgs,
                   gj_min=args.gj[0], gj_max=args.gj[1], gj_rel_tol=args.tol, n_coarse=args.coarse,
                   method=args.method, n_elements=args.elements, weak_damping=args.weak_damping,
                   weak_amplitude_deg=args.weak_amplitude, rigid_spring=args.rigid_spring)


def _warn(msg: str) -> None:
    print(f"amra boundary: warning: {msg}", file=sys.stderr)


class _Stop(KeyboardInterrupt):
    """SIGTERM during a map: handled like Ctrl-C."""


def cmd_boundary(args) -> int:
    from ..boundary import iter_map, solver_fingerprint
    from ..executor import cap_workers, make_executor
    if args.scheduler and args.workers:
        raise ValueError("--workers and --scheduler are both given: the dask cluster sets its own workers")
    spec = _spec(args)
    workers, note = cap_workers(args.workers)
    if note:
        _warn(note)
    store = None
    if args.store:
        from ..store import CellStore, StoreWarning
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", StoreWarning)
            store = CellStore(args.store, solver=solver_fingerprint())
        if store.notice:
            _warn(store.notice)
    try:
        executor = make_executor(workers=workers, scheduler=args.scheduler)
    except ImportError as exc:
        if store is not None:
            store.close()
        raise ValueError(f"--scheduler: {exc}") from None
    except BaseException:
        if store is not None:
            store.close()
        raise
    tty = sys.stderr.isatty() and not args.quiet
    cancel = threading.Event()
    run = iter_map(spec, executor=executor, store=store, cancel=cancel)
    interrupted = None
    old_term = None
    looping = False  #: True while waiting for the map's cells: only there does SIGTERM raise

    def on_term(signum, frame):
        nonlocal interrupted
        signal.signal(signal.SIGTERM, signal.SIG_IGN)  # one is enough: the map is being stopped
        cancel.set()
        if looping:
            raise _Stop()  # out of the wait for the next cell
        # before the first cell or after the last (the map assembled, the pool closing): the map
        # stops, or has finished, by itself; an exception here would skip the report and the
        # clean exit (a map that finished while its SIGTERM was on the way ended "interrupted", 130)
        interrupted = "SIGTERM"

    try:
        old_term = signal.signal(signal.SIGTERM, on_term)
    except ValueError:  # not the main thread: no signal handling here
        old_term = None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("always")
            warnings.showwarning = lambda m, *a, **k: _warn(str(m))
            try:
                looping = True
                for cell in run:
                    if tty:
                        total = max(run.estimated_total, run.done)
                        k = int(30 * run.done / total)
                        sys.stderr.write(f"\r[{'#' * k}{'.' * (30 - k)}] {run.done} cells ({run.cached} from store), "
                                         f"CG {cell.cg:.3f} GJ {cell.gj_nm2:8.1f}: {cell.verdict:15s}")
                        sys.stderr.flush()
                looping = False
            except KeyboardInterrupt as exc:
                looping = False
                cancel.set()
                interrupted = "SIGTERM" if isinstance(exc, _Stop) else "SIGINT"
                run.cancelled = True
            try:
                signal.signal(signal.SIGINT, signal.SIG_IGN) if interrupted else None
            except ValueError:
                pass
            bmap = run.result()
    finally:
        executor.close()
        n_stored = None
        if store is not None:
            try:
                n_stored = len(store)
            except Exception:  # noqa: BLE001
                n_stored = None
            store.close()
        if old_term is not None:
            signal.signal(signal.SIGTERM, old_term)
        if interrupted:
            try:
                signal.signal(signal.SIGINT, signal.default_int_handler)
            except ValueError:
                pass
    if interrupted:
        kept = (f"; the store {args.store!r} holds {n_stored} cells: rerun with the same --store to resume"
                if store is not None else "; nothing was stored (no --store)")
        print(f"amra boundary: interrupted ({interrupted}): {bmap.computed_cases} cells computed, "
              f"{bmap.cached_cases} from the store{kept}", file=sys.stderr)
    if tty:
        sys.stderr.write("\n")
    out = bmap.to_dict()
    write_error = None
    try:
        if args.out:
            bmap.to_csv(args.out)
            out["csv"] = args.out
        if args.plot:
            from ..map_plot import PAPER_AXIAL_POINTS, plot_map
            marks = PAPER_AXIAL_POINTS.get(spec.fidelity, []) if spec.mu == 0 and abs(spec.ea - 0.32) < 1e-9 else []
            plot_map(bmap, args.plot, marks=marks)
            out["plot"] = args.plot
    except OSError as exc:  # checked before the run; a disk that fills up meanwhile still ends here
        write_error = f"cannot write {exc.filename or 'the output'!r}: {exc.strerror or exc}"
    if args.json:
        print(dumps_strict(out))
    else:
        print(f"{spec.rotor_name()}, {spec.fidelity}, {spec.aero}, mu {spec.mu:g}, EA {spec.ea:g}, method {spec.method}: "
              f"{bmap.cases} cells ({bmap.cached_cases} from store) in {bmap.wall_time_s:.2f} s"
              + (" -- interrupted, partial map" if bmap.cancelled else ""))
        print(f"GJ in N m^2/rad; fold: no normal autorotation below; flutter: top of the highest strong instability; "
              f"critical: the larger; weak: damping ratio above -{spec.weak_damping:g} and a 20 s run within "
              f"{spec.weak_amplitude_deg:g} deg")
        print("fold, flutter and critical GJ are the upper ends of their brackets (the safe side); an interval "
              "ends at the geometric mean of the two GJ values that bracket its edge")
        # a cell's rotor has EA, CG and GJ uniform along the span: the preset's own (McCutcheon's tapered EA)
        # is another rotor, and a run of "the same cell" without --ea disagreed with the map
        rotor_arg = f"--rotor {args.rotor}" if args.rotor is not None else f"--preset {spec.rotor_name()}"
        print(f"a cell is this rotor with EA {spec.ea:g}, its CG and its GJ uniform along the span; run one with: amra "
              f"simulate {rotor_arg} --fidelity {spec.fidelity} --aero {spec.aero} --mu {spec.mu:g} --ea {spec.ea:g} "
              f"--cg CG --gj GJ")
        print(f"{'CG [c]':>8s} {'fold GJ':>9s} {'flutter GJ':>11s} {'critical GJ':>12s} {'bracket':>22s}  status")

        def gjs(g):
            return "-" if g is None else ("> GJ max" if not math.isfinite(g) else f"{g:.1f}")
        for col in bmap.columns:
            br = "" if not col["bracket"] else f"[{col['bracket'][0]:.1f}, {col['bracket'][1]:.1f}]"
            print(f"{col['cg']:8.3f} {gjs(col.get('fold_gj')):>9s} {gjs(col.get('flutter_gj')):>11s} "
                  f"{gjs(col['critical_gj']):>12s} {br:>22s}  {col['status']}"
                  + (f" ({col['kind']})" if col.get("kind") else ""))
            for iv in col.get("intervals") or []:
                line = f"{iv['kind']} {iv['gj_lo_nm2']:.0f}-{iv['gj_hi_nm2']:.0f}"
                if iv["kind"] == "flutter":
                    line += f" {'fold approach' if iv.get('fold_approach') else iv.get('strength', '')}"
                    if iv.get("peak_growth_rate_1_s") is not None:
                        line += (f": peak {iv['peak_growth_rate_1_s']:+.2f} 1/s, damping ratio {iv['damping_ratio']:+.4f},"
                                 f" {iv['frequency_hz']:.1f} Hz, {iv['mode']}")
                    if iv.get("run_outcome"):
                        a = iv.get("run_amplitude") or {}
                        line += (f"; run at {iv['run_gj_nm2']:.0f}: {iv['run_outcome']}, twist +/-"
                                 f"{a.get('twist_deg') or 0:.2f} deg, teeter +/-{a.get('teeter_deg') or 0:.2f} deg")
                if not iv.get("resolved", True):
                    line += " (edge from the probe grid)"
                print(" " * 10 + line)
        for k in ("csv", "plot"):
            if k in out:
                print(f"{k}: {out[k]}")
    if write_error:
        print(f"amra boundary: error: {write_error} (the map above is complete)", file=sys.stderr)
        return 2
    return {"SIGINT": 130, "SIGTERM": 143}.get(interrupted, 0)
