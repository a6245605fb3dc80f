"""``amra`` command line: one module per sub-command, shared argument helpers in :mod:`.common`.

Bad input exits with code 2 and a one-line message naming the parameter and its allowed range;
never a traceback. Output paths are checked before any work starts. ``--json`` output is strict
JSON: a number that is not finite is written as ``null``. Long runs show progress on stderr when it is a terminal.
"""
from __future__ import annotations

import argparse
import sys

from .. import __version__
from ..flight import SettingsError
from ..rotor import RotorError
from . import bench, boundary, modes, rotor, sensitivity, serve, simulate, stability, trim, validate
from .common import UsageError, check_outputs

COMMANDS = (rotor, modes, trim, simulate, stability, bench, serve, boundary, sensitivity, validate)


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="amra", description="Aeroelastic model of a rotor in autorotation")
    ap.add_argument("--version", action="version", version=f"amra {__version__}")
    sub = ap.add_subparsers(dest="command", required=True)
    for command in COMMANDS:
        command.register(_Commands(sub))
    return ap


class _Commands:
    """The sub-command registry handed to each module's ``register``: a command without its own
    ``description`` gets its one-line ``help`` as one (``amra validate --help`` had none)."""

    def __init__(self, sub):
        self._sub = sub

    def add_parser(self, name: str, **kw) -> argparse.ArgumentParser:
        text = kw.get("help") or ""
        if text and not kw.get("description"):
            kw["description"] = text[:1].upper() + text[1:].rstrip(".") + "."
        return self._sub.add_parser(name, **kw)


def main(argv=None) -> int:
    ap = build_parser()
    args = ap.parse_args(argv)
    try:
        check_outputs(args)  # --out/--plot/report folders: before any work, not after it
        rc = args.func(args)
    except (RotorError, SettingsError, UsageError, ValueError) as exc:
        print(f"amra {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    return rc or 0
