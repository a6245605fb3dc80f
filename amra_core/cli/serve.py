"""``amra serve``: start the dashboard (``panel serve app/main.py``)."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from .common import number


def cmd_serve(args):
    main = Path(__file__).resolve().parents[2] / "app" / "main.py"
    return subprocess.call([sys.executable, "-m", "panel", "serve", str(main), "--port", str(args.port),
                            "--address", args.address, "--num-threads", "0"])


def register(sub) -> None:
    p = sub.add_parser("serve", help="start the dashboard")
    p.add_argument("--port", type=number("--port", 1, 65535, integer=True), default=5006)
    p.add_argument("--address", default="127.0.0.1")
    p.set_defaults(func=cmd_serve)
