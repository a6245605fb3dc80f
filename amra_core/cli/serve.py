"""``amra serve``: run the dashboard as a (team) server: ``python -m panel serve app/main.py
--setup app/warmup.py ...``.

Every option can also be set by an environment variable (the flag wins over the variable, the
variable over the default); a bad value, from either, exits 2 with a message naming it:

=============================  ================================  =======================================
flag                           variable                          default
=============================  ================================  =======================================
``--port``                     ``AMRA_PORT``                     5006
``--address``                  ``AMRA_ADDRESS``                  127.0.0.1
``--store FILE``               ``AMRA_STORE``                    ``$XDG_DATA_HOME/amra/amra-store.sqlite``
``--num-procs N``              ``AMRA_NUM_PROCS``                1 (0: one per core)
``--num-threads N``            ``AMRA_NUM_THREADS``              none (callbacks on the event loop)
``--allow-websocket-origin``   ``AMRA_ALLOW_WEBSOCKET_ORIGIN``   address:port, localhost:port, 127.0.0.1:port
``--liveness/--no-liveness``   ``AMRA_LIVENESS`` (1/0)           on (``/liveness``)
``--prefix P``                 ``AMRA_PREFIX``                   none
``--basic-auth FILE``          ``AMRA_BASIC_AUTH``               none
``--cookie-secret S``          ``AMRA_COOKIE_SECRET``            random per start (basic auth only)
``--map-workers N``            ``AMRA_MAP_WORKERS``              1 (processes for map cells, kept between maps)
``--dask-scheduler ADDR``      ``AMRA_DASK_SCHEDULER``           none (local processes)
``--max-run-s S``              ``AMRA_MAX_RUN_S``                120 (per-session cap on run length)
``--max-message-bytes B``      ``AMRA_MAX_MESSAGE_BYTES``        4 MiB (largest websocket message in)
``--admin``                    ``AMRA_ADMIN`` (1/0)              off (``/admin`` shows every session)
``--use-xheaders``             ``AMRA_USE_XHEADERS`` (1/0)       off (behind a TLS proxy: on)
``--log-level``                ``AMRA_LOG_LEVEL``                info
=============================  ================================  =======================================

``AMRA_ALLOW_WEBSOCKET_ORIGIN`` takes several ``HOST[:PORT]`` separated by commas or spaces. ``*``
is never a default; given explicitly it is accepted with a warning. OAuth is Panel's own: set
``PANEL_OAUTH_PROVIDER``, ``PANEL_OAUTH_KEY``, ``PANEL_OAUTH_SECRET``, ``PANEL_OAUTH_REDIRECT_URI``,
``PANEL_OAUTH_ENCRYPTION`` and ``PANEL_COOKIE_SECRET`` (they pass through to Panel unchanged).
The basic-auth file is JSON, ``{"user": "password", ...}`` (a password is never taken on the
command line, where ``ps`` shows it). Secrets reach Panel through its environment, not its argv.

The app reads its settings from the environment of the server process: ``AMRA_STORE``,
``AMRA_MAP_WORKERS``, ``AMRA_DASK_SCHEDULER``, ``AMRA_MAX_RUN_S``.
"""
from __future__ import annotations

import json
import os
import re
import secrets
import sys
from pathlib import Path
from typing import Mapping, Optional

from .common import UsageError

APP_DIR = Path(__file__).resolve().parents[2] / "app"
_TRUE = {"1", "true", "yes", "on"}
_FALSE = {"0", "false", "no", "off", ""}
_HOST_PORT = re.compile(r"^(\*|[A-Za-z0-9]([A-Za-z0-9.-]*[A-Za-z0-9])?|\[[0-9a-fA-F:]+\])(:\d{1,5})?$")
_LOG_LEVELS = ("trace", "debug", "info", "warning", "error", "critical")


