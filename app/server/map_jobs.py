"""Server-wide boundary-map jobs: one job per MapSpec however many sessions ask, in a fair,
bounded queue, with a result store that a bad disk never stops.

One :class:`MapRegistry` per server process (``pn.state.cache``, :func:`get_registry`).
``subscribe(spec, who, on_change)`` returns the running or finished job for ``spec`` (starting it
if needed) and calls ``on_change`` from the job's thread at each change; a job nobody follows is
cancelled (finished cells are in the SQLite store, so a later job resumes at once). At most
``max_running`` jobs compute at a time (:class:`FairSlots`); finished jobs are kept (``max_jobs``).
"""
from __future__ import annotations

import threading
from collections import OrderedDict, deque
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path
from typing import Optional

from amra_core.boundary import MapSpec, compute_column, iter_map, solver_fingerprint
from amra_core.executor import DaskExecutor, LocalPoolExecutor
from amra_core.store import CellStore

from .pool import BACKGROUND_NICE, lower_priority_of_this_thread
from .settings import ServerSettings

CACHE_KEY = "amra-map-registry"

MAX_RUNNING = 1  #: map jobs computing at once per server process (each uses all map workers)
MAX_QUEUED = 16  #: map jobs waiting at most; more are refused with "busy"


def open_store(path, solver: str = "") -> tuple[Optional[CellStore], str]:
    """``(store, "")``, or ``(None, notice)`` for the page when the store cannot be opened and written
    (read-only or full file system, a directory that cannot be created): runs and maps work without
    it. A store that fails later, while writing, is reported by the map run (``MapRun.store_error``)."""
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
    """At most ``max_running`` map jobs compute at once; the others wait in first-come order (a plain
    semaphore wakes waiters in no fixed order) and can tell their position; at most ``max_queued``
    wait, and a job beyond that is refused at once (:class:`Busy`) instead of stalling. Jobs are one
    per map specification and a session follows one map at a time, so the queue is fair across
    sessions."""

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


