"""Fixtures of the team-server tests (helpers: ``server_helpers.py``). Every server a test starts
runs in its own process group and is stopped, group and all, when the test ends."""
from __future__ import annotations

import sys

import pytest

from server_helpers import CHROMIUM, REPO, free_port, start_amra_serve


@pytest.fixture
def amra_server(tmp_path):
    """Factory: ``amra_server(*serve_args, env_extra=...) -> (url_base, ServerProcess)``; all
    servers started are stopped at the end of the test."""
    started = []

    def start(*args, env_extra=None, port=None):
        port = port or free_port()
        srv = start_amra_serve(tmp_path, port, *args, env_extra=env_extra)
        started.append(srv)
        return f"http://127.0.0.1:{port}", srv

    yield start
    for srv in started:
        srv.stop()


@pytest.fixture(scope="session")
def chromium_args():
    if not CHROMIUM.exists():
        pytest.fail(f"{CHROMIUM} is missing: run scripts/test.sh (it apt-installs chromium)")
    sys.path.insert(0, str(REPO / "scripts"))
    from load_test import CHROMIUM_ARGS
    return {"executable_path": str(CHROMIUM), "args": list(CHROMIUM_ARGS), "headless": True}