def default_store() -> Path:
    base = os.environ.get("XDG_DATA_HOME") or str(Path.home() / ".local" / "share")
    return Path(base) / "amra" / "amra-store.sqlite"


# ---------------------------------------------------------------------------- value checks
def _int(name, text, lo, hi):
    try:
        v = int(str(text).strip())
    except ValueError:
        raise UsageError(f"{name} = {text!r} is not an integer: allowed [{lo}, {hi}]") from None
    if not lo <= v <= hi:
        raise UsageError(f"{name} = {v} is out of range: allowed [{lo}, {hi}]")
    return v


def _float(name, text, lo, hi):
    try:
        v = float(str(text).strip())
    except ValueError:
        raise UsageError(f"{name} = {text!r} is not a number: allowed [{lo}, {hi}]") from None
    if not lo <= v <= hi:  # also refuses nan
        raise UsageError(f"{name} = {text} is out of range: allowed [{lo}, {hi}]")
    return v


def _bool(name, text):
    t = str(text).strip().lower()
    if t in _TRUE:
        return True
    if t in _FALSE:
        return False
    raise UsageError(f"{name} = {text!r} is not allowed: give 1 or 0")


def _origins(name, text):
    out = []
    for item in re.split(r"[,\s]+", str(text).strip()):
        if not item:
            continue
        if not _HOST_PORT.match(item) or (":" in item and not item.endswith("]")
                                          and not 1 <= int(item.rsplit(":", 1)[1]) <= 65535):
            raise UsageError(f"{name}: {item!r} is not allowed: give HOST[:PORT] (no scheme, no path)")
        out.append(item)
    return out


def _prefix(name, text):
    p = str(text).strip().strip("/")
    if p and (not re.fullmatch(r"[A-Za-z0-9._~-]+(/[A-Za-z0-9._~-]+)*", p)
              or any(seg in (".", "..") for seg in p.split("/"))):
        raise UsageError(f"{name} = {text!r} is not allowed: URL path segments of letters, digits, . _ ~ -")
    return f"/{p}" if p else ""


def _basic_auth_file(name, text):
    path = Path(text).expanduser()
    try:
        users = json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise UsageError(f"{name} = {text!r}: cannot read it ({exc.strerror})") from None
    except ValueError:
        raise UsageError(f"{name} = {text!r} is not JSON: give a file {{\"user\": \"password\", ...}}") from None
    if (not isinstance(users, dict) or not users
            or not all(isinstance(k, str) and k and isinstance(v, str) and v for k, v in users.items())):
        raise UsageError(f"{name} = {text!r}: must hold a non-empty JSON object {{\"user\": \"password\", ...}}")
    return str(path.resolve())


def _scheduler(name, text):
    t = str(text).strip()
    if t and not re.fullmatch(r"(tcp|tls|inproc|ucx)://[^\s/]+", t):
        raise UsageError(f"{name} = {text!r} is not allowed: give a scheduler address like tcp://host:8786")
    return t


