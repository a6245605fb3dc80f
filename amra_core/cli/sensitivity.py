"""``amra sensitivity``: how the fold GJ and the flutter GJ of one CG column move when each
estimated rotor value changes by +-10 % (:mod:`amra_core.sensitivity`)::

    amra sensitivity --preset paper-boundary --fidelity rigid --cg 0.40 --ea 0.32 --json
"""
from __future__ import annotations

import math
import sys

from ..flight import SolverSettings
from .common import chord_fraction, column_case_args, dumps_strict, number, value_range


def _fmt(v):
    if v is None:
        return "none"  # no such boundary inside the GJ range
    return "> max" if not math.isfinite(v) else f"{v:.0f}"


def _dfmt(v):
    return "-" if v is None else f"{v:+.0f}"


def cmd_sensitivity(args):
    from ..rotor_io import load_preset, load_rotor_file
    from ..sensitivity import ESTIMATE_NAMES, sensitivity
    rotor = (load_rotor_file(args.rotor) if args.rotor is not None
             else load_preset("paper-boundary" if args.preset is None else args.preset))
    params = None
    if args.params:
        params = tuple(p.strip() for p in args.params.split(",") if p.strip())
        bad = [p for p in params if p not in ESTIMATE_NAMES]
        if bad or not params:
            raise ValueError(f"--params {args.params!r} is not allowed: give a comma-separated list of "
                             f"{', '.join(ESTIMATE_NAMES)}")
    from ..flight import FlightCondition
    flight = FlightCondition(mu=args.mu) if args.mu > 0 else FlightCondition()
    settings = SolverSettings(fidelity=args.fidelity, aero=args.aero, n_elements=args.elements,
                              rigid_spring=args.rigid_spring)
    show = not args.quiet and sys.stderr.isatty()

    def progress(done, total, what):
        if show:
            print(f"\ramra sensitivity: {done}/{total} column walks ({what})", end="", file=sys.stderr, flush=True)

    res = sensitivity(rotor, args.cg, ea=args.ea, settings=settings, flight=flight, step=args.step,
                      parameters=params, gj_min_nm2=args.gj[0], gj_max_nm2=args.gj[1], rel_tol=args.tol,
                      n_probe=args.coarse, workers=args.workers, progress=progress)
    if show:
        print(file=sys.stderr)
    if args.json:
        print(dumps_strict(res.to_dict()))
        return 0
    b = res.baseline
    print(f"{res.rotor}, {res.fidelity}" + (f" ({res.rigid_spring} torsion spring)" if res.fidelity == "rigid" else "")
          + f", {res.aero}, mu {res.mu:g}, EA {args.ea:g}, CG {res.cg:g}: each estimate changed by "
          f"+-{res.step:.0%}; GJ in N m^2/rad, bracketed to {res.rel_tol:.0%}")
    print(f"baseline: fold GJ {_fmt(b.fold_gj_nm2)}, flutter GJ {_fmt(b.flutter_gj_nm2)}")
    print(f"{'estimate':30s} {'nominal':>10s} {'unit':8s} {'change':>7s} {'fold GJ':>8s} {'d fold':>7s} "
          f"{'flutter GJ':>10s} {'d flutter':>9s}")
    for r in res.rows:
        line = (f"{r.label:30s} {r.base_value:10.4g} {r.unit:8s} {r.change:+7.0%} {_fmt(r.fold_gj_nm2):>8s} "
                f"{_dfmt(r.d_fold_gj_nm2):>7s} {_fmt(r.flutter_gj_nm2):>10s} {_dfmt(r.d_flutter_gj_nm2):>9s}")
        print(line + (f"  ({r.note})" if r.note else ""))

    def band(bd):
        return "-" if bd is None else f"{_fmt(bd[0])} .. {_fmt(bd[1])}"
    print(f"band over the perturbations: fold GJ {band(res.fold_band_nm2)}, flutter GJ {band(res.flutter_band_nm2)}")
    print(f"({res.wall_time_s:.0f} s)")
    return 0


def register(sub) -> None:
    """Add the ``sensitivity`` sub-command to the ``amra`` parser's sub-parsers ``sub``."""
    from ..sensitivity import ESTIMATE_NAMES
    p = sub.add_parser("sensitivity", help="change of the fold and flutter GJ when each estimate changes by +-10 %%",
                       description="For each estimated rotor value (" + ", ".join(ESTIMATE_NAMES) + ") the CG "
                                   "column is walked again (the map's column walk) with the value changed by "
                                   "-STEP and +STEP; prints the fold GJ and flutter GJ and their changes.")
    column_case_args(p)
    p.add_argument("--cg", type=chord_fraction("--cg"), default=0.40, help="CG column [chord fraction]")
    p.add_argument("--step", type=number("--step", 0.001, 0.49), default=0.10,
                   help="relative change of each estimate (default 0.10: +-10 %%)")
    p.add_argument("--params", metavar="A,B,...", help="only these estimates (default: all)")
    p.add_argument("--gj", type=value_range("--gj", 1.0, 1e6, False), default=(30.0, 3000.0),
                   help="GJ range A:B [N m^2/rad] of the column walks (default 30:3000)")
    p.add_argument("--tol", type=number("--tol", 1e-4, 0.5), default=0.02,
                   help="relative GJ bracket width of the fold and flutter edges (default 0.02)")
    p.add_argument("--coarse", type=number("--coarse", 2, 200, integer=True), default=7,
                   help="GJ values of the log grid probed below a fold (default 7)")
    p.add_argument("--elements", type=number("--elements", 1, 60, integer=True), default=10,
                   help="FEM elements per blade")
    p.add_argument("--workers", type=number("--workers", 1, 64, integer=True), default=1,
                   help="worker processes for the column walks (default 1)")
    p.add_argument("--json", action="store_true", help="strict JSON (numbers that are not finite are null)")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    p.set_defaults(func=cmd_sensitivity)
