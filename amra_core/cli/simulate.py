"""``amra simulate``: time marching from trim plus a perturbation, with a verdict."""
from __future__ import annotations

import math
import sys
import time

from ..flight import AERO_MODELS, INFLOW_MODELS, SolverSettings
from .common import emit, flight, flight_args, load_rotor, number, rotor_args


def cmd_simulate(args):
    from ..simulation import Case, Simulation
    rotor = load_rotor(args)
    settings = SolverSettings(fidelity=args.fidelity, aero=args.aero, inflow=args.inflow, n_elements=args.elements,
                              rigid_spring=args.rigid_spring)
    case = Case(rotor, flight(args), settings, t_end_s=args.t_end)
    t0 = time.perf_counter()
    from ..model import compile_model
    from ..trim import trim
    tr = trim(compile_model(case.rotor, case.flight, case.settings))
    if not tr.ok and tr.state is None:  # not even a branch end to start from: the verdict is the trim's
        out = {"verdict": "no-autorotation", "rotor_speed": "rotor speed not kept: no trimmed state to start from",
               "outcome": "undetermined", "limit_cycle": None, "growth_rate_per_s": None, "frequency_hz": None,
               "collapse_time_s": None, "explanation": tr.reason or "no trimmed state to start from",
               "run_status": "not-started", "start": "not started: no trimmed state, not even a branch end",
               "trim": tr.to_dict(), "sim_time_s": 0.0, "wall_time_s": time.perf_counter() - t0,
               "case_key": case.key(), "fidelity": settings.fidelity, "aero": settings.aero}
        emit(out, args.json)
        return 0
    sim = Simulation(case, trim_result=tr)
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
    from ..simulation import COL
    last = h[h[:, 0] >= h[-1, 0] - 2 * math.pi / max(h[-1, COL["omega_rad_s"]], 1e-3)]
    out = {
        "rotor_speed": v.rotor_speed, "verdict": v.verdict, "outcome": v.outcome, "limit_cycle": v.limit_cycle,
        "growth_rate_per_s": v.growth_rate_per_s, "frequency_hz": v.frequency_hz,
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
    emit(out, args.json)
    return 0


def register(sub) -> None:
    p = sub.add_parser("simulate", help="time marching from trim plus a perturbation, with a verdict")
    rotor_args(p)
    flight_args(p)
    p.add_argument("--aero", choices=AERO_MODELS, default="theodorsen")
    p.add_argument("--inflow", choices=INFLOW_MODELS, default="uniform",
                   help="uniform (Pitt-Peters) or three-state (Peters-HaQuang first harmonics)")
    p.add_argument("--t-end", type=number("--t-end", 0.01, 600.0), default=10.0, help="simulated time [s]")
    p.add_argument("--out", metavar="FILE.csv", help="write the time histories as CSV")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=cmd_simulate)
