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
* :class:`StreamBudget`: the live-plot updates per second the whole server sends, shared evenly by
  the sessions that stream (each update costs the event loop a few ms, whoever watches).
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


def stream_period_ms(default: int) -> int:
    """Period of each session's update of the page [ms]: ``AMRA_STREAM_PERIOD_MS`` (set by
    ``amra serve --stream-period-ms``), else ``default``. Each update of the live plots costs the
    server a roughly fixed amount of CPU whatever the number of new rows, so a team server sends
    fewer, larger updates."""
    import os
    raw = os.environ.get("AMRA_STREAM_PERIOD_MS", "")
    try:
        v = int(raw)
    except ValueError:
        return default
    return v if 20 <= v <= 2000 else default


DEFAULT_STREAM_BUDGET_HZ = 160.0  #: live-plot updates per second for the whole server, by default


def stream_budget_hz(default: float = DEFAULT_STREAM_BUDGET_HZ) -> float:
    """``AMRA_STREAM_BUDGET_HZ`` (10..10000), else ``default``."""
    import os
    try:
        v = float(os.environ.get("AMRA_STREAM_BUDGET_HZ", ""))
    except ValueError:
        return default
    return v if 10.0 <= v <= 10000.0 else default


LAG_HIGH_S = 0.15  #: smoothed event-loop lag above which the stream budget is cut [s]
LAG_LOW_S = 0.05  #: smoothed event-loop lag below which the stream budget grows back [s]
ADJUST_PERIOD_S = 0.5  #: the budget changes at most this often [s]
MIN_SESSION_HZ = 1.0  #: the budget never gives a streaming session fewer updates than this per second
MAX_SLOWDOWN = 4.0  #: the secondary updates and map polls stretch with the budget's cut, by this at most


class StreamBudget:
    """The server's live-plot updates per second, shared by the sessions streaming a run.

    With ``n`` sessions streaming, each sends an update at most every ``n / rate_hz`` seconds
    (:meth:`min_interval_s`): 160 /s serves 8 sessions at the full chunk rate (about 17 /s), 16 at
    10 /s, 32 at 5 /s, and the event loop's share spent on streaming stays bounded. A session's
    browser that draws more slowly gets fewer (flow control, :mod:`app.streams`).

    ``rate_hz`` follows the event loop's lag (:meth:`observe_lag`, fed by :mod:`app.loop_watch`):
    when the loop's smoothed lag exceeds :data:`LAG_HIGH_S`, the rate is cut by 30 %; below
    :data:`LAG_LOW_S` it grows by 10 %, up to ``total_hz``; at most every :data:`ADJUST_PERIOD_S`,
    and never below :data:`MIN_SESSION_HZ` per streaming session. Why: a slider release waits for
    the loop to read it, and on a saturated machine the loop waits for a core. With eight
    browsers on the server's two cores, the loop was runnable but not running for 13.5 of the
    16.6 s in which it lagged more than 50 ms (``/proc`` schedstat of the loop's thread,
    2026-12-02), and each browser's drawing of an update takes about 50 ms of CPU. Fewer updates
    leave the loop its core; on a server whose users' browsers run elsewhere, they cut the
    server's own streaming work the same way."""

    def __init__(self, total_hz: float = DEFAULT_STREAM_BUDGET_HZ):
        self.total_hz = float(total_hz)
        self.rate_hz = float(total_hz)  #: the updates per second now (<= total_hz)
        self.lag_s = 0.0  #: smoothed event-loop lag [s]
        self._adjusted_at = -1e9
        self._lock = threading.Lock()
        self._streaming: set = set()

    def join(self, who) -> None:
        with self._lock:
            self._streaming.add(who)

    def leave(self, who) -> None:
        with self._lock:
            self._streaming.discard(who)

    @property
    def streaming(self) -> int:
        with self._lock:
            return len(self._streaming)

    def min_interval_s(self) -> float:
        """Shortest wall-clock interval between one session's updates now [s] (at most
        ``1 / MIN_SESSION_HZ``, also when more sessions joined since the last cut)."""
        n = self.streaming
        return n / max(self.rate_hz, min(self.total_hz, MIN_SESSION_HZ * n))

    def observe_lag(self, lag_s: float, now_s: float) -> None:
        """One sample of the event loop's lag [s] (how late a timed wake-up ran), at ``now_s``
        (monotonic) [s]: smoothed, and the rate adjusted (class docstring)."""
        self.lag_s += 0.3 * (max(0.0, float(lag_s)) - self.lag_s)
        if now_s - self._adjusted_at < ADJUST_PERIOD_S:
            return
        floor_hz = max(2.0, MIN_SESSION_HZ * self.streaming)
        if self.lag_s > LAG_HIGH_S:
            rate = max(min(floor_hz, self.total_hz), 0.7 * self.rate_hz)
        elif self.lag_s < LAG_LOW_S:
            rate = min(self.total_hz, 1.1 * self.rate_hz)
        else:
            return
        if rate != self.rate_hz:
            self.rate_hz = rate
            self._adjusted_at = now_s

    def load_factor(self) -> float:
        """1 with one or two sessions streaming, n/2 with n: the factor by which each session
        stretches the periods of its secondary updates (running clock, "so far" verdict)."""
        return max(1.0, self.streaming / 2.0)

    def slowdown(self) -> float:
        """How far the lagging loop has cut the rate (``total_hz / rate_hz``, 1 to
        :data:`MAX_SLOWDOWN`): the sessions stretch their secondary updates and map polls by it too,
        since each of those also makes every page redraw."""
        return min(MAX_SLOWDOWN, max(1.0, self.total_hz / self.rate_hz))


STREAM_BUDGET_KEY = "amra-stream-budget"


def get_stream_budget() -> StreamBudget:
    """The process-wide budget (``pn.state.cache``), created on first use."""
    import panel as pn
    budget = pn.state.cache.get(STREAM_BUDGET_KEY)
    if budget is None:
        budget = pn.state.cache.setdefault(STREAM_BUDGET_KEY, StreamBudget(stream_budget_hz()))
    return budget
