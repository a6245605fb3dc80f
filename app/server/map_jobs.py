"""Server-wide boundary-map jobs: one job per MapSpec however many sessions ask, bounded.

One :class:`MapRegistry` per server process (``pn.state.cache``, :func:`get_registry`).
``subscribe(spec, who, on_change)`` returns the running or finished job for ``spec`` (starting it
if needed) and calls ``on_change`` from the job's thread at each change; a job nobody follows is
cancelled (finished cells are in the SQLite store, so a later job resumes at once). At most
``max_running`` jobs compute at a time, the others queue; finished jobs are kept (``max_jobs``).
"""
from __future__ import annotations

import threading
import time
from collections import OrderedDict
from dataclasses import replace
from typing import Optional

from amra_core.boundary import MapSpec, iter_map, solver_fingerprint
from amra_core.executor import DaskExecutor, LocalPoolExecutor

from .queue import Busy, FairSlots, lower_priority_of_this_thread, open_store
from .settings import ServerSettings

CACHE_KEY = "amra-map-registry"


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
        self.started_at = time.time()
        self._columns: list = []  #: the finished columns' summaries (amra_core.boundary.BoundaryMap.columns)
        self._n_columns = 0
        self._thread = threading.Thread(target=self._run, name="amra-map", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def join(self, timeout: Optional[float] = None) -> None:
        self._thread.join(timeout)

    def _run(self) -> None:
        lower_priority_of_this_thread()  # maps yield the CPU to interactive runs (app.server.queue)
        reg = self._registry
        with reg.slots.slot(self, self.cancel) as got:  # first come, first served (app.server.queue)
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
                ex = DaskExecutor(sched) if sched else LocalPoolExecutor(reg.settings.map_workers)
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
                if ex is not None:
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

    def columns(self) -> list:
        """The finished columns: ``fold_gj``, ``flutter_gj`` (strong flutter only), ``critical_gj`` and
        the ``intervals`` with their ``strength`` (:mod:`amra_core.boundary.intervals`)."""
        with self._lock:
            return list(self._columns)


class MapRegistry:
    """The process's map jobs, keyed by MapSpec (see the module docstring)."""

    def __init__(self, settings: ServerSettings, max_running: int = 1, max_jobs: int = 24):
        self.settings = settings
        # a store that cannot be used leaves None and a notice for the page (app.server.queue)
        self.store, self.store_notice = open_store(settings.store_path, solver_fingerprint())
        self.slots = FairSlots(max_running)
        self.max_jobs = max_jobs
        self._lock = threading.Lock()
        self._jobs: "OrderedDict[MapSpec, MapJob]" = OrderedDict()
        self._live: list = []  #: every job whose thread may still run (cancelled ones included)
        self.jobs_started = 0

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


def get_registry(settings: Optional[ServerSettings] = None) -> MapRegistry:
    """The process-wide registry, created on first use (``pn.state.cache``)."""
    import panel as pn
    reg = pn.state.cache.get(CACHE_KEY)
    if reg is None:
        new = MapRegistry(settings or ServerSettings.from_env())
        reg = pn.state.cache.setdefault(CACHE_KEY, new)
        if reg is not new and new.store is not None:  # another session created it at the same moment
            new.store.close()
    return reg
