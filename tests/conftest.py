"""Shared pytest configuration for the whole AMRA suite.

Kept deliberately small: solver-specific fixtures live in ``tests/core/``,
dashboard ones in ``tests/app/`` and browser ones in ``tests/browser/``.
"""

from __future__ import annotations

from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="session")
def repo_root() -> Path:
    """Absolute path of the repository checkout (where ``assets/`` lives)."""
    return REPO_ROOT
