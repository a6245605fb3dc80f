"""Argument helpers shared by every ``amra`` sub-command: number and range parsers with the
allowed range in their messages, the rotor and flight arguments, and output."""
from __future__ import annotations

import argparse
import json
import math

from ..flight import FlightCondition
from ..shapes import FIDELITIES


class UsageError(Exception):
    """A combination of arguments that cannot be used; exits 2 with the message."""


def number(name, lo, hi, integer=False):
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


def rotor_args(p, overrides=True):
    g = p.add_mutually_exclusive_group()
    g.add_argument("--preset", help="shipped rotor preset (mccutcheon, paper-boundary)")
    g.add_argument("--rotor", metavar="FILE", help="a rotor TOML file of your own")
    if overrides:
        p.add_argument("--gj", type=number("--gj", 1.0, 1e6), help="uniform GJ [N m^2/rad]")
        p.add_argument("--ea", type=number("--ea", 0.0, 1.0), help="uniform elastic axis [chord fraction]")
        p.add_argument("--cg", type=number("--cg", 0.0, 1.0), help="uniform centre of gravity [chord fraction]")


def flight_args(p):
    g = p.add_mutually_exclusive_group()
    g.add_argument("--mu", type=number("--mu", 0.0, 0.5), help="advance ratio of the trimmed state [-]")
    g.add_argument("--airspeed", type=number("--airspeed", 0.0, 80.0), help="horizontal airspeed [m/s]")
    p.add_argument("--fidelity", choices=FIDELITIES, default="rigid")
    p.add_argument("--elements", type=number("--elements", 1, 60, integer=True), default=10,
                   help="FEM elements per blade")


def load_rotor(args):
    from ..rotor_io import load_preset, load_rotor_file
    rotor = load_rotor_file(args.rotor) if args.rotor else load_preset(args.preset or "mccutcheon")
    if hasattr(args, "gj"):
        rotor = rotor.with_overrides(gj_nm2=args.gj, x_ea=args.ea, x_cg=args.cg)
    return rotor


def flight(args, omega_hold=None):
    mu = getattr(args, "mu", None)
    airspeed = getattr(args, "airspeed", None) or 0.0
    return FlightCondition(airspeed_m_s=airspeed, mu=mu if mu else None, omega_hold_rad_s=omega_hold)


def emit(obj, as_json):
    if as_json:
        print(json.dumps(obj, indent=2, default=jsonable))
    else:
        for k, v in obj.items():
            if isinstance(v, float):
                v = f"{v:.6g}"
            print(f"{k:28s} {v}")


def jsonable(o):
    import numpy as np
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(type(o).__name__)


def value_range(name, lo, hi, with_count):
    """Parser of ``A:B`` (or ``A:B:N`` with ``with_count``) with both ends in [lo, hi]."""
    form = "A:B:N" if with_count else "A:B"

    def parse(text):
        parts = text.split(":")
        if len(parts) != (3 if with_count else 2):
            raise argparse.ArgumentTypeError(f"{name} = {text!r} is not allowed: give {form}")
        try:
            a, b = float(parts[0]), float(parts[1])
            n = int(parts[2]) if with_count else None
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} = {text!r} is not allowed: give {form} with numbers") from None
        for v in (a, b):
            if not math.isfinite(v) or not lo <= v <= hi:
                raise argparse.ArgumentTypeError(f"{name} = {text!r} is out of range: A and B must lie in [{lo}, {hi}]")
        if with_count:
            if not 1 <= n <= 200:
                raise argparse.ArgumentTypeError(f"{name} = {text!r} is out of range: N must be an integer in [1, 200]")
            if n > 1 and not b > a:
                raise argparse.ArgumentTypeError(f"{name} = {text!r} is not allowed: B must exceed A")
            return (a, b, n)
        if not b > a:
            raise argparse.ArgumentTypeError(f"{name} = {text!r} is not allowed: B must exceed A")
        return (a, b)
    return parse
