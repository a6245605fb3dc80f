"""Server-wide process pools (one of each per process, ``pn.state.cache``) that keep GIL-heavy
Python work (trims, eigen-analyses) out of the process serving the pages: the **analysis** pool
(modes, locus, fan plot, ladder; low CPU priority) and the **run** pool (the trim that starts a
run, normal priority: a Run never waits behind analyses). :class:`LatestTasks` is a session's
front to the analysis pool: ``submit(key, event, fn, *args)`` supersedes what the session queued
under ``key`` and posts ``event(result)`` through the session's thread-safe ``post``.
"""
from __future__ import annotations

import concurrent.futures as cf
import multiprocessing as mp
import threading
from typing import Callable

from ..events import Notice
from .queue import BACKGROUND_NICE

CACHE_KEY = "amra-analysis-pool"
RUN_CACHE_KEY = "amra-run-pool"


class AnalysisPool:
    """``workers`` spawned processes (spawn: the server holds threads, fork could deadlock)."""

    def __init__(self, workers: int = 1, nice: int = BACKGROUND_NICE):
        self.workers = workers
        self.nice = nice
        self._ctx = mp.get_context("spawn")
        self._lock = threading.Lock()
        self._pool = self._new_pool()

    def _new_pool(self):
        return cf.ProcessPoolExecutor(max_workers=self.workers, mp_context=self._ctx,
                                      initializer=_nice, initargs=(self.nice,))

    def submit(self, fn, *args) -> cf.Future:
        with self._lock:
            try:
                return self._pool.submit(fn, *args)
            except cf.process.BrokenProcessPool:  # a worker died: a fresh pool for what follows
                self._pool.shutdown(wait=False, cancel_futures=True)
                self._pool = self._new_pool()
                return self._pool.submit(fn, *args)

    def close(self) -> None:
        with self._lock:
            self._pool.shutdown(wait=True, cancel_futures=True)


def _get(key: str, nice: int) -> AnalysisPool:
    import panel as pn
    pool = pn.state.cache.get(key)
    if pool is None:
        new = AnalysisPool(nice=nice)
        pool = pn.state.cache.setdefault(key, new)
        if pool is not new:
            new.close()
    return pool


def get_analysis_pool() -> AnalysisPool:
    """The process-wide analysis pool (low priority: live runs and the event loop first)."""
    return _get(CACHE_KEY, BACKGROUND_NICE)


def get_run_pool() -> AnalysisPool:
    """The process-wide pool that trims new runs (normal priority)."""
    return _get(RUN_CACHE_KEY, 0)


class LatestTasks:
    def __init__(self, post: Callable, pool: AnalysisPool):
        self._post = post
        self._pool = pool
        self._lock = threading.Lock()
        self._latest: dict = {}  #: key -> the future whose result counts
        self._closed = False

    def submit(self, key: str, event, fn, *args) -> cf.Future:
        """Run ``fn(*args)`` in the pool; ``event(result)`` is posted unless superseded."""
        fut = self._pool.submit(fn, *args)
        with self._lock:
            old = self._latest.get(key)
            self._latest[key] = fut
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

    def idle(self) -> bool:
        with self._lock:
            return not self._latest

    def close(self) -> None:
        self._closed = True
        with self._lock:
            futs, self._latest = list(self._latest.values()), {}
        for f in futs:
            f.cancel()


def _nice(n: int) -> None:
    import os
    try:
        os.nice(n)
    except OSError:
        pass