# ---------------------------------------------------------------------------- settings
_SPECS = {
    # dest: (flag, variable, parse(name, text) -> value, default)
    "port": ("--port", "AMRA_PORT", lambda n, t: _int(n, t, 1, 65535), 5006),
    "address": ("--address", "AMRA_ADDRESS", lambda n, t: str(t).strip() or "127.0.0.1", "127.0.0.1"),
    "store": ("--store", "AMRA_STORE", lambda n, t: str(Path(t).expanduser()), None),
    "num_procs": ("--num-procs", "AMRA_NUM_PROCS", lambda n, t: _int(n, t, 0, 64), 1),
    # default: no thread pool, sessions built and callbacks run on the event loop one at a time (Panel's
    # process-wide resource mode is switched while a page renders: built in parallel threads, pages
    # of concurrent sessions referenced cdn.holoviz.org); the solver runs in its own threads anyway
    "num_threads": ("--num-threads", "AMRA_NUM_THREADS", lambda n, t: _int(n, t, 0, 256), None),
    "origins": ("--allow-websocket-origin", "AMRA_ALLOW_WEBSOCKET_ORIGIN", _origins, None),
    "liveness": ("--liveness", "AMRA_LIVENESS", _bool, True),
    "prefix": ("--prefix", "AMRA_PREFIX", _prefix, ""),
    "basic_auth": ("--basic-auth", "AMRA_BASIC_AUTH", _basic_auth_file, None),
    "cookie_secret": ("--cookie-secret", "AMRA_COOKIE_SECRET", lambda n, t: str(t), None),
    "map_workers": ("--map-workers", "AMRA_MAP_WORKERS", lambda n, t: _int(n, t, 1, 256), None),
    "dask_scheduler": ("--dask-scheduler", "AMRA_DASK_SCHEDULER", _scheduler, ""),
    "max_run_s": ("--max-run-s", "AMRA_MAX_RUN_S", lambda n, t: _float(n, t, 1.0, 3600.0), 120.0),
    "max_message_bytes": ("--max-message-bytes", "AMRA_MAX_MESSAGE_BYTES",
                          lambda n, t: _int(n, t, 64 * 1024, 256 * 1024 * 1024), 4 * 1024 * 1024),
    "admin": ("--admin", "AMRA_ADMIN", _bool, False),
    "use_xheaders": ("--use-xheaders", "AMRA_USE_XHEADERS", _bool, False),
    "log_level": ("--log-level", "AMRA_LOG_LEVEL", lambda n, t: _choice(n, t, _LOG_LEVELS), "info"),
}


def _choice(name, text, choices):
    t = str(text).strip().lower()
    if t not in choices:
        raise UsageError(f"{name} = {text!r} is not allowed: one of {', '.join(choices)}")
    return t


def resolve(args, environ: Mapping[str, str]) -> dict:
    """Settings from the parsed flags, else the environment, else the defaults; each checked."""
    s = {}
    for dest, (flag, var, parse, default) in _SPECS.items():
        given = getattr(args, dest, None)
        if given is not None:
            s[dest] = parse(flag, ",".join(given) if isinstance(given, list) else given) \
                if not isinstance(given, bool) else given
        elif environ.get(var, "").strip() != "" or (dest in ("liveness", "admin", "use_xheaders") and var in environ):
            s[dest] = parse(var, environ[var])
        else:
            s[dest] = default
    if s["store"] is None:
        s["store"] = str(default_store())
    if not s["origins"]:
        s["origins"] = default_origins(s["address"], s["port"])
    return s


def default_origins(address: str, port: int) -> list:
    hosts = ["localhost", "127.0.0.1"]
    if address not in ("0.0.0.0", "::", "", *hosts):
        hosts.insert(0, f"[{address}]" if ":" in address else address)
    return [f"{h}:{port}" for h in hosts]


def url(s: dict) -> str:
    host = s["address"]
    if host in ("0.0.0.0", "::", ""):
        host = "localhost"
    elif ":" in host:
        host = f"[{host}]"
    return f"http://{host}:{s['port']}{s['prefix']}/main"


