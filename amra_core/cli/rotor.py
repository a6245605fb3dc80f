"""``amra rotor``: the resolved rotor and blade as the solver uses them (SI)."""
from __future__ import annotations

from .common import emit, load_rotor, rotor_args


def cmd_rotor(args):
    emit(load_rotor(args).to_dict(), args.json)


def register(sub) -> None:
    p = sub.add_parser("rotor", help="print the resolved rotor as the solver uses it (SI)")
    rotor_args(p)
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=cmd_rotor)
