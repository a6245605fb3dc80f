"""Fixtures for dashboard tests that run without a browser."""

from __future__ import annotations

import pytest

pn = pytest.importorskip("panel")


@pytest.fixture(autouse=True)
def _reset_panel_state():
    """Panel keeps process-wide state (caches, sessions); clear it after each test."""
    yield
    pn.state.reset()
