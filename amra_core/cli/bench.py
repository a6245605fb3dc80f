"""``amra bench``: simulated seconds per wall second for each fidelity."""
from __future__ import annotations

from .common import emit, number


def cmd_bench(args):
    import sys
    from ..bench import FORWARD_ACCURACY, run_bench
    rep = run_bench(sim_seconds=args.seconds)
    emit(rep, args.json)
    for key in FORWARD_ACCURACY:  # reported, not failed (bench docstring)
        out = [f"{fid}: {a['max_omega_relative_error']:.2g} relative at its largest, "
               f"{a['max_omega_relative_error_after_kick']:.2g} after the kick"
               for fid, f in rep["fidelities"].items() if key in f and not (a := f[key])["within_bounds"]]
        if out:
            mu = next(f[key]["mu"] for f in rep["fidelities"].values() if key in f)
            print(f"amra bench: warning: in forward flight (mu {mu:g}) the default steps exceed the bounds "
                  f"during the kick (rotor speed: " + "; ".join(out) + ")", file=sys.stderr)
    if not rep["accuracy_ok"]:  # a speed bought with accuracy is no speed: fail loudly
        bad = [f"{fid}: tip twist error {a['max_tip_twist_relative_error']:.3g} of its excursion (bound "
               f"{a['tip_twist_relative_error_bound']:g}), rotor speed {a['max_omega_relative_error']:.3g} relative "
               f"(bound {a['omega_relative_error_bound']:g})"
               for fid, f in rep["fidelities"].items() if not (a := f["accuracy"])["within_bounds"]]
        print("amra bench: error: accuracy lost against the reference at 1/8 of the step: " + "; ".join(bad),
              file=sys.stderr)
        return 1
    return 0


def register(sub) -> None:
    p = sub.add_parser("bench", help="simulated seconds per wall second for each fidelity")
    p.add_argument("--seconds", type=number("--seconds", 0.5, 60.0), default=5.0)
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=cmd_bench)
