"""``amra`` command line: rotor, modes, trim, simulate, bench.

Bad input exits with code 2 and a one-line message naming the parameter and its allowed range;
never a traceback. Long runs show progress on stderr when it is a terminal.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time

from . import boundary_cli
from . import validate_cli
from .flight import FlightCondition, SettingsError, SolverSettings
from .rotor import RotorError
from .shapes import FIDELITIES


class UsageError(Exception):
    pass


def _number(name, lo, hi, integer=False):
    def parse(text):
        try:
            v = int(text) if integer else float(text)
        except ValueError:
            kind = "an integer" if integer else "a number"
            raise argparse.ArgumentTypeError(f"{name} = {text!r} is not {kind}: allowed [{lo}, {hi}]") from None
        if not (lo <= v <= hi) or (not integer and not math.isfinite(v)):
            raise argparse.ArgumentTypeError(f"{name} = {text} is out of range: allowed [{lo}, {hi}]")
        return v
    return parse


def _rotor_args(p, overrides=True):
    g = p.add_mutually_exclusive_group()
    g.add_argument("--preset", help="shipped rotor preset (mccutcheon, paper-boundary)")
    g.add_argument("--rotor", metavar="FILE", help="a rotor TOML file of your own")
    if overrides:
        p.add_argument("--gj", type=_number("--gj", 1.0, 1e6), help="uniform GJ [N m^2/rad]")
        p.add_argument("--ea", type=_number("--ea", 0.0, 1.0), help="uniform elastic axis [chord fraction]")
        p.add_argument("--cg", type=_number("--cg", 0.0, 1.0), help="uniform centre of gravity [chord fraction]")


def _flight_args(p):
    g = p.add_mutually_exclusive_group()
    g.add_argument("--mu", type=_number("--mu", 0.0, 0.5), help="advance ratio of the trimmed state [-]")
    g.add_argument("--airspeed", type=_number("--airspeed", 0.0, 80.0), help="horizontal airspeed [m/s]")
    p.add_argument("--fidelity", choices=FIDELITIES, default="rigid")
    p.add_argument("--elements", type=_number("--elements", 1, 60, integer=True), default=10,
                   help="FEM elements per blade")


def _load_rotor(args):
    from .rotor_io import load_preset, load_rotor_file
    rotor = load_rotor_file(args.rotor) if args.rotor else load_preset(args.preset or "mccutcheon")
    if hasattr(args, "gj"):
        rotor = rotor.with_overrides(gj_nm2=args.gj, x_ea=args.ea, x_cg=args.cg)
    return rotor


def _flight(args, omega_hold=None):
    mu = getattr(args, "mu", None)
    airspeed = getattr(args, "airspeed", None) or 0.0
    return FlightCondition(airspeed_m_s=airspeed, mu=mu if mu else None, omega_hold_rad_s=omega_hold)


def _emit(obj, as_json):
    if as_json:
        print(json.dumps(obj, indent=2, default=_jsonable))
    else:
        for k, v in obj.items():
            if isinstance(v, float):
                v = f"{v:.6g}"
            print(f"{k:28s} {v}")


def _jsonable(o):
    import numpy as np
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(type(o).__name__)


# ----------------------------------------------------------------------------- commands
def cmd_rotor(args):
    _emit(_load_rotor(args).to_dict(), args.json)


def cmd_modes(args):
    from .modes import modes_report
    rep = modes_report(_load_rotor(args), args.fidelity, args.elements, args.omega)
    if args.json:
        print(json.dumps(rep, indent=2, default=_jsonable))
    else:
        print(f"{'mode':28s} {'f [Hz]':>10s} {'per rev':>8s}")
        for m in rep["modes"]:
            pr = "" if m["per_rev"] is None else f"{m['per_rev']:.3f}"
            print(f"{m['label']:28s} {m['frequency_hz']:10.3f} {pr:>8s}")


def cmd_trim(args):
    from .model import compile_model
    from .trim import trim
    rotor = _load_rotor(args)
    settings = SolverSettings(fidelity=args.fidelity, n_elements=args.elements)
    model = compile_model(rotor, _flight(args, args.omega_hold), settings)
    res = trim(model)
    _emit(res.to_dict(), args.json)
    return 0


def cmd_simulate(args):
    from .simulation import Case, Simulation
    rotor = _load_rotor(args)
    settings = SolverSettings(fidelity=args.fidelity, aero=args.aero, inflow=args.inflow, n_elements=args.elements)
    case = Case(rotor, _flight(args), settings, t_end_s=args.t_end)
    t0 = time.perf_counter()
    sim = Simulation(case)
    tty = sys.stderr.isatty() and not args.quiet

    def progress(t, t_end):
        if tty:
            n = int(30 * t / t_end)
            sys.stderr.write(f"\r[{'#' * n}{'.' * (30 - n)}] {t:6.2f}/{t_end:.2f} s simulated")
            sys.stderr.flush()

    sim.run(progress=progress)
    if tty:
        sys.stderr.write("\n")
    wall = time.perf_counter() - t0
    v = sim.verdict()
    h = sim.history
    from .simulation import COL
    last = h[h[:, 0] >= h[-1, 0] - 2 * math.pi / max(h[-1, COL["omega_rad_s"]], 1e-3)]
    out = {
        "verdict": v.verdict, "growth_rate_per_s": v.growth_rate_per_s, "frequency_hz": v.frequency_hz,
        "collapse_time_s": v.collapse_time_s, "explanation": v.explanation,
        "omega_trim_rad_s": sim.trim.omega_rad_s if sim.trim.ok else None,
        "descent_rate_trim_m_s": sim.trim.descent_rate_m_s if sim.trim.ok else None,
        "omega_start_rad_s": sim.omega_ref,
        "omega_final_rad_s": float(h[-1, COL["omega_rad_s"]]),
        "descent_rate_final_m_s": float(h[-1, COL["descent_rate_m_s"]]),
        "teeter_amplitude_rad": float(abs(last[:, COL["teeter_rad"]]).max()),
        "sim_time_s": sim.t, "wall_time_s": wall, "solver_wall_time_s": sim.wall_time_s,
        "run_status": sim.status, "start": sim.start_note, "case_key": case.key(),
        "fidelity": settings.fidelity, "aero": settings.aero,
    }
    if args.out:
        sim.to_csv(args.out)
        out["csv"] = args.out
    out = {k: (None if isinstance(val, float) and not math.isfinite(val) else val) for k, val in out.items()}
    _emit(out, args.json)
    return 0


def cmd_stability(args):
    from .model import compile_model
    from .stability import analyse
    settings = SolverSettings(fidelity=args.fidelity, aero=args.aero, n_elements=args.elements)
    res = analyse(compile_model(_load_rotor(args), _flight(args), settings))
    out = res.to_dict(include_aero_lag=args.all_modes)
    if not res.trim.ok:
        out["reason"] = res.trim.reason
    if args.json:
        print(json.dumps(out, indent=2, default=_jsonable))
    else:
        print(f"stable: {out['stable']}  ({out['method']}; trim {res.trim.status})")
        print(f"{'mode':14s} {'f [Hz]':>9s} {'zeta [-]':>9s} {'Re [1/s]':>10s}")
        for m in out["modes"]:
            print(f"{m['label']:14s} {m['frequency_hz']:9.3f} {m['damping_ratio']:9.4f} {m['real_part_per_s']:10.4f}")
    return 0


def cmd_bench(args):
    from .bench import run_bench
    rep = run_bench(sim_seconds=args.seconds)
    _emit(rep, args.json)


def cmd_app(args):
    import subprocess
    from pathlib import Path
    main = Path(__file__).resolve().parents[1] / "app" / "main.py"
    return subprocess.call([sys.executable, "-m", "panel", "serve", str(main), "--port", str(args.port),
                            "--address", args.address, "--num-threads", "0"])


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="amra", description="Aeroelastic model of a rotor in autorotation")
    sub = ap.add_subparsers(dest="command", required=True)

    p = sub.add_parser("rotor", help="print the resolved rotor as the solver uses it (SI)")
    _rotor_args(p)
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=cmd_rotor)

    p = sub.add_parser("modes", help="natural frequencies with labels (in vacuo)")
    _rotor_args(p)
    p.add_argument("--omega", type=_number("--omega", 0.0, 200.0), default=0.0, help="rotor speed [rad/s]")
    p.add_argument("--elements", type=_number("--elements", 1, 60, integer=True), default=10)
    p.add_argument("--fidelity", choices=FIDELITIES, default="fem-coupled")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=cmd_modes)

    p = sub.add_parser("trim", help="steady autorotation for a flight condition")
    _rotor_args(p)
    _flight_args(p)
    p.add_argument("--omega-hold", type=_number("--omega-hold", 1.0, 200.0), help="hold rotor speed [rad/s]")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=cmd_trim)

    p = sub.add_parser("simulate", help="time marching from trim plus a perturbation, with a verdict")
    _rotor_args(p)
    _flight_args(p)
    p.add_argument("--aero", choices=("quasi-steady", "theodorsen"), default="theodorsen")
    p.add_argument("--inflow", choices=("uniform", "three-state"), default="uniform",
                   help="uniform (Pitt-Peters) or three-state (Peters-HaQuang first harmonics)")
    p.add_argument("--t-end", type=_number("--t-end", 0.01, 600.0), default=10.0, help="simulated time [s]")
    p.add_argument("--out", metavar="FILE.csv", help="write the time histories as CSV")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=cmd_simulate)

    p = sub.add_parser("stability", help="eigenvalues (axial) or Floquet exponents (forward) about trim")
    _rotor_args(p)
    _flight_args(p)
    p.add_argument("--aero", choices=("quasi-steady", "theodorsen"), default="theodorsen")
    p.add_argument("--all-modes", action="store_true", help="also list the aerodynamic lag modes")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=cmd_stability)

    p = sub.add_parser("bench", help="simulated seconds per wall second for each fidelity")
    p.add_argument("--seconds", type=_number("--seconds", 0.5, 60.0), default=5.0)
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=cmd_bench)

    p = sub.add_parser("app", help="start the dashboard")
    p.add_argument("--port", type=_number("--port", 1, 65535, integer=True), default=5006)
    p.add_argument("--address", default="127.0.0.1")
    p.set_defaults(func=cmd_app)
    boundary_cli.register(sub)
    validate_cli.register(sub)
    return ap


def main(argv=None) -> int:
    ap = build_parser()
    args = ap.parse_args(argv)
    try:
        rc = args.func(args)
    except (RotorError, SettingsError, UsageError, ValueError) as exc:
        print(f"amra {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    return rc or 0


if __name__ == "__main__":
    sys.exit(main())
