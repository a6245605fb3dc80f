"""SQLite store of finished map cells, keyed by the case key (all parameters + solver version).

One table ``cells(key, params, result, solver, created)``; ``params`` and ``result`` are JSON. The file
is opened in WAL mode with a busy timeout, each write is its own short ``INSERT OR REPLACE``
transaction, so several processes can read and write one store at once without losing rows.

The file is ours when its SQLite ``application_id`` is :data:`APPLICATION_ID` and its
``user_version`` is :data:`SCHEMA_VERSION`. A file that is not SQLite, is damaged, or is SQLite of
some other program (or of another schema) is never modified and never crashes the caller: it is
renamed aside to ``<name>.corrupt-<UTC timestamp>`` (or ``.foreign-``), a :class:`StoreWarning`
says so (also kept in :attr:`CellStore.notice`), and a fresh store is created in its place.
"""
from __future__ import annotations

import json
import math
import os
import sqlite3
import threading
import time
import warnings
from pathlib import Path
from typing import Optional

APPLICATION_ID = 0x414D5241  #: "AMRA"
SCHEMA_VERSION = 1
BUSY_TIMEOUT_MS = 60_000


class StoreWarning(UserWarning):
    """The store file could not be used as it was (set aside, a fresh one created)."""


def _clean(obj):
    """JSON-safe copy: non-finite floats become None."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if hasattr(obj, "item") and callable(obj.item):  # numpy scalar
        return _clean(obj.item())
    return obj


class CellStore:
    """Finished cells in the SQLite file ``path``: ``get(key) -> dict | None``,
    ``put(key, params, result)`` (``params``, ``result``: JSON-able dicts, or objects with
    ``to_dict()``). Thread-safe within a process; safe across processes."""

    def __init__(self, path, solver: str = ""):
        self.path = Path(path)
        self.solver = solver
        self.notice = ""
        self._lock = threading.Lock()
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._conn = self._open()

    # ------------------------------------------------------------------ opening
    def _connect(self) -> sqlite3.Connection:
        conn = sqlite3.connect(str(self.path), timeout=BUSY_TIMEOUT_MS / 1000, isolation_level=None,
                               check_same_thread=False)
        conn.execute(f"PRAGMA busy_timeout = {BUSY_TIMEOUT_MS}")
        return conn

    def _problem(self, conn: sqlite3.Connection) -> Optional[tuple[str, str]]:
        """None if the file is ours (or new and empty), else (kind, description)."""
        try:
            app_id = conn.execute("PRAGMA application_id").fetchone()[0]
            version = conn.execute("PRAGMA user_version").fetchone()[0]
            n_objects = conn.execute("SELECT count(*) FROM sqlite_master").fetchone()[0]
        except sqlite3.DatabaseError as exc:
            return "corrupt", f"not a readable SQLite database ({exc})"
        if app_id == 0 and version == 0 and n_objects == 0:
            return None  # new (or empty) file: ours to initialise
        if app_id != APPLICATION_ID:
            return "foreign", f"an SQLite database of another program (application_id {app_id:#x})"
        if version != SCHEMA_VERSION:
            return "foreign", f"an AMRA store of schema {version}, this version reads schema {SCHEMA_VERSION}"
        try:
            ok = conn.execute("PRAGMA quick_check").fetchone()[0]
        except sqlite3.DatabaseError as exc:
            return "corrupt", f"a damaged SQLite database ({exc})"
        if ok != "ok":
            return "corrupt", f"a damaged SQLite database (quick_check: {ok})"
        return None

    def _set_aside(self, kind: str, why: str) -> None:
        stamp = time.strftime("%Y%m%dT%H%M%SZ", time.gmtime())
        aside = self.path.with_name(f"{self.path.name}.{kind}-{stamp}")
        n = 1
        while aside.exists():
            aside = self.path.with_name(f"{self.path.name}.{kind}-{stamp}-{n}")
            n += 1
        try:
            os.replace(self.path, aside)
        except FileNotFoundError:  # another process set it aside first
            pass
        for suffix in ("-wal", "-shm"):
            side = Path(str(self.path) + suffix)
            if side.exists():
                try:
                    os.replace(side, Path(str(aside) + suffix))
                except OSError:
                    pass
        self.notice = (f"result store {str(self.path)!r} is {why}; it was set aside as {aside.name!r} "
                       f"and a fresh store was created")
        warnings.warn(self.notice, StoreWarning, stacklevel=4)

    def _open(self) -> sqlite3.Connection:
        conn = self._connect()
        problem = self._problem(conn)
        if problem is not None:
            conn.close()
            self._set_aside(*problem)
            conn = self._connect()
        try:
            self._init_schema(conn)
        except sqlite3.DatabaseError as exc:  # e.g. damaged pages found only while writing
            conn.close()
            self._set_aside("corrupt", f"not usable ({exc})")
            conn = self._connect()
            self._init_schema(conn)
        return conn

    @staticmethod
    def _init_schema(conn: sqlite3.Connection) -> None:
        conn.execute("PRAGMA journal_mode = WAL")
        conn.execute("PRAGMA synchronous = NORMAL")
        conn.execute("BEGIN IMMEDIATE")
        try:
            conn.execute("CREATE TABLE IF NOT EXISTS cells (key TEXT PRIMARY KEY, params TEXT NOT NULL, "
                         "result TEXT NOT NULL, solver TEXT NOT NULL, created REAL NOT NULL)")
            conn.execute(f"PRAGMA application_id = {APPLICATION_ID}")
            conn.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
            conn.execute("COMMIT")
        except BaseException:
            conn.execute("ROLLBACK")
            raise

    # ------------------------------------------------------------------ access
    def get(self, key: str) -> Optional[dict]:
        """The stored result dict for ``key``, or None."""
        with self._lock:
            row = self._conn.execute("SELECT result FROM cells WHERE key = ?", (key,)).fetchone()
        return None if row is None else json.loads(row[0])

    def get_many(self, keys) -> dict:
        """``{key: result}`` for those of ``keys`` that are stored."""
        keys = list(keys)
        out = {}
        with self._lock:
            for i in range(0, len(keys), 500):
                chunk = keys[i:i + 500]
                q = f"SELECT key, result FROM cells WHERE key IN ({','.join('?' * len(chunk))})"
                for k, r in self._conn.execute(q, chunk):
                    out[k] = json.loads(r)
        return out

    def put(self, key: str, params, result) -> None:
        """Store ``result`` for ``key`` (replacing an earlier one) with the case ``params``."""
        p = params.to_dict() if hasattr(params, "to_dict") else params
        r = result.to_dict() if hasattr(result, "to_dict") else result
        row = (key, json.dumps(_clean(p), sort_keys=True), json.dumps(_clean(r), sort_keys=True),
               self.solver, time.time())
        with self._lock:
            self._conn.execute("INSERT OR REPLACE INTO cells (key, params, result, solver, created) "
                               "VALUES (?, ?, ?, ?, ?)", row)

    def __contains__(self, key: str) -> bool:
        return self.get(key) is not None

    def __len__(self) -> int:
        with self._lock:
            return self._conn.execute("SELECT count(*) FROM cells").fetchone()[0]

    def keys(self) -> list[str]:
        with self._lock:
            return [k for (k,) in self._conn.execute("SELECT key FROM cells ORDER BY key")]

    def close(self) -> None:
        with self._lock:
            self._conn.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False
