"""Server-wide process pools (one of each per process, ``pn.state.as_cached``) that keep GIL-heavy
Python work (trims, eigen-analyses) out of the process serving the pages: the **analysis** pool
(modes, locus, fan plot, ladder; low CPU priority) and the **run** pool (the trim that starts a
run, normal priority: a Run never waits behind analyses). :class:`LatestTasks` is a session's
front to the analysis pool.
"""
from __future__ import annotations

import concurrent.futures as cf
import multiprocessing as mp
import os
import threading
from typing import Callable

from ..events import Notice

#: niceness of background work (map jobs and the processes they start, the analysis pool):
#: interactive runs and the event loop get the CPU first
BACKGROUND_NICE = 10


def lower_priority_of_this_thread(nice: int = BACKGROUND_NICE) -> None:
    """Lower the CPU priority of the calling thread (Linux: niceness is per thread, and processes
    the thread starts inherit it, so a map job's worker pool runs at the same low priority).
    Without effect (and harmless) where not supported."""
    try:
        tid = threading.get_native_id()
        if os.getpriority(os.PRIO_PROCESS, tid) < nice:
            os.setpriority(os.PRIO_PROCESS, tid, nice)
    except (AttributeError, OSError):
        pass


def start_pool_worker(nice: int) -> None:
    """Pool worker initializer: one BLAS thread (the pools already run a process per core), then
    :func:`lower_priority_of_this_thread`."""
    from amra_core.blas_threads import use_one_blas_thread
    use_one_blas_thread()
    lower_priority_of_this_thread(nice)


class AnalysisPool:
    """``workers`` spawned processes (spawn: the server holds threads, fork could deadlock) at
    niceness ``nice``; a pool whose worker died is replaced for what follows."""

    def __init__(self, workers: int = 1, nice: int = BACKGROUND_NICE):
        self.workers, self.nice = workers, nice
        self._lock = threading.Lock()
        self._pool = self._new_pool()

    def _new_pool(self):
        return cf.ProcessPoolExecutor(max_workers=self.workers, mp_context=mp.get_context("spawn"),
                                      initializer=start_pool_worker, initargs=(self.nice,))

    def submit(self, fn, *args) -> cf.Future:
        with self._lock:
            try:
                return self._pool.submit(fn, *args)
            except cf.process.BrokenProcessPool:
                self._pool.shutdown(wait=False, cancel_futures=True)
                self._pool = self._new_pool()
                return self._pool.submit(fn, *args)

    def close(self) -> None:
        with self._lock:
            self._pool.shutdown(wait=True, cancel_futures=True)


def get_analysis_pool() -> AnalysisPool:
    """The process-wide analysis pool (low priority: live runs and the event loop first)."""
    import panel as pn
    return pn.state.as_cached("amra-analysis-pool", lambda: AnalysisPool(nice=BACKGROUND_NICE))


def get_run_pool() -> AnalysisPool:
    """The process-wide pool that trims new runs (normal priority)."""
    import panel as pn
    return pn.state.as_cached("amra-run-pool", lambda: AnalysisPool(nice=0))


class LatestTasks:
    """``submit(key, event, fn, *args)`` supersedes what the session queued under ``key`` and posts
    ``event(result)`` (or a :class:`Notice` of its failure) through the session's thread-safe ``post``."""

    def __init__(self, post: Callable, pool: AnalysisPool):
        self._post, self._pool = post, pool
        self._lock = threading.Lock()
        self._latest: dict = {}  #: key -> the future whose result counts
        self._closed = False

    def submit(self, key: str, event, fn, *args) -> cf.Future:
        fut = self._pool.submit(fn, *args)
        with self._lock:
            old, self._latest[key] = self._latest.get(key), fut
        if old is not None:
            old.cancel()
        fut.add_done_callback(lambda f: self._done(key, event, f))
        return fut

    def _done(self, key: str, event, fut: cf.Future) -> None:
        with self._lock:
            current = self._latest.get(key) is fut
            if current:
                del self._latest[key]
        if not current or self._closed or fut.cancelled():
            return
        exc = fut.exception()
        if exc is not None:
            self._post(Notice(f"{key} failed: {type(exc).__name__}: {exc}"))
        else:
            self._post(event(fut.result()))

    def close(self) -> None:
        self._closed = True
        with self._lock:
            futs, self._latest = list(self._latest.values()), {}
        for f in futs:
            f.cancel()
