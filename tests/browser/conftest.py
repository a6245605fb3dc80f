"""Browser tests: Playwright drives Debian's headless Chromium (/usr/bin/chromium).

``playwright install`` cannot download its own browser builds on our machines, so
the launch is pointed at the system Chromium (``scripts/test.sh`` apt-installs it).
The dashboard is served in-process with ``pn.serve`` (warmed like ``--setup app/warmup.py``),
with its own temporary SQLite store. Screenshots go to ``test-results/screenshots/``.
"""

from __future__ import annotations

import os
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


@pytest.fixture(scope="session")
def browser_context_args(browser_context_args):
    return {**browser_context_args, "viewport": {"width": 1500, "height": 1000}}


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def _wait_for_http(url: str, timeout: float = 60.0) -> None:
    deadline = time.monotonic() + timeout
    while True:
        try:
            with urllib.request.urlopen(url, timeout=30) as response:
                if response.status == 200:
                    return
        except OSError:
            pass
        if time.monotonic() > deadline:
            raise TimeoutError(f"dashboard did not answer at {url} within {timeout} s")
        time.sleep(0.2)


@pytest.fixture(scope="session")
def dashboard_server(tmp_path_factory):
    """Serve ``app.main.create_app`` on a free loopback port (one server for the session); yield
    ``(url, sessions)`` where ``sessions`` lists the per-session Dashboard objects."""
    import panel as pn

    store = tmp_path_factory.mktemp("store") / "cells.sqlite"
    old = os.environ.get("AMRA_STORE")
    os.environ["AMRA_STORE"] = str(store)
    from app.compute import warm, warm_worker
    from app.main import create_app
    from app.server.map_jobs import get_registry
    from app.server.pool import get_analysis_pool, get_run_pool
    from app.server.settings import ServerSettings

    warm()
    registry = get_registry(ServerSettings.from_env())
    pool = get_analysis_pool()
    run_pool = get_run_pool()
    for p in (pool, run_pool):
        p.submit(warm_worker).result(timeout=300)
    sessions = []

    def app():
        page = create_app()
        sessions.append(page.dashboard)
        return page

    port = _free_port()
    server = pn.serve(app, port=port, address="127.0.0.1", websocket_origin=f"127.0.0.1:{port}",
                      threaded=True, show=False, verbose=False,
                      check_unused_sessions_milliseconds=1000, unused_session_lifetime_milliseconds=5000)
    url = f"http://127.0.0.1:{port}/"
    try:
        _wait_for_http(url)
        yield url, sessions
    finally:
        server.stop()
        server.join(timeout=30)
        registry.close()
        pool.close()
        run_pool.close()
        for key in ("amra-map-registry", "amra-analysis-pool", "amra-run-pool"):
            pn.state.cache.pop((key,), None)  # (pn.state.as_cached's keys)
        if old is None:
            os.environ.pop("AMRA_STORE", None)
        else:
            os.environ["AMRA_STORE"] = old


@pytest.fixture
def dashboard_url(dashboard_server):
    return dashboard_server[0]


@pytest.fixture
def watched_page(page):
    """The Playwright page with its console errors and outside requests recorded."""
    # a page on a starved machine (browsers beside the server and other work on two cores) can take
    # tens of seconds to answer; the tests wait for states, never for a time
    page.set_default_timeout(120_000)
    page.amra_errors = []
    page.amra_outside = []
    page.amra_range_warnings = []  # Bokeh's "could not set initial ranges": a plot drawn with no span
    page.on("console", lambda m: m.type == "error" and page.amra_errors.append(m.text))
    page.on("console", lambda m: "could not set initial ranges" in m.text and page.amra_range_warnings.append(m.text))
    page.on("pageerror", lambda e: page.amra_errors.append(str(e)))

    def on_request(req):
        host = req.url.split("/")[2] if "://" in req.url else ""
        if req.url.startswith(("http://", "https://", "ws://", "wss://")) and not host.startswith(("127.0.0.1", "localhost")):
            page.amra_outside.append(req.url)
    page.on("request", on_request)
    return page


