"""``amra stability``: eigenvalues (axial) or Floquet exponents (forward) about trim."""
from __future__ import annotations

import json

from ..flight import AERO_MODELS, SolverSettings
from .common import flight, flight_args, dumps_strict, load_rotor, rotor_args


def cmd_stability(args):
    from ..model import compile_model
    from ..stability import analyse, verdict_of_trim
    settings = SolverSettings(fidelity=args.fidelity, aero=args.aero, n_elements=args.elements,
                              rigid_spring=args.rigid_spring)
    rotor, fl = load_rotor(args), flight(args)
    res = analyse(compile_model(rotor, fl, settings))
    out = res.to_dict(include_aero_lag=args.all_modes)
    out["verdict"] = verdict_of_trim(res.trim, res.modes)  #: a map cell's word for this case
    if not res.trim.ok:
        out["reason"] = res.trim.reason
    if args.json:
        print(dumps_strict(out))
    else:
        crit = res.critical
        why = "" if crit is None else (f"; least damped: {crit.label} {crit.real_part_per_s:+.3g} 1/s at "
                                       f"{crit.frequency_hz:.3g} Hz")
        print(f"verdict: {out['verdict']} (a map cell's word{why})")
        print(f"stable: {out['stable']}  ({out['method']}; trim {res.trim.status}, branch {res.trim.branch})")
        print(f"case: {case_line(rotor, settings.fidelity, fl, res.trim)}")
        if not res.trim.ok:
            print(f"reason: {res.trim.reason}")
        print(f"{'mode':14s} {'f [Hz]':>9s} {'zeta [-]':>9s} {'Re [1/s]':>10s}")
        for m in out["modes"]:
            print(f"{m['label']:14s} {m['frequency_hz']:9.3f} {m['damping_ratio']:9.4f} {m['real_part_per_s']:10.4f}")
    return 0


def case_line(rotor, fidelity: str, fl, tr) -> str:
    """What was analysed, in one line: rotor, fidelity, mean GJ, flight, and the trim it is about."""
    where = "axial" if fl.is_axial else (f"mu {fl.mu:g}" if fl.mu is not None else f"{fl.airspeed_m_s:g} m/s")
    line = f"{rotor.name}, {fidelity}, GJ {rotor.stations.mean('gj_nm2'):.4g} N m^2/rad, {where}"
    if tr.ok:
        line += f"; trim: rotor speed {tr.omega_rad_s:.2f} rad/s, descent rate {tr.descent_rate_m_s:.2f} m/s"
    return line


def register(sub) -> None:
    p = sub.add_parser("stability", help="eigenvalues (axial) or Floquet exponents (forward) about trim")
    rotor_args(p)
    flight_args(p)
    p.add_argument("--aero", choices=AERO_MODELS, default="theodorsen")
    p.add_argument("--all-modes", action="store_true", help="also list the aerodynamic lag modes")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=cmd_stability)
