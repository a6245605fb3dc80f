"""Server-level settings of the dashboard, read from the environment (set by ``amra serve``).

``AMRA_STORE``: SQLite store of map cells [path] (default ``~/.cache/amra/cells.sqlite``);
``AMRA_MAP_WORKERS``: processes for map cells (default 1), kept between maps;
``AMRA_DASK_SCHEDULER``: optional dask.distributed scheduler address for map cells;
``AMRA_MAX_RUN_S``: per-session cap on the simulated run length [s] (default 120).
"""
from __future__ import annotations

import math
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

        def number(key: str, default: str, cast, lo: float, hi: float, allowed: str):
            raw = env.get(key, default)
            try:
                value = cast(raw)
            except ValueError:
                value = math.nan
            if not lo <= value <= hi:
                raise SettingsError(f"{key} = {raw!r} is not allowed: must be {allowed}")
            return value
        store = env.get("AMRA_STORE") or str(default_store_path())
        return cls(Path(store).expanduser(), number("AMRA_MAP_WORKERS", "1", int, 1, math.inf, "an integer >= 1"),
                   env.get("AMRA_DASK_SCHEDULER") or None,
                   number("AMRA_MAX_RUN_S", "120", float, 1.0, 3600.0, "a number of seconds in [1, 3600]"))
