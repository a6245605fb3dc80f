"""Server-level settings of the dashboard, read from the environment (set by ``amra serve``).

``AMRA_STORE``: SQLite store of map cells [path] (default ``~/.cache/amra/cells.sqlite``);
``AMRA_MAP_WORKERS``: processes for map cells (default 1: cells run in the map's own thread);
``AMRA_DASK_SCHEDULER``: optional dask.distributed scheduler address for map cells;
``AMRA_MAX_RUN_S``: per-session cap on the simulated run length [s] (default 120).
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping, Optional


class SettingsError(ValueError):
    """An environment variable has a value the dashboard cannot use; the message names it."""


def default_store_path() -> Path:
    return Path.home() / ".cache" / "amra" / "cells.sqlite"


@dataclass(frozen=True)
class ServerSettings:
    """Validated server settings (see the module docstring for the variables and units)."""

    store_path: Path
    map_workers: int = 1
    dask_scheduler: Optional[str] = None
    max_run_s: float = 120.0

    @classmethod
    def from_env(cls, env: Optional[Mapping[str, str]] = None) -> "ServerSettings":
        env = os.environ if env is None else env
        store = env.get("AMRA_STORE") or str(default_store_path())
        try:
            workers = int(env.get("AMRA_MAP_WORKERS", "1"))
        except ValueError:
            raise SettingsError(f"AMRA_MAP_WORKERS = {env.get('AMRA_MAP_WORKERS')!r} is not allowed: "
                                f"must be an integer >= 1") from None
        if workers < 1:
            raise SettingsError(f"AMRA_MAP_WORKERS = {workers} is not allowed: must be an integer >= 1")
        try:
            max_run = float(env.get("AMRA_MAX_RUN_S", "120"))
        except ValueError:
            raise SettingsError(f"AMRA_MAX_RUN_S = {env.get('AMRA_MAX_RUN_S')!r} is not allowed: "
                                f"must be a number of seconds in [1, 3600]") from None
        if not 1.0 <= max_run <= 3600.0:
            raise SettingsError(f"AMRA_MAX_RUN_S = {max_run:g} is out of range: allowed [1, 3600] s")
        return cls(Path(store).expanduser(), workers, env.get("AMRA_DASK_SCHEDULER") or None, max_run)
