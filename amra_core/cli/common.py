"""Argument helpers shared by every ``amra`` sub-command: number and range parsers with the
allowed range in their messages, the rotor and flight arguments, output-path checks (before any
work starts) and strict JSON output (non-finite numbers become ``null``, never ``NaN``/``Infinity``)."""
from __future__ import annotations

import argparse
import errno
import json
import math
import os
import stat

from ..flight import AERO_MODELS, FlightCondition
from ..shapes import FIDELITIES, TORSION_SPRINGS


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


def chord_fraction(name):
    """A chordwise position [chord fraction, 0 to 1]; a value typed in % chord (as the dashboard
    shows it) is refused with the fraction it meant."""
    def parse(text):
        try:
            v = float(text)
        except ValueError:
            v = math.nan
        if 1.0 < v <= 100.0:
            raise argparse.ArgumentTypeError(f"{name} = {text} is out of range: allowed [0.0, 1.0], a chord fraction "
                                             f"({v:g} % chord is {name} {v / 100:g})")
        return number(name, 0.0, 1.0)(text)
    return parse


def rotor_args(p, overrides=True):
    g = p.add_mutually_exclusive_group()
    g.add_argument("--preset", help="shipped rotor preset (mccutcheon, paper-boundary)")
    g.add_argument("--rotor", metavar="FILE", help="a rotor TOML file of your own")
    if overrides:
        p.add_argument("--gj", type=number("--gj", 1.0, 1e6), help="uniform GJ [N m^2/rad]")
        p.add_argument("--ea", type=chord_fraction("--ea"), help="uniform elastic axis [chord fraction]")
        p.add_argument("--cg", type=chord_fraction("--cg"), help="uniform centre of gravity [chord fraction]")


def flight_args(p):
    g = p.add_mutually_exclusive_group()
    g.add_argument("--mu", type=number("--mu", 0.0, 0.5), help="advance ratio of the trimmed state [-]")
    g.add_argument("--airspeed", type=number("--airspeed", 0.0, 80.0), help="horizontal airspeed [m/s]")
    p.add_argument("--fidelity", choices=FIDELITIES, default="rigid")
    rigid_spring_arg(p)
    p.add_argument("--elements", type=number("--elements", 1, 60, integer=True), default=10,
                   help="FEM elements per blade")


def rigid_spring_arg(p):
    """``--rigid-spring frequency|static`` (:attr:`amra_core.flight.SolverSettings.rigid_spring`)."""
    p.add_argument("--rigid-spring", choices=TORSION_SPRINGS, default="frequency",
                   help="the rigid level's root torsion spring: frequency ((pi/2)^2 GJ/L, the cantilever's first torsion frequency; default) or static (the same load-weighted twist under an r^2 moment, about 1.6x softer)")


def column_case_args(p):
    """The arguments a map column's case shares (``amra boundary``, ``amra sensitivity``): the rotor
    (``--preset`` or ``--rotor``), ``--fidelity``, ``--rigid-spring``, ``--aero``, ``--mu``, ``--ea``."""
    g = p.add_mutually_exclusive_group()
    g.add_argument("--preset", help="shipped rotor preset (default paper-boundary)")
    g.add_argument("--rotor", metavar="FILE", help="a rotor TOML file of your own")
    p.add_argument("--fidelity", choices=FIDELITIES, default="rigid")
    rigid_spring_arg(p)
    p.add_argument("--aero", choices=AERO_MODELS, default="theodorsen")
    p.add_argument("--mu", type=number("--mu", 0.0, 0.5), default=0.0, help="advance ratio [-] (0 = axial)")
    p.add_argument("--ea", type=chord_fraction("--ea"), default=0.32, help="elastic axis [chord fraction]")


def load_rotor(args):
    from ..rotor_io import load_preset, load_rotor_file
    rotor = (load_rotor_file(args.rotor) if args.rotor is not None
             else load_preset("mccutcheon" if args.preset is None else args.preset))
    if hasattr(args, "gj"):
        rotor = rotor.with_overrides(gj_nm2=args.gj, x_ea=args.ea, x_cg=args.cg)
    return rotor


def flight(args, omega_hold=None):
    mu = getattr(args, "mu", None)
    airspeed = getattr(args, "airspeed", None) or 0.0
    return FlightCondition(airspeed_m_s=airspeed, mu=mu if mu else None, omega_hold_rad_s=omega_hold)


def emit(obj, as_json):
    if as_json:
        print(dumps_strict(obj))
    else:
        for k, v in obj.items():
            if isinstance(v, float):
                v = f"{v:.6g}"
            print(f"{k:28s} {v}")


def value_range(name, lo, hi, with_count):
    """Parser of ``A:B`` (or ``A:B:N`` with ``with_count``, where one value ``A`` means ``A:A:1``)
    with both ends in [lo, hi]."""
    form = "A:B:N (or one value A)" if with_count else "A:B"

    def parse(text):
        parts = text.split(":")
        if with_count and len(parts) == 1:  # one column, as a user checking one cell writes it
            parts = [parts[0], parts[0], "1"]
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