def build_command(s: dict, environ: Mapping[str, str], python: str = sys.executable) -> tuple[list, dict]:
    """``(argv, env)`` of the ``panel serve`` process for the settings ``s``."""
    main, setup = APP_DIR / "main.py", APP_DIR / "warmup.py"
    # 0 means one per core; given to Panel as 0, its --setup (the warm-up that builds the pools) ran
    # before the fork, in the parent, and the serving processes' Run never started
    procs = s["num_procs"] or os.cpu_count() or 1
    argv = [python, "-m", "panel", "serve", str(main), "--address", s["address"], "--port", str(s["port"]),
            "--num-procs", str(procs),
            "--websocket-max-message-size", str(s["max_message_bytes"]), "--log-level", s["log_level"]]
    if s["num_threads"] is not None:
        argv += ["--num-threads", str(s["num_threads"])]
    if setup.is_file():
        argv += ["--setup", str(setup)]
    report = APP_DIR.parent / "docs" / "validation"
    if report.is_dir():  # the validation report, linked from the page's help
        argv += ["--static-dirs", f"validation={report}"]
    for origin in s["origins"]:
        argv += ["--allow-websocket-origin", origin]
    if s["liveness"]:
        argv += ["--liveness"]
    if s["prefix"]:
        argv += ["--prefix", s["prefix"]]
    if s["admin"]:
        argv += ["--admin"]
    if s["use_xheaders"]:
        argv += ["--use-xheaders"]
    env = dict(environ)
    # ours win over Panel's own spellings of the same setting (Panel refuses both at once)
    env.pop("PANEL_NUM_THREADS", None)
    if s["basic_auth"]:
        if env.get("PANEL_OAUTH_PROVIDER"):
            raise UsageError("--basic-auth and PANEL_OAUTH_PROVIDER are both set: choose one authentication")
        argv += ["--basic-auth", s["basic_auth"]]
        env.pop("PANEL_BASIC_AUTH", None)
    if s["cookie_secret"]:
        env["PANEL_COOKIE_SECRET"] = s["cookie_secret"]
    elif s["basic_auth"] and not env.get("PANEL_COOKIE_SECRET"):
        # logins last until the server restarts; set AMRA_COOKIE_SECRET to keep them (and for
        # several containers behind one proxy)
        env["PANEL_COOKIE_SECRET"] = secrets.token_urlsafe(32)
    env["AMRA_STORE"] = s["store"]
    env["AMRA_MAX_RUN_S"] = repr(s["max_run_s"])
    if s["map_workers"] is not None:
        env["AMRA_MAP_WORKERS"] = str(s["map_workers"])
    if s["dask_scheduler"]:
        env["AMRA_DASK_SCHEDULER"] = s["dask_scheduler"]
    else:
        env.pop("AMRA_DASK_SCHEDULER", None)
    # Page resources (JS, CSS) from this server, never a CDN: the server may be offline, and with
    # concurrent sessions Panel's temporary resource mode (panel.io.resources.set_resource_mode,
    # a process-wide setting) races between threads and falls back to Bokeh's default, the CDN,
    # unless the mode is also set in the environment (measured: every page of 8 concurrent
    # sessions fetched cdn.holoviz.org without it)
    env.setdefault("BOKEH_RESOURCES", "server")
    # Bokeh's own setting for servers: no inspect.signature of every callback a page registers (Panel
    # links ~230 widget properties per page, each a new partial): page build 541 -> 518 ms in-process
    # (scripts/bench_page_build.py's page, alternated, median of 25). A bad callback then fails when
    # called instead of when registered; the in-process app tests keep the check.
    env.setdefault("BOKEH_PERFORM_ERROR_DIAGNOSTICS", "false")
    env["AMRA_LOG_LEVEL"] = s["log_level"]  # the app's own loggers ("amra.*") follow it (app/warmup.py)
    # Numba: only a thread-safe layer (OpenMP from libgomp1, or TBB) when threads share kernels
    env.setdefault("NUMBA_THREADING_LAYER", "safe")
    return argv, env


def _check_store(path: str) -> Optional[str]:
    """A warning if the store cannot be written (the app still serves runs, with a message)."""
    p = Path(path)
    d = p.parent
    try:
        d.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        return f"cannot create the store directory {str(d)!r} ({exc.strerror}): maps will not be kept"
    if not os.access(d, os.W_OK) or (p.exists() and not os.access(p, os.W_OK)):
        return f"the store {path!r} is not writable: maps will be computed but not kept"
    return None


