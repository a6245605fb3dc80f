"""One-shot analyses (modes, locus, fan plot, ladder) in a server-wide process pool, latest wins.

The pool (:func:`get_analysis_pool`, one per server process in ``pn.state.cache``) keeps the
GIL-heavy trim/eigen work out of the process that serves the pages. :class:`LatestTasks` is the
per-session front: ``submit(key, fn, *args)`` supersedes what this session queued under ``key``
(a pending call is cancelled, a running one's result is dropped), and results are posted as
``(key, result)`` through the session's thread-safe ``post``.
"""
from __future__ import annotations

import concurrent.futures as cf
import multiprocessing as mp
import threading
from typing import Callable

CACHE_KEY = "amra-analysis-pool"


class AnalysisPool:
    """``workers`` spawned processes (spawn: the server holds threads, fork could deadlock)."""

    def __init__(self, workers: int = 1):
        self.workers = workers
        self._ctx = mp.get_context("spawn")
        self._lock = threading.Lock()
        self._pool = self._new_pool()

    def _new_pool(self):
        # analyses at low CPU priority: the live runs and the event loop first (server_limits)
        from .server_limits import BACKGROUND_NICE
        return cf.ProcessPoolExecutor(max_workers=self.workers, mp_context=self._ctx,
                                      initializer=_nice, initargs=(BACKGROUND_NICE,))

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


def get_analysis_pool() -> AnalysisPool:
    """The process-wide pool, created on first use."""
    import panel as pn
    pool = pn.state.cache.get(CACHE_KEY)
    if pool is None:
        new = AnalysisPool()
        pool = pn.state.cache.setdefault(CACHE_KEY, new)
        if pool is not new:
            new.close()
    return pool


class LatestTasks:
    def __init__(self, post: Callable[[str, dict], None], pool: AnalysisPool):
        self._post = post
        self._pool = pool
        self._lock = threading.Lock()
        self._latest: dict = {}  #: key -> the future whose result counts
        self._closed = False

    def submit(self, key: str, fn, *args) -> cf.Future:
        """Run ``fn(*args)`` in the pool; its dict result is posted as ``(key, result)`` unless superseded."""
        fut = self._pool.submit(fn, *args)
        with self._lock:
            old = self._latest.get(key)
            self._latest[key] = fut
        if old is not None:
            old.cancel()
        fut.add_done_callback(lambda f: self._done(key, f))
        return fut

    def _done(self, key: str, fut: cf.Future) -> None:
        with self._lock:
            current = self._latest.get(key) is fut
            if current:
                del self._latest[key]
        if not current or self._closed or fut.cancelled():
            return
        exc = fut.exception()
        if exc is not None:
            self._post("error", {"text": f"{key} failed: {type(exc).__name__}: {exc}"})
        else:
            self._post(key, fut.result())

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
