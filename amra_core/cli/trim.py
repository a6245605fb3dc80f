"""``amra trim``: steady autorotation for a flight condition."""
from __future__ import annotations

from ..flight import SolverSettings
from .common import emit, flight, flight_args, load_rotor, number, rotor_args


def cmd_trim(args):
    from ..model import compile_model
    from ..trim import trim
    rotor = load_rotor(args)
    settings = SolverSettings(fidelity=args.fidelity, n_elements=args.elements, rigid_spring=args.rigid_spring)
    model = compile_model(rotor, flight(args, args.omega_hold), settings)
    res = trim(model)
    emit(res.to_dict(), args.json)
    return 0


def register(sub) -> None:
    p = sub.add_parser("trim", help="steady autorotation for a flight condition")
    rotor_args(p)
    flight_args(p)
    p.add_argument("--omega-hold", type=number("--omega-hold", 1.0, 200.0), help="hold rotor speed [rad/s]")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=cmd_trim)
