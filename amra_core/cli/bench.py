"""``amra bench``: simulated seconds per wall second for each fidelity."""
from __future__ import annotations

from .common import emit, number


def cmd_bench(args):
    from ..bench import run_bench
    emit(run_bench(sim_seconds=args.seconds), args.json)


def register(sub) -> None:
    p = sub.add_parser("bench", help="simulated seconds per wall second for each fidelity")
    p.add_argument("--seconds", type=number("--seconds", 0.5, 60.0), default=5.0)
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=cmd_bench)
