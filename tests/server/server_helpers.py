"""Helpers of the team-server tests: start ``amra serve`` (or anything) as a real process in its
own process group and always stop the whole group; HTTP probes.

The long tests are marked ``slow``. The image tests need root and the Debian packages ``buildah``
and ``debootstrap`` (scripts/test.sh).
"""
from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
CHROMIUM = Path("/usr/bin/chromium")


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def http_get(url: str, timeout: float = 10.0, headers=None):
    """``(status, body bytes, headers)``; redirects are not followed."""
    class NoRedirect(urllib.request.HTTPRedirectHandler):
        def redirect_request(self, *a, **k):
            return None
    opener = urllib.request.build_opener(NoRedirect)
    req = urllib.request.Request(url, headers=headers or {})
    try:
        with opener.open(req, timeout=timeout) as r:
            return r.status, r.read(), dict(r.headers)
    except urllib.error.HTTPError as e:
        return e.code, e.read(), dict(e.headers)


def wait_for_http(url: str, timeout: float, proc=None) -> None:
    deadline = time.monotonic() + timeout
    while True:
        if proc is not None and proc.poll() is not None:
            raise RuntimeError(f"server exited with code {proc.returncode} before answering {url}")
        try:
            status, _, _ = http_get(url, timeout=5)
            if status == 200:
                return
        except OSError:
            pass
        if time.monotonic() > deadline:
            raise TimeoutError(f"no answer at {url} within {timeout} s")
        time.sleep(0.3)


class ServerProcess:
    """A process (group) started with ``argv``; ``stop()`` ends the whole group."""

    def __init__(self, argv, env=None, log: Path = None, cwd=REPO):
        self.log_path = log
        self._log = open(log, "ab") if log else subprocess.DEVNULL
        self.proc = subprocess.Popen(argv, env=env, cwd=cwd, stdout=self._log, stderr=subprocess.STDOUT,
                                     start_new_session=True)

    @property
    def pid(self) -> int:
        return self.proc.pid

    def kill(self, sig=signal.SIGKILL) -> None:
        try:
            os.killpg(self.proc.pid, sig)
        except ProcessLookupError:
            pass

    def stop(self, timeout: float = 20.0) -> None:
        if self.proc.poll() is None:
            self.kill(signal.SIGTERM)
            try:
                self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                pass
        self.kill(signal.SIGKILL)  # stragglers of the group (workers)
        try:
            self.proc.wait(5)
        except subprocess.TimeoutExpired:
            pass
        if self._log is not subprocess.DEVNULL:
            self._log.close()

    def log_text(self) -> str:
        return self.log_path.read_text(errors="replace") if self.log_path else ""


def start_amra_serve(tmp_path: Path, port: int, *args, env_extra=None, timeout: float = 120.0) -> ServerProcess:
    """``python -m amra_core.cli serve`` on 127.0.0.1:``port`` with its store in ``tmp_path``;
    waits until ``/liveness`` answers."""
    env = dict(os.environ)
    env.setdefault("AMRA_STORE", str(tmp_path / "store.sqlite"))
    env.update(env_extra or {})
    srv = ServerProcess([sys.executable, "-m", "amra_core.cli", "serve", "--address", "127.0.0.1",
                         "--port", str(port), *args], env=env, log=tmp_path / f"serve-{port}.log")
    try:
        wait_for_http(f"http://127.0.0.1:{port}{_prefix(args, env)}/liveness", timeout, srv.proc)
    except Exception:
        log = srv.log_text()
        srv.stop()
        raise RuntimeError(f"amra serve did not start:\n{log[-3000:]}")
    return srv


def _prefix(args, env) -> str:
    args = list(args)
    p = args[args.index("--prefix") + 1] if "--prefix" in args else env.get("AMRA_PREFIX", "")
    p = p.strip("/")
    return f"/{p}" if p else ""




def json_get(url: str):
    status, body, _ = http_get(url)
    return status, json.loads(body) if body else None