class MapJob:
    """One map computation in its own thread; subscribers are called back on each change and read :meth:`snapshot`."""

    def __init__(self, spec: MapSpec, registry: "MapRegistry"):
        self.spec = spec
        self._registry = registry
        self._lock = threading.Lock()
        self.cells: list = []
        self.cached = 0
        self.estimated_total = len(spec.cg_values) * spec.n_coarse
        self.state = "queued"  #: queued | running | done | cancelled | failed | busy
        self.error = ""
        self.store_error = ""  #: a store write that failed during this job (the map went on)
        self.cancel = threading.Event()
        self.subscribers: dict = {}  #: who -> callback(), called from the map's thread on every change
        self._columns: list = []  #: the finished columns' summaries (amra_core.boundary.BoundaryMap.columns)
        self._n_columns = 0
        self._thread = threading.Thread(target=self._run, name="amra-map", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def join(self, timeout: Optional[float] = None) -> None:
        self._thread.join(timeout)

    def _run(self) -> None:
        lower_priority_of_this_thread()  # maps yield the CPU to interactive runs
        reg = self._registry
        with reg.slots.slot(self, self.cancel) as got:  # first come, first served
            if not got or self.cancel.is_set():
                self.state = "cancelled"
                return
            self.state = "running"
            self._changed()
            ex = None
            try:
                # cells in other processes (trim and eigen-analysis hold the GIL: in this process
                # they would starve the sessions' event loop)
                sched = reg.settings.dask_scheduler
                ex = DaskExecutor(sched) if sched else reg.map_pool()
                run = iter_map(self.spec, executor=ex, store=reg.store, cancel=self.cancel)
                for cell in run:
                    self.store_error = getattr(run, "store_error", "")
                    columns = run.result().columns if len(run.info) != self._n_columns else None
                    with self._lock:
                        self.cells.append(cell)
                        self.cached = run.cached
                        self.estimated_total = max(run.estimated_total, len(self.cells))
                        if columns is not None:  # a column finished: its fold and flutter GJ are known
                            self._columns, self._n_columns = [c for c in columns if c["status"] != "incomplete"], \
                                len(run.info)
                    self._changed()
                self.state = "cancelled" if run.cancelled else "done"
            except Exception as exc:  # noqa: BLE001 - shown to every subscriber
                self.error = f"{type(exc).__name__}: {exc}"
                self.state = "failed"
            finally:
                if ex is not None and sched:  # the local pool stays, warm, for the next job
                    ex.close()
                if self.state == "done":
                    with self._lock:
                        self.estimated_total = len(self.cells)
                reg.changed()  # every job: its end frees the slot, so queued jobs move up

    def _changed(self) -> None:
        """Tell the subscribers (each throttles its own redraws: app.session.Throttle)."""
        for callback in list(self.subscribers.values()):
            callback()

    def snapshot(self, since: int = 0) -> dict:
        """New cells since index ``since`` and the progress."""
        with self._lock:
            cells = list(self.cells[since:])
            n = len(self.cells)
            return {"cells": cells, "n": n, "cached": self.cached, "total": max(self.estimated_total, n),
                    "state": self.state, "error": self.error,
                    "position": self._registry.slots.position(self) if self.state == "queued" else 0,
                    "notice": self._registry.store_notice or self.store_error}

    def all_cells(self) -> list:
        with self._lock:
            return list(self.cells)

    def for_export(self) -> tuple:
        """``(cells, finished columns, done)`` read together: a file saved mid-map said "0 cells so
        far" above a finished column's fold line (the page's copy of the cells lags the job's)."""
        with self._lock:
            return list(self.cells), list(self._columns), self.state == "done"

    def columns(self) -> list:
        """The finished columns: ``fold_gj``, ``flutter_gj`` (strong flutter only), ``critical_gj`` and
        the ``intervals`` with their ``strength`` (:mod:`amra_core.boundary.intervals`)."""
        with self._lock:
            return list(self._columns)


class MapRegistry:
    """The process's map jobs, keyed by MapSpec (see the module docstring)."""

    def __init__(self, settings: ServerSettings, max_running: int = 1, max_jobs: int = 24):
        self.settings = settings
        # a store that cannot be used leaves None and a notice for the page
        self.store, self.store_notice = open_store(settings.store_path, solver_fingerprint())
        self.slots = FairSlots(max_running)
        self.max_jobs = max_jobs
        self._lock = threading.Lock()
        self._jobs: "OrderedDict[MapSpec, MapJob]" = OrderedDict()
        self._live: list = []  #: every job whose thread may still run (cancelled ones included)
        self.jobs_started = 0
        self._pool: Optional[LocalPoolExecutor] = None

    def map_pool(self) -> LocalPoolExecutor:
        """The map workers' processes, kept between jobs (one job computes at a time): a new pool
        per job cost every map 0.6-0.9 s of process start and kernel loading. A job takes only its
        own columns from it (amra_core.boundary.MapRun), so a cancelled job's late results are
        ignored."""
        with self._lock:
            if self._pool is None:
                # at low priority, as the map thread: the warm-up column and the maps yield the
                # CPU to the sessions' runs (measured: the first Run's first row 2.3 s, 1.5 s
                # without the warm-up, the server on one core)
                self._pool = LocalPoolExecutor(self.settings.map_workers, nice=BACKGROUND_NICE)
            return self._pool

    def warm_map_pool(self) -> None:
        """Start the map workers and have each load the solver (a short rigid column), without
        waiting: ``panel serve --setup``, before any session asks for a map."""
        pool = self.map_pool()
        spec = MapSpec(cg_values=(0.40,), gj_min=2500.0)
        for _ in range(pool.workers):
            pool.submit(compute_column, spec.column_task(0.40), None)

    def subscribe(self, spec: MapSpec, who, on_change=lambda: None) -> MapJob:
        with self._lock:
            job = self._jobs.get(spec)
            if job is None or job.state in ("cancelled", "failed", "busy"):
                job = MapJob(spec, self)
                try:
                    self.slots.admit(job)
                except Busy as exc:  # the queue is full: say so at once, compute nothing
                    job.state, job.error = "busy", str(exc)
                    return job
                self._jobs[spec] = job
                self._live = [j for j in self._live if j.state in ("queued", "running")] + [job]
                self.jobs_started += 1
                job.start()
            self._jobs.move_to_end(spec)
            job.subscribers[who] = on_change
            self._trim()
            return job

    def unsubscribe(self, job: MapJob, who) -> None:
        with self._lock:
            job.subscribers.pop(who, None)
            if not job.subscribers and job.state in ("queued", "running"):
                job.cancel.set()
                if self._jobs.get(job.spec) is job:
                    del self._jobs[job.spec]

    def related(self, spec: MapSpec) -> dict:
        """``{fidelity: job}`` of the known jobs for ``spec`` at every fidelity (``spec``'s own included)."""
        out = {}
        with self._lock:
            for fid in ("rigid", "fem-torsion", "fem-coupled"):
                job = self._jobs.get(replace(spec, fidelity=fid))
                if job is not None:
                    out[fid] = job
        return out

    def changed(self) -> None:
        """A job started or ended: every subscriber redraws (its queue position may have moved)."""
        with self._lock:
            jobs = list(self._jobs.values())
        for job in jobs:
            job._changed()

    def _trim(self) -> None:
        while len(self._jobs) > self.max_jobs:
            for spec, job in self._jobs.items():
                if not job.subscribers:
                    job.cancel.set()
                    del self._jobs[spec]
                    break
            else:
                return

    def close(self) -> None:
        with self._lock:
            jobs = list({id(j): j for j in [*self._jobs.values(), *self._live]}.values())
            self._jobs.clear()
            self._live = []
        for job in jobs:
            job.cancel.set()
        for job in jobs:
            job.join(10.0)
        if self.store is not None:
            self.store.close()
        with self._lock:
            pool, self._pool = self._pool, None
        if pool is not None:
            pool.close()


def get_registry(settings: Optional[ServerSettings] = None) -> MapRegistry:
    """The process-wide registry, created once (``pn.state.as_cached``, under :data:`CACHE_KEY`)."""
    import panel as pn
    return pn.state.as_cached(CACHE_KEY, lambda: MapRegistry(settings or ServerSettings.from_env()))
