"""``amra modes``: labelled natural frequencies (in vacuo) at a rotor speed."""
from __future__ import annotations

import json

from ..shapes import FIDELITIES
from .common import dumps_strict, load_rotor, number, rigid_spring_arg, rotor_args


def cmd_modes(args):
    from ..modes import modes_report
    rotor = load_rotor(args)
    rep = modes_report(rotor, args.fidelity, args.elements, args.omega, rigid_spring=args.rigid_spring)
    if args.json:
        print(dumps_strict(rep))
    else:
        print(f"case: {rotor.name}, {args.fidelity}, in vacuo at rotor speed {args.omega:g} rad/s"
              + (" (per rev: give --omega)" if args.omega == 0 else ""))
        print(f"{'mode':28s} {'f [Hz]':>10s} {'per rev':>8s}")
        for m in rep["modes"]:
            pr = "" if m["per_rev"] is None else f"{m['per_rev']:.3f}"
            print(f"{m['label']:28s} {m['frequency_hz']:10.3f} {pr:>8s}")


def register(sub) -> None:
    p = sub.add_parser("modes", help="natural frequencies with labels (in vacuo)")
    rotor_args(p)
    p.add_argument("--omega", type=number("--omega", 0.0, 200.0), default=0.0, help="rotor speed [rad/s]")
    p.add_argument("--elements", type=number("--elements", 1, 60, integer=True), default=10)
    p.add_argument("--fidelity", choices=FIDELITIES, default="fem-coupled")
    rigid_spring_arg(p)
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=cmd_modes)