def strict(obj):
    """A JSON-safe copy of ``obj``: numpy scalars and arrays to Python, non-finite floats to None."""
    import numpy as np
    if isinstance(obj, bool) or obj is None or isinstance(obj, (str, int)):
        return obj
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {str(k) if not isinstance(k, str) else k: strict(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [strict(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return strict(obj.tolist())
    if isinstance(obj, (np.floating, np.integer, np.bool_)):
        return strict(obj.item())
    if hasattr(obj, "to_dict"):
        return strict(obj.to_dict())
    raise TypeError(f"{type(obj).__name__} is not JSON serialisable")


def dumps_strict(obj, indent=2) -> str:
    """Strict JSON (RFC 8259): every non-finite number is written as ``null``."""
    return json.dumps(strict(obj), indent=indent, allow_nan=False)


# ----------------------------------------------------------------------------- output paths
_NOT_REGULAR = {stat.S_IFDIR: "a directory", stat.S_IFIFO: "a FIFO (named pipe)", stat.S_IFCHR: "a device",
                stat.S_IFBLK: "a device", stat.S_IFSOCK: "a socket"}


def _writable_dir(flag, path, folder) -> None:
    try:
        st = os.stat(folder)
    except FileNotFoundError:
        raise UsageError(f"{flag} {path!r} cannot be written: the folder {folder!r} does not exist") from None
    except OSError as exc:
        raise UsageError(f"{flag} {path!r} cannot be written: the folder {folder!r}: {exc.strerror}") from None
    if not stat.S_ISDIR(st.st_mode):
        raise UsageError(f"{flag} {path!r} cannot be written: {folder!r} is not a folder")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise UsageError(f"{flag} {path!r} cannot be written: the folder {folder!r} is read-only or not writable "
                         f"by this user")


def check_output_file(flag: str, path: str) -> None:
    """Raise :class:`UsageError` unless ``path`` can be written as a regular file: it must not be
    a directory, FIFO, device or socket (``/dev/full``), its folder must exist and be writable."""
    if not path or "\x00" in path:
        raise UsageError(f"{flag} {path!r} is not allowed: not a usable file name")
    try:
        st = os.stat(path)
    except FileNotFoundError:
        if os.path.lexists(path):
            raise UsageError(f"{flag} {path!r} is not allowed: a dangling symbolic link") from None
        st = None
    except OSError as exc:
        why = "a symbolic link loop" if exc.errno == errno.ELOOP else exc.strerror
        raise UsageError(f"{flag} {path!r} cannot be written: {why}") from None
    if st is not None:
        if not stat.S_ISREG(st.st_mode):
            kind = _NOT_REGULAR.get(stat.S_IFMT(st.st_mode), "not a regular file")
            raise UsageError(f"{flag} {path!r} is not allowed: it is {kind}; give a file name")
        if not os.access(path, os.W_OK):
            raise UsageError(f"{flag} {path!r} cannot be written: the file is read-only or not writable by this user")
    if len(os.path.basename(path).encode()) > 255:
        raise UsageError(f"{flag} {path!r} is not allowed: the file name is longer than 255 bytes")
    _writable_dir(flag, path, os.path.dirname(os.path.abspath(path)))


def check_output_dir(flag: str, path: str) -> None:
    """Raise :class:`UsageError` unless ``path`` is a writable folder or can be created as one
    (its parent exists and is writable)."""
    if not path or "\x00" in path:
        raise UsageError(f"{flag} {path!r} is not allowed: not a usable folder name")
    try:
        st = os.stat(path)
    except FileNotFoundError:
        if os.path.lexists(path):
            raise UsageError(f"{flag} {path!r} is not allowed: a dangling symbolic link") from None
        if len(os.path.basename(os.path.normpath(path)).encode()) > 255:
            raise UsageError(f"{flag} {path!r} is not allowed: the folder name is longer than 255 bytes")
        _writable_dir(flag, path, os.path.dirname(os.path.abspath(path)))
        return
    except OSError as exc:
        why = "a symbolic link loop" if exc.errno == errno.ELOOP else exc.strerror
        raise UsageError(f"{flag} {path!r} cannot be written: {why}") from None
    if not stat.S_ISDIR(st.st_mode):
        kind = _NOT_REGULAR.get(stat.S_IFMT(st.st_mode), "a file")
        raise UsageError(f"{flag} {path!r} is not allowed: it is {kind}, not a folder")
    if not os.access(path, os.W_OK | os.X_OK):
        raise UsageError(f"{flag} {path!r} cannot be written: the folder is read-only or not writable by this user")


#: output arguments per sub-command: (attribute, flag, "file" | "dir")
OUTPUT_ARGS = {"validate": (("out", "--out", "dir"),)}
_DEFAULT_OUTPUTS = (("out", "--out", "file"), ("plot", "--plot", "file"))


def check_outputs(args) -> None:
    """Check every output path of the parsed ``args`` before the command does any work."""
    for attr, flag, kind in OUTPUT_ARGS.get(getattr(args, "command", ""), _DEFAULT_OUTPUTS):
        path = getattr(args, attr, None)
        if path is None:
            continue
        (check_output_dir if kind == "dir" else check_output_file)(flag, path)
