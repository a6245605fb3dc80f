"""Browser tests: Playwright drives Debian's headless Chromium (/usr/bin/chromium).

``playwright install`` cannot download its own browser builds on our machines, so
the launch is pointed at the system Chromium (``scripts/test.sh`` apt-installs it).
"""

from __future__ import annotations

import socket
import time
import urllib.request
from pathlib import Path

import pytest

CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--no-first-run",
    "--disable-sync",
]


def pytest_collection_modifyitems(config, items):
    here = Path(__file__).parent
    for item in items:
        if here in Path(str(item.fspath)).parents:
            item.add_marker(pytest.mark.browser)


@pytest.fixture(scope="session")
def browser_type_launch_args(browser_type_launch_args):
    if not CHROMIUM.exists():
        pytest.fail(f"{CHROMIUM} is missing: run scripts/test.sh (it apt-installs chromium)")
    return {
        **browser_type_launch_args,
        "executable_path": str(CHROMIUM),
        "args": [*browser_type_launch_args.get("args", []), *CHROMIUM_ARGS],
    }


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def _wait_for_http(url: str, timeout: float = 30.0) -> None:
    deadline = time.monotonic() + timeout
    while True:
        try:
            with urllib.request.urlopen(url, timeout=5) as response:
                if response.status == 200:
                    return
        except OSError:
            pass
        if time.monotonic() > deadline:
            raise TimeoutError(f"dashboard did not answer at {url} within {timeout} s")
        time.sleep(0.2)


@pytest.fixture
def dashboard_url():
    """Serve ``app.main.create_app`` on a free loopback port; yield its URL."""
    import panel as pn

    from app.main import create_app

    port = _free_port()
    server = pn.serve(
        create_app,
        port=port,
        address="127.0.0.1",
        websocket_origin=f"127.0.0.1:{port}",
        threaded=True,
        show=False,
        verbose=False,
    )
    url = f"http://127.0.0.1:{port}/"
    try:
        _wait_for_http(url)
        yield url
    finally:
        server.stop()
        server.join(timeout=30)
