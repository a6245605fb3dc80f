"""``amra simulate``: time marching from trim plus a perturbation, with a verdict."""
from __future__ import annotations

import math
import sys
import time

from ..flight import AERO_MODELS, INFLOW_MODELS, SolverSettings
from .common import UsageError, emit, flight, flight_args, load_rotor, number, rotor_args

DEFAULT_T_END_S = 10.0


def scenario_of(args, case):
    """The scripted changes asked for: ``--paper-case`` (a whole case of its own) or ``--change-at``
    with ``--gj-after`` on the case the other flags describe; None for a plain run."""
    from ..paper_cases import PAPER_CASES
    from ..scenario import LiveChange, Scenario
    if args.paper_case:
        return PAPER_CASES[args.paper_case].scenario(run_s=args.t_end)
    if (args.change_at is None) != (args.gj_after is None):
        raise UsageError("--change-at and --gj-after go together: the time [s] and the GJ [N m^2/rad] from then on")
    if args.change_at is None:
        return None
    if not args.change_at < case.t_end_s:
        raise UsageError(f"--change-at = {args.change_at:g} is not allowed: must come before --t-end "
                         f"({case.t_end_s:g} s)")
    return Scenario(case, (LiveChange(args.change_at, gj_nm2=args.gj_after),))


def cmd_simulate(args):
    from ..simulation import Case, Simulation
    rotor = load_rotor(args)
    settings = SolverSettings(fidelity=args.fidelity, aero=args.aero, inflow=args.inflow, n_elements=args.elements,
                              rigid_spring=args.rigid_spring, dt_s=args.dt_s)
    case = Case(rotor, flight(args), settings, t_end_s=args.t_end or DEFAULT_T_END_S)
    scenario = scenario_of(args, case)
    if scenario is not None:
        return _simulate_scenario(args, scenario)
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
    progress, tty = _progress_bar(args)
    sim.run(progress=progress)
    if tty:
        sys.stderr.write("\n")
    return _report(args, sim, t0)


def _progress_bar(args):
    tty = sys.stderr.isatty() and not args.quiet

    def progress(t, t_end):
        if tty:
            n = int(30 * t / t_end)
            sys.stderr.write(f"\r[{'#' * n}{'.' * (30 - n)}] {t:6.2f}/{t_end:.2f} s simulated")
            sys.stderr.flush()
    return progress, tty


def _simulate_scenario(args, scenario):
    from ..paper_cases import PAPER_CASES
    from ..scenario import run_scenario
    t0 = time.perf_counter()
    progress, tty = _progress_bar(args)
    sim = run_scenario(scenario, progress=progress)
    if tty:
        sys.stderr.write("\n")
    extra = {"changes": [c.describe() for c in scenario.changes]}
    if args.paper_case:
        pc = PAPER_CASES[args.paper_case]
        extra["paper_case"] = {"key": pc.key, "label": pc.label, "paper_reports": pc.paper_reports,
                               "model_gives": pc.model_gives, "model_fold_gj_nm2": pc.model_fold_gj_nm2}
    return _report(args, sim, t0, extra)


def _report(args, sim, t0, extra=None):
    case, settings = sim.case, sim.case.settings
    wall = time.perf_counter() - t0
    v = sim.verdict()
    h = sim.history
    from ..simulation import COL
    from ..verdict import teeter_amplitude_rad
    out = {
        "rotor_speed": v.rotor_speed, "verdict": v.verdict, "outcome": v.outcome, "limit_cycle": v.limit_cycle,
        "growth_rate_per_s": v.growth_rate_per_s, "frequency_hz": v.frequency_hz,
        "collapse_time_s": v.collapse_time_s, "explanation": v.explanation,
        "omega_trim_rad_s": sim.trim.omega_rad_s if sim.trim.ok else None,
        "descent_rate_trim_m_s": sim.trim.descent_rate_m_s if sim.trim.ok else None,
        "omega_start_rad_s": sim.omega_ref,
        "omega_final_rad_s": float(h[-1, COL["omega_rad_s"]]),
        "descent_rate_final_m_s": float(h[-1, COL["descent_rate_m_s"]]),
        "teeter_amplitude_rad": teeter_amplitude_rad(h),  # first harmonic, last revolution (Table 1)
        "sim_time_s": sim.t, "dt_s": sim.dt, "wall_time_s": wall, "solver_wall_time_s": sim.wall_time_s,
        "run_status": sim.status, "start": sim.start_note, "case_key": case.key(),
        "fidelity": settings.fidelity, "aero": settings.aero,
    } | (extra or {})
    if args.out:
        sim.to_csv(args.out, verdict=v)
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
    p.add_argument("--dt-s", type=number("--dt-s", 1e-6, 0.01), default=None, metavar="DT_S",
                   help="time step [s] (default: chosen from the stiffest mode); a shorter one tells a numerical "
                        "failure of the step from a motion growing beyond the model's range")
    p.add_argument("--t-end", type=number("--t-end", 0.01, 600.0), default=None,
                   help=f"simulated time [s] (default {DEFAULT_T_END_S:g}; a paper case's own, 12)")
    p.add_argument("--change-at", type=number("--change-at", 0.01, 599.0), metavar="T_S",
                   help="apply a live change at this simulated time [s] (with --gj-after)")
    p.add_argument("--gj-after", type=number("--gj-after", 1.0, 1e6), metavar="GJ",
                   help="uniform GJ [N m^2/rad] from --change-at on, as a live slider change")
    from ..paper_cases import PAPER_CASES
    p.add_argument("--paper-case", choices=sorted(PAPER_CASES),
                   help="the paper's Fig. 10-13 story: the nominal blade trimmed, softened to the figure's GJ at "
                        "t = 2 s (sets rotor, EA, CG, fidelity and flight; the other case flags are ignored)")
    p.add_argument("--out", metavar="FILE.csv", help="write the time histories as CSV")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=cmd_simulate)
