"""Server-level limits shared by every session of a process: the result store opened so that a bad
disk never stops the server, and a fair, bounded queue of map jobs.

* :func:`open_store`: the SQLite store, or ``None`` with a notice for the page when it cannot be
  used (read-only or full file system, a directory that cannot be created). Runs and maps work
  without it; finished cells are then not kept. A store that fails later, while writing (disk
  full), is reported by the map run itself (``MapRun.store_error``) and shown the same way.
* :class:`FairSlots`: at most ``max_running`` map jobs compute at once; the others wait in
  first-come order (a plain semaphore wakes waiters in no fixed order) and can tell their
  position; at most ``max_queued`` wait, and a job beyond that is refused at once with
  "busy, N maps queued" instead of stalling. Jobs are already one per map specification (sessions
  asking for the same parameters share one), and a session follows one map at a time, so the
  queue is fair across sessions.
"""
from __future__ import annotations

import threading
from collections import deque
from contextlib import contextmanager
from pathlib import Path
from typing import Optional

from amra_core.store import CellStore

MAX_RUNNING = 1  #: map jobs computing at once per server process (each uses all map workers)
MAX_QUEUED = 16  #: map jobs waiting at most; more are refused with "busy"


def open_store(path, solver: str = "") -> tuple[Optional[CellStore], str]:
    """``(store, "")``, or ``(None, notice)`` when the store cannot be opened and written."""
    p = Path(path)
    try:
        store = CellStore(p, solver=solver)
    except Exception as exc:  # noqa: BLE001 - OSError, sqlite3.Error: the server serves without a store
        reason = getattr(exc, "strerror", None) or str(exc) or type(exc).__name__
        return None, (f"The result store {str(p)!r} cannot be used ({reason}): runs and maps work, "
                      f"but finished map cells are not kept. Ask the operator to check the volume.")
    return store, store.notice


class Busy(Exception):
    """The map queue is full; the message says how many wait."""


class FairSlots:
    """First-come slots for map jobs (see the module docstring)."""

    def __init__(self, max_running: int = MAX_RUNNING, max_queued: int = MAX_QUEUED):
        self.max_running = max_running
        self.max_queued = max_queued
        self._cond = threading.Condition()
        self._running: set = set()
        self._waiting: deque = deque()

    def admit(self, who) -> None:
        """Enter the queue (raises :class:`Busy` when it is full)."""
        with self._cond:
            if len(self._running) < self.max_running and not self._waiting:
                self._running.add(who)
                return
            if len(self._waiting) >= self.max_queued:
                raise Busy(f"server busy: {len(self._waiting)} maps are queued (at most {self.max_queued}); "
                           f"try again in a few minutes")
            self._waiting.append(who)

    def position(self, who) -> int:
        """0 when running (or not queued), else 1 for the next to run, 2, ..."""
        with self._cond:
            try:
                return self._waiting.index(who) + 1
            except ValueError:
                return 0

    @property
    def queued(self) -> int:
        with self._cond:
            return len(self._waiting)

    @contextmanager
    def slot(self, who, cancel: Optional[threading.Event] = None):
        """Wait for ``who``'s turn (after :meth:`admit`); yields True when it runs, False when
        ``cancel`` was set while it waited."""
        got = False
        with self._cond:
            if who not in self._running and who not in self._waiting:
                self._waiting.append(who)
            while who not in self._running:
                if cancel is not None and cancel.is_set():
                    break
                if self._waiting and self._waiting[0] is who and len(self._running) < self.max_running:
                    self._waiting.popleft()
                    self._running.add(who)
                    break
                self._cond.wait(0.2)
            got = who in self._running
            if not got and who in self._waiting:
                self._waiting.remove(who)
                self._cond.notify_all()
        try:
            yield got
        finally:
            with self._cond:
                self._running.discard(who)
                self._cond.notify_all()


#: niceness of background work (map jobs and the processes they start, per-session analyses):
#: interactive runs and the event loop get the CPU first
BACKGROUND_NICE = 10


def lower_priority_of_this_thread(nice: int = BACKGROUND_NICE) -> None:
    """Lower the CPU priority of the calling thread (Linux: niceness is per thread, and processes
    the thread starts inherit it, so a map job's worker pool runs at the same low priority).
    Without effect (and harmless) where not supported."""
    import os
    try:
        tid = threading.get_native_id()
        cur = os.getpriority(os.PRIO_PROCESS, tid)
        if cur < nice:
            os.setpriority(os.PRIO_PROCESS, tid, nice)
    except (AttributeError, OSError):
        pass
