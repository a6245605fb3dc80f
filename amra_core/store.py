"""SQLite store of finished map cells, keyed by the case key (all parameters + solver version).

One table ``cells(key, params, result, solver, created, checksum)``; ``params`` and ``result`` are
strict JSON (no NaN/Infinity), ``checksum`` is the SHA-256 of key, params, result and solver. The
file is opened in WAL mode with a busy timeout, each write is its own short ``INSERT OR REPLACE``
transaction, so several processes can read and write one store at once without losing rows.

Safety rules (issue 10):

* The file is ours only when it is an SQLite database whose header carries our
  ``application_id`` (:data:`APPLICATION_ID`), read from the raw header bytes before SQLite opens
  it. Anything else -- a rotor file, another program's database, a directory, a device, a FIFO --
  is **never** opened for writing, moved or overwritten: :class:`StoreError` names the path and the
  reason. An empty or missing file becomes a new store.
* An AMRA store that SQLite reports damaged is set aside to ``<name>.corrupt-<UTC stamp>`` (it is
  ours, and a fresh store is created), with a :class:`StoreWarning`.
* A store that cannot be written (read-only mount, someone else's file, read-only directory) is
  opened read-only and used: cells are read, new ones are not kept (:attr:`CellStore.read_only`,
  :attr:`CellStore.notice`).
* A row whose checksum or JSON does not verify is skipped with a :class:`StoreWarning` (its cell is
  then recomputed and, on a writable store, replaced).
"""
from __future__ import annotations

import errno
import hashlib
import json
import math
import os
import sqlite3
import stat
import threading
import time
import warnings
from pathlib import Path
from typing import Optional

APPLICATION_ID = 0x414D5241  #: "AMRA"
SCHEMA_VERSION = 2  #: 2: rows carry a checksum (1: none; upgraded in place, its rows unverifiable)
BUSY_TIMEOUT_MS = 60_000
_SQLITE_MAGIC = b"SQLite format 3\x00"


class StoreWarning(UserWarning):
    """The store could not be used as it was (set aside, read-only, a damaged row skipped)."""


class StoreError(ValueError):
    """The store path cannot be used; the message names the path and the reason."""


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


def row_checksum(key: str, params: str, result: str, solver: str) -> str:
    h = hashlib.sha256()
    for part in (key, params, result, solver):
        b = part.encode()
        h.update(len(b).to_bytes(8, "little"))
        h.update(b)
    return h.hexdigest()


_KIND = {stat.S_IFDIR: "a directory", stat.S_IFIFO: "a FIFO (named pipe)", stat.S_IFCHR: "a character device",
         stat.S_IFBLK: "a block device", stat.S_IFSOCK: "a socket"}


def _os_reason(exc: OSError) -> str:
    if exc.errno == errno.ELOOP:
        return "a symbolic link loop"
    if exc.errno == errno.ENAMETOOLONG:
        return "a name that is too long for the file system"
    if exc.errno in (errno.EACCES, errno.EPERM):
        return "not accessible (permission denied)"
    if exc.errno == errno.ENOTDIR:
        return "a path through something that is not a folder"
    return exc.strerror or str(exc)


