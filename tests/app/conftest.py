"""Fixtures for dashboard tests that run without a browser."""

from __future__ import annotations

import time

import pytest

pn = pytest.importorskip("panel")


@pytest.fixture(autouse=True)
def _reset_panel_state():
    """Panel keeps process-wide state (caches, sessions); clear it after each test."""
    yield
    reg = pn.state.cache.pop(("amra-map-registry",), (None, None))[0]  # (pn.state.as_cached's key and entry)
    if reg is not None:
        reg.close()
    pn.state.reset()


@pytest.fixture(scope="session")
def analysis_pool():
    """One analysis process for the whole test session (spawning one costs seconds)."""
    from app.server.pool import AnalysisPool
    pool = AnalysisPool()
    yield pool
    pool.close()


@pytest.fixture
def server_settings(tmp_path):
    from app.server.settings import ServerSettings
    return ServerSettings(store_path=tmp_path / "cells.sqlite", map_workers=1, max_run_s=30.0)


@pytest.fixture
def dash(server_settings, analysis_pool):
    """A dashboard without a server (its pool: the session's analysis process), with a small map."""
    from app.app import Dashboard
    from app.server.map_jobs import MapRegistry
    reg = MapRegistry(server_settings)
    d = Dashboard(server_settings, registry=reg, pool=analysis_pool)
    d.controls.param.update(map_columns=2, map_coarse=3)
    yield d
    d.close()
    reg.close()


def wait_until(predicate, timeout_s=30.0, every_s=0.02, what="condition"):
    deadline = time.monotonic() + timeout_s
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")
        time.sleep(every_s)


@pytest.fixture
def wait():
    """``wait(predicate, timeout_s, what=...)``: poll until true, else fail."""
    return wait_until