def cmd_serve(args):
    s = resolve(args, os.environ)
    argv, env = build_command(s, os.environ)
    if args.print_command:
        print(json.dumps({"argv": argv, "env": {k: v for k, v in env.items()
                                                if k.startswith(("AMRA_", "NUMBA_", "BOKEH_"))}}, indent=2))
        return 0
    if "*" in s["origins"]:
        print("amra serve: warning: websocket origin '*' accepts pages from any site", file=sys.stderr)
    warn = _check_store(s["store"])
    if warn:
        print(f"amra serve: warning: {warn}", file=sys.stderr)
    auth = "basic auth" if s["basic_auth"] else ("OAuth" if env.get("PANEL_OAUTH_PROVIDER") else "none")
    print(f"amra serve: AMRA dashboard at {url(s)}  (store {s['store']}; authentication {auth}; "
          f"origins {' '.join(s['origins'])})", flush=True)
    sys.stdout.flush()
    sys.stderr.flush()
    # exec, not a child: SIGTERM from `docker stop` (PID 1) reaches the server itself
    os.execve(argv[0], argv, env)


def register(sub) -> None:
    p = sub.add_parser("serve", help="serve the dashboard (team server; every option also from AMRA_* variables)",
                       description="Run the dashboard as a (team) server: python -m panel serve app/main.py --setup "
                                   "app/warmup.py with the options below. Every option can also be set by its AMRA_* "
                                   "variable; the flag wins over the variable, the variable over the default.")
    p.add_argument("--port", help="port [1, 65535] (AMRA_PORT; default 5006)")
    p.add_argument("--address", help="address to listen on (AMRA_ADDRESS; default 127.0.0.1, 0.0.0.0 for all)")
    p.add_argument("--store", metavar="FILE", help="SQLite result store (AMRA_STORE)")
    p.add_argument("--num-procs", metavar="N", help="server processes, 0 = one per core (AMRA_NUM_PROCS; default 1)")
    p.add_argument("--num-threads", metavar="N",
                   help="callback threads per process, 0 = Panel's pool of min(32, cores + 4) (AMRA_NUM_THREADS; "
                        "default: none, callbacks on the event loop)")
    p.add_argument("--allow-websocket-origin", dest="origins", action="append", metavar="HOST[:PORT]",
                   help="page origin allowed to connect, repeatable (AMRA_ALLOW_WEBSOCKET_ORIGIN)")
    p.add_argument("--liveness", dest="liveness", action="store_true", default=None,
                   help="serve /liveness for health checks (AMRA_LIVENESS; default on)")
    p.add_argument("--no-liveness", dest="liveness", action="store_false")
    p.add_argument("--prefix", help="URL prefix, e.g. amra (AMRA_PREFIX)")
    p.add_argument("--basic-auth", metavar="FILE", help='JSON file {"user": "password"} (AMRA_BASIC_AUTH)')
    p.add_argument("--cookie-secret", help="secret signing login cookies (AMRA_COOKIE_SECRET)")
    p.add_argument("--map-workers", metavar="N", help="processes for map cells (AMRA_MAP_WORKERS)")
    p.add_argument("--dask-scheduler", metavar="ADDR", help="dask.distributed scheduler for maps (AMRA_DASK_SCHEDULER)")
    p.add_argument("--max-run-s", metavar="S", help="per-session cap on run length [s] (AMRA_MAX_RUN_S)")
    p.add_argument("--max-message-bytes", metavar="B", help="largest websocket message accepted (AMRA_MAX_MESSAGE_BYTES)")
    p.add_argument("--admin", action="store_true", default=None, help="serve /admin (AMRA_ADMIN)")
    p.add_argument("--use-xheaders", action="store_true", default=None,
                   help="trust X-Forwarded-* headers of a reverse proxy (AMRA_USE_XHEADERS)")
    p.add_argument("--log-level", help=f"one of {', '.join(_LOG_LEVELS)} (AMRA_LOG_LEVEL)")
    p.add_argument("--print-command", action="store_true", help="print the panel command and settings, do not serve")
    p.set_defaults(func=cmd_serve)