def inspect_store_path(path, _again: bool = True) -> tuple[str, str]:
    """Classify ``path`` without modifying anything: ``(kind, detail)`` with kind ``new`` (missing or
    empty: a store can be created), ``amra`` (an AMRA store; detail: schema version), or raise
    :class:`StoreError` naming the path and why it cannot be used."""
    p = str(path)
    if not p or "\x00" in p:
        raise StoreError(f"--store {p!r} is not allowed: not a usable file name")
    try:
        st = os.stat(p)
    except FileNotFoundError:
        if os.path.islink(p):
            try:
                target = os.readlink(p)
            except OSError:
                target = "?"
            raise StoreError(f"--store {p!r} is not allowed: a dangling symbolic link "
                             f"(it points to {target!r}, which does not exist)") from None
        if _again and os.path.lexists(p):  # another process created the store just now: look again
            return inspect_store_path(path, _again=False)
        parent = os.path.dirname(os.path.abspath(p))
        try:
            pst = os.stat(parent)
        except FileNotFoundError:
            return "new", "missing (the folder will be created)"
        except OSError as exc:
            raise StoreError(f"--store {p!r} is not allowed: its folder is {_os_reason(exc)}") from None
        if not stat.S_ISDIR(pst.st_mode):
            raise StoreError(f"--store {p!r} is not allowed: {parent!r} is not a folder")
        return "new", "missing"
    except OSError as exc:
        raise StoreError(f"--store {p!r} is not allowed: {_os_reason(exc)}") from None
    if not stat.S_ISREG(st.st_mode):
        kind = _KIND.get(stat.S_IFMT(st.st_mode), "not a regular file")
        raise StoreError(f"--store {p!r} is not allowed: it is {kind}, not an AMRA result store")
    if st.st_size == 0:
        return "new", "empty"
    try:
        with open(p, "rb") as f:
            head = f.read(100)
    except OSError as exc:
        raise StoreError(f"--store {p!r} cannot be read: {_os_reason(exc)}") from None
    if not head.startswith(_SQLITE_MAGIC) or len(head) < 72:
        raise StoreError(f"--store {p!r} is not allowed: the file exists and is not an AMRA result store "
                         f"(not an SQLite database); it was left untouched -- choose another path")
    app_id = int.from_bytes(head[68:72], "big")
    version = int.from_bytes(head[60:64], "big")
    if app_id != APPLICATION_ID and os.path.exists(p + "-wal"):
        # page 1 may live in the write-ahead log still (a writer killed before its first checkpoint)
        try:
            conn = sqlite3.connect(f"{Path(p).resolve().as_uri()}?mode=ro", uri=True, timeout=5)
            try:
                app_id = conn.execute("PRAGMA application_id").fetchone()[0]
                version = conn.execute("PRAGMA user_version").fetchone()[0]
            finally:
                conn.close()
        except sqlite3.Error:
            pass
    if app_id != APPLICATION_ID:
        raise StoreError(f"--store {p!r} is not allowed: it is an SQLite database of another program "
                         f"(application_id {app_id:#x}); it was left untouched -- choose another path")
    if version not in (1, SCHEMA_VERSION):
        raise StoreError(f"--store {p!r} is not allowed: an AMRA store of schema {version} (this version "
                         f"reads schema {SCHEMA_VERSION}); it was left untouched -- choose another path")
    return "amra", str(version)


def _writable(p: Path, exists: bool) -> bool:
    """Can we write the store (and its -wal/-shm side files, which live in the same folder)?"""
    d = p.parent if str(p.parent) else Path(".")
    if exists and not os.access(p, os.W_OK):
        return False
    return os.access(d, os.W_OK | os.X_OK)


class CellStore:
    """Finished cells in the SQLite file ``path``: ``get(key) -> dict | None``,
    ``put(key, params, result)`` (``params``, ``result``: JSON-able dicts, or objects with
    ``to_dict()``). Thread-safe within a process; safe across processes. ``read_only=None``: open
    read-only when the file cannot be written; ``True``: always read-only."""

    def __init__(self, path, solver: str = "", read_only: Optional[bool] = None):
        self.path = Path(path)
        self.solver = solver
        self.notice = ""
        self.damaged_rows: list[str] = []
        self._lock = threading.Lock()
        kind, _ = inspect_store_path(self.path)
        exists = self.path.exists()
        if kind == "new" and not exists:
            try:
                self.path.parent.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise StoreError(f"--store {str(self.path)!r}: its folder cannot be created: "
                                 f"{_os_reason(exc)}") from None
        writable = _writable(self.path, exists)
        if read_only is None:
            read_only = not writable
            if read_only:
                if kind == "new":
                    raise StoreError(f"--store {str(self.path)!r} cannot be created: its folder is not writable "
                                     f"(read-only or no permission)")
                self._note("cannot be written (read-only file, folder or mount, or no permission); it was opened "
                           "read-only: stored cells are used, new ones are not kept")
        self.read_only = bool(read_only)
        try:
            self._conn = self._open()
        except sqlite3.Error as exc:
            raise StoreError(f"--store {str(self.path)!r} cannot be opened: {exc}") from None

    def _note(self, text: str) -> None:
        msg = f"result store {str(self.path)!r} {text}"
        self.notice = f"{self.notice}; {msg}" if self.notice else msg
        warnings.warn(msg, StoreWarning, stacklevel=3)

    # ------------------------------------------------------------------ opening
    def _connect(self) -> sqlite3.Connection:
        if self.read_only:
            uri = f"{self.path.resolve().as_uri()}?mode=ro"
            conn = sqlite3.connect(uri, uri=True, timeout=BUSY_TIMEOUT_MS / 1000, isolation_level=None,
                                   check_same_thread=False)
            try:
                conn.execute("SELECT count(*) FROM sqlite_master").fetchone()
            except sqlite3.OperationalError:  # WAL store on a read-only mount without its -shm file
                conn.close()
                uri = f"{self.path.resolve().as_uri()}?immutable=1"
                conn = sqlite3.connect(uri, uri=True, isolation_level=None, check_same_thread=False)
        else:
            conn = sqlite3.connect(str(self.path), timeout=BUSY_TIMEOUT_MS / 1000, isolation_level=None,
                                   check_same_thread=False)
        conn.execute(f"PRAGMA busy_timeout = {BUSY_TIMEOUT_MS}")
        return conn

    @staticmethod
    def _damage(conn: sqlite3.Connection) -> Optional[str]:
        """None if SQLite finds the (AMRA) file sound, else a description of the damage."""
        try:
            ok = conn.execute("PRAGMA quick_check").fetchone()[0]
            if ok == "ok" and conn.execute("SELECT count(*) FROM sqlite_master WHERE name = 'cells'").fetchone()[0] == 0:
                n = conn.execute("SELECT count(*) FROM sqlite_master").fetchone()[0]
                if n:
                    return "an AMRA store without its cells table"
        except sqlite3.DatabaseError as exc:
            return f"a damaged SQLite database ({exc})"
        return None if ok == "ok" else f"a damaged SQLite database (quick_check: {ok})"

    def _set_aside(self, why: str) -> None:
        """Only ever called for a file whose header says it is an AMRA store."""
        stamp = time.strftime("%Y%m%dT%H%M%SZ", time.gmtime())
        aside = self.path.with_name(f"{self.path.name}.corrupt-{stamp}")
        n = 1
        while aside.exists():
            aside = self.path.with_name(f"{self.path.name}.corrupt-{stamp}-{n}")
            n += 1
        try:
            os.rename(self.path, aside)
        except FileNotFoundError:  # another process set it aside first
            pass
        for suffix in ("-wal", "-shm"):
            side = Path(str(self.path) + suffix)
            if side.exists():
                try:
                    os.rename(side, Path(str(aside) + suffix))
                except OSError:
                    pass
        self._note(f"is {why}; it was set aside as {aside.name!r} and a fresh store was created")

    def _open(self) -> sqlite3.Connection:
        conn = self._connect()
        kind, version = inspect_store_path(self.path)
        if kind == "amra":
            why = self._damage(conn)
            if why is not None:
                conn.close()
                if self.read_only:
                    raise StoreError(f"--store {str(self.path)!r} is {why} and cannot be written, so it cannot "
                                     f"be set aside: choose another path")
                self._set_aside(why)
                conn = self._connect()
                kind, version = "new", ""
        if self.read_only:
            return conn
        try:
            self._init_schema(conn, upgrade_from=int(version) if kind == "amra" else None)
        except sqlite3.DatabaseError as exc:  # damaged pages found only while writing
            conn.close()
            if kind != "amra":
                raise
            self._set_aside(f"not usable ({exc})")
            conn = self._connect()
            self._init_schema(conn)
        return conn

    @staticmethod
    def _init_schema(conn: sqlite3.Connection, upgrade_from: Optional[int] = None) -> None:
        # a new file gets its application_id in the main file's header first (rollback journal), so
        # it is recognised as ours even if this process is killed before WAL's first checkpoint
        mode = conn.execute("PRAGMA journal_mode").fetchone()[0]
        if mode.lower() != "wal":
            conn.execute("BEGIN IMMEDIATE")
            try:
                if conn.execute("PRAGMA application_id").fetchone()[0] == 0:
                    conn.execute(f"PRAGMA application_id = {APPLICATION_ID}")
                    conn.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
                conn.execute("COMMIT")
            except BaseException:
                conn.execute("ROLLBACK")
                raise
        conn.execute("PRAGMA journal_mode = WAL")
        conn.execute("PRAGMA synchronous = NORMAL")
        conn.execute("BEGIN IMMEDIATE")
        try:
            conn.execute("CREATE TABLE IF NOT EXISTS cells (key TEXT PRIMARY KEY, params TEXT NOT NULL, "
                         "result TEXT NOT NULL, solver TEXT NOT NULL, created REAL NOT NULL, checksum TEXT)")
            cols = [r[1] for r in conn.execute("PRAGMA table_info(cells)")]
            if "checksum" not in cols:  # schema 1: rows without a checksum are never served
                conn.execute("ALTER TABLE cells ADD COLUMN checksum TEXT")
            conn.execute(f"PRAGMA application_id = {APPLICATION_ID}")
            conn.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
            conn.execute("COMMIT")
        except BaseException:
            conn.execute("ROLLBACK")
            raise

    # ------------------------------------------------------------------ access
    def _verify(self, key, params, result, solver, checksum) -> Optional[dict]:
        """The result dict of a row, or None (with a warning) when the row does not verify."""
        why = None
        if checksum is None:
            why = "has no checksum (written by an older AMRA)"
        elif not all(isinstance(x, str) for x in (params, result, solver)):
            why = "has fields of the wrong type"
        elif row_checksum(key, params, result, solver) != checksum:
            why = "does not match its checksum (edited or damaged on disk)"
        else:
            try:
                d = json.loads(result, parse_constant=_reject_constant)
            except (ValueError, RecursionError) as exc:
                why = f"is not valid JSON ({exc})"
            else:
                if isinstance(d, dict):
                    return d
                why = "is not a JSON object"
        with self._lock:
            first = key not in self.damaged_rows
            if first:
                self.damaged_rows.append(key)
        if first:
            warnings.warn(f"result store {str(self.path)!r}: the row for cell {key} {why}; it is skipped and "
                          f"the cell recomputed", StoreWarning, stacklevel=3)
        return None

    def get(self, key: str) -> Optional[dict]:
        """The stored result dict for ``key``, or None (also for a row that does not verify)."""
        with self._lock:
            row = self._conn.execute("SELECT key, params, result, solver, checksum FROM cells WHERE key = ?",
                                     (key,)).fetchone()
        return None if row is None else self._verify(*row)

    def get_many(self, keys) -> dict:
        """``{key: result}`` for those of ``keys`` that are stored (and verify)."""
        keys = list(keys)
        rows = []
        with self._lock:
            for i in range(0, len(keys), 500):
                chunk = keys[i:i + 500]
                q = (f"SELECT key, params, result, solver, checksum FROM cells "
                     f"WHERE key IN ({','.join('?' * len(chunk))})")
                rows.extend(self._conn.execute(q, chunk).fetchall())
        out = {}
        for row in rows:
            d = self._verify(*row)
            if d is not None:
                out[row[0]] = d
        return out

    def _row(self, key: str, params, result) -> tuple:
        p = params.to_dict() if hasattr(params, "to_dict") else params
        r = result.to_dict() if hasattr(result, "to_dict") else result
        ps = json.dumps(_clean(p), sort_keys=True, allow_nan=False)
        rs = json.dumps(_clean(r), sort_keys=True, allow_nan=False)
        return (key, ps, rs, self.solver, time.time(), row_checksum(key, ps, rs, self.solver))

    def put(self, key: str, params, result) -> bool:
        """Store ``result`` for ``key`` (replacing an earlier one) with the case ``params``.
        Returns False (nothing written) on a read-only store."""
        return self.put_many([(key, params, result)])

    def put_many(self, items) -> bool:
        """Store every ``(key, params, result)`` of ``items`` in one transaction: all of them or,
        if writing fails, none (a map's column and its record go in together). Returns False
        (nothing written) on a read-only store."""
        if self.read_only:
            return False
        rows = [self._row(k, p, r) for k, p, r in items]
        with self._lock:
            self._conn.execute("BEGIN IMMEDIATE")
            try:
                self._conn.executemany("INSERT OR REPLACE INTO cells (key, params, result, solver, created, "
                                       "checksum) VALUES (?, ?, ?, ?, ?, ?)", rows)
                self._conn.execute("COMMIT")
            except BaseException:
                self._conn.execute("ROLLBACK")
                raise
            for row in rows:
                if row[0] in self.damaged_rows:
                    self.damaged_rows.remove(row[0])
        return True

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


def _reject_constant(tok):
    raise ValueError(f"non-standard JSON constant {tok}")
