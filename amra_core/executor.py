"""Where map cells run: one small interface over a local process pool, in-process serial
execution, and a dask.distributed cluster.

Interface (:class:`CellExecutor`): ``submit(fn, arg, tag)`` queues ``fn(arg)``; ``wait(timeout)``
blocks until at least one queued call has finished (or ``timeout`` [s] passed) and returns the
finished ones as :class:`Outcome` (``tag``, ``ok``, ``value`` or the exception); ``cancel_pending()``
drops what has not started; ``close()`` releases the workers. ``map_unordered(fn, args)`` is the
batch form: submit them all and yield ``(arg, Outcome)`` as they complete.

* :class:`LocalPoolExecutor` (default): ``concurrent.futures.ProcessPoolExecutor`` with ``workers``
  processes (default ``os.cpu_count()``), started with ``spawn`` so a parent holding threads (a
  dashboard, a dask client) cannot deadlock a forked child. Processes rather than threads: the
  kernels release the GIL, but trim and the eigen-analysis are largely Python/SciPy; the kernels
  are Numba-cached, so a worker pays the import (about a second) once, not the compilation.
* :class:`SerialExecutor`: in the calling process, one call per ``wait`` (``workers=1``).
* :class:`DaskExecutor`: ``distributed.Client(address)`` (``pip install 'amra[dask]'``); the workers
  must be able to import ``amra_core``.

An exception inside ``fn`` becomes ``Outcome(ok=False)``; it never escapes ``wait``. A call whose worker
process died (killed, segfault, out of memory) is run again on a fresh pool, up to ``retries``
times (default 2), before it becomes a failure: a crash is retried, not recorded. (Dask reschedules
the tasks of a lost worker itself.)
"""
from __future__ import annotations

import concurrent.futures as cf
import multiprocessing as mp
import os
import time
from collections import deque
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Iterator, Optional


@dataclass(frozen=True)
class Outcome:
    """A finished call: ``tag`` as given to ``submit``; ``value`` is the return value when ``ok``,
    else the exception (``reason`` is its one-line text)."""

    tag: Any
    ok: bool
    value: Any

    @property
    def reason(self) -> str:
        if self.ok:
            return ""
        return f"{type(self.value).__name__}: {self.value}"


class CellExecutor:
    """Base class; see the module docstring."""

    name = "base"
    workers = 1

    def submit(self, fn: Callable, arg, tag=None) -> None:
        raise NotImplementedError

    def wait(self, timeout: Optional[float] = None) -> list[Outcome]:
        raise NotImplementedError

    @property
    def n_pending(self) -> int:
        raise NotImplementedError

    def cancel_pending(self) -> None:
        raise NotImplementedError

    def close(self) -> None:
        pass

    def map_unordered(self, fn: Callable, args: Iterable) -> Iterator[tuple[Any, Outcome]]:
        """Submit every ``fn(arg)`` and yield ``(arg, outcome)`` in completion order."""
        args = list(args)
        for i, a in enumerate(args):
            self.submit(fn, a, ("map_unordered", i))
        left = len(args)
        while left:
            for out in self.wait():
                yield args[out.tag[1]], out
                left -= 1

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def describe(self) -> str:
        return f"{self.name} ({self.workers} worker{'s' if self.workers != 1 else ''})"


class SerialExecutor(CellExecutor):
    """Runs each call in the calling process when ``wait`` is called (one per call)."""

    name = "serial"

    def __init__(self):
        self._queue: deque = deque()

    def submit(self, fn, arg, tag=None):
        self._queue.append((fn, arg, tag))

    def wait(self, timeout=None):
        if not self._queue:
            return []
        fn, arg, tag = self._queue.popleft()
        try:
            return [Outcome(tag, True, fn(arg))]
        except Exception as exc:  # noqa: BLE001 - any failure of a case is an outcome, not a crash
            return [Outcome(tag, False, exc)]

    @property
    def n_pending(self):
        return len(self._queue)

    def cancel_pending(self):
        self._queue.clear()


class LocalPoolExecutor(CellExecutor):
    """``workers`` local processes (default ``os.cpu_count()``)."""

    name = "local"

    def __init__(self, workers: Optional[int] = None, start_method: str = "spawn", retries: int = 2):
        n = (os.cpu_count() or 1) if workers is None else workers
        if not isinstance(n, int) or n < 1:
            raise ValueError(f"workers = {workers!r} is not allowed: must be an integer >= 1")
        self.workers = n
        self.retries = retries  #: resubmissions of a call whose worker process died
        self.restarts = 0  #: pools replaced after a worker died
        self._ctx = mp.get_context(start_method)
        self._pool = cf.ProcessPoolExecutor(max_workers=n, mp_context=self._ctx)
        self._futures: dict = {}
        self._calls: dict = {}  # future -> (fn, arg, attempt, pool generation)
        self._gen = 0

    def submit(self, fn, arg, tag=None, _attempt=0):
        try:
            fut = self._pool.submit(fn, arg)
        except cf.process.BrokenProcessPool:
            self._restart()
            fut = self._pool.submit(fn, arg)
        self._futures[fut] = tag
        self._calls[fut] = (fn, arg, _attempt, self._gen)

    def _restart(self):
        self.restarts += 1
        self._gen += 1
        self._pool.shutdown(wait=False, cancel_futures=True)
        self._pool = cf.ProcessPoolExecutor(max_workers=self.workers, mp_context=self._ctx)

    def wait(self, timeout=None):
        if not self._futures:
            return []
        done, _ = cf.wait(list(self._futures), timeout=timeout, return_when=cf.FIRST_COMPLETED)
        out, retry, broken_now = [], [], False
        for fut in done:
            tag = self._futures.pop(fut)
            fn, arg, attempt, gen = self._calls.pop(fut, (None, None, 0, -1))
            if fut.cancelled():
                continue
            exc = fut.exception()
            if exc is None:
                out.append(Outcome(tag, True, fut.result()))
            elif isinstance(exc, cf.process.BrokenProcessPool) and fn is not None:
                # its worker died (killed, segfault, out of memory): the whole pool broke with it,
                # so every call in flight failed; run them again on a fresh pool, not a result
                broken_now |= gen == self._gen
                if attempt < self.retries:
                    retry.append((fn, arg, tag, attempt + 1))
                else:
                    out.append(Outcome(tag, False, cf.process.BrokenProcessPool(
                        f"the worker process died {attempt + 1} times running this call")))
            else:
                out.append(Outcome(tag, False, exc))
        if broken_now:
            self._restart()
        for fn, arg, tag, attempt in retry:
            self.submit(fn, arg, tag, _attempt=attempt)
        return out

    @property
    def n_pending(self):
        return len(self._futures)

    def cancel_pending(self):
        for fut in list(self._futures):
            if fut.cancel():
                self._futures.pop(fut)
        self._futures.clear()
        self._calls.clear()  # running ones finish in the background; their results are dropped

    def close(self):
        self._pool.shutdown(wait=False, cancel_futures=True)


class DaskExecutor(CellExecutor):
    """Calls run on a dask.distributed cluster: ``address`` of its scheduler (``tcp://host:8786``)
    or an existing ``distributed.Client`` (``client=``, not closed by :meth:`close`)."""

    name = "dask"

    def __init__(self, address: Optional[str] = None, client=None, timeout_s: float = 30.0):
        try:
            import distributed
        except ImportError:
            raise ImportError("running on a dask scheduler needs the 'distributed' package: "
                              "pip install 'amra[dask]'") from None
        self._distributed = distributed
        if client is None:
            if not address:
                raise ValueError("scheduler = '' is not allowed: give the scheduler address, e.g. tcp://host:8786")
            try:
                client = distributed.Client(address, timeout=timeout_s)
            except (OSError, TimeoutError) as exc:
                raise ValueError(f"scheduler = {address!r}: cannot connect ({exc})") from None
            self._own = True
        else:
            self._own = False
        self.client = client
        self.workers = max(1, sum(w.get("nthreads", 1) for w in client.scheduler_info().get("workers", {}).values()))
        self._futures: dict = {}
        self._ac = distributed.as_completed()

    def submit(self, fn, arg, tag=None):
        fut = self.client.submit(fn, arg, pure=False)
        self._futures[fut.key] = (fut, tag)
        self._ac.add(fut)

    def wait(self, timeout=None):
        if not self._futures:
            return []
        t_end = None if timeout is None else time.monotonic() + timeout
        out = []
        while not out:
            batch = self._ac.next_batch(block=False)
            if not batch:
                if t_end is not None and time.monotonic() >= t_end:
                    return []
                time.sleep(0.01)
                continue
            for fut in batch:
                item = self._futures.pop(fut.key, None)
                if item is None:  # cancelled earlier
                    continue
                tag = item[1]
                if fut.status == "finished":
                    out.append(Outcome(tag, True, fut.result()))
                elif fut.status == "cancelled":
                    continue
                else:
                    try:
                        exc = fut.exception()
                    except Exception as e:  # noqa: BLE001
                        exc = e
                    out.append(Outcome(tag, False, exc if isinstance(exc, BaseException) else RuntimeError(str(exc))))
        return out

    @property
    def n_pending(self):
        return len(self._futures)

    def cancel_pending(self):
        futs = [f for f, _ in self._futures.values()]
        self._futures.clear()
        if futs:
            self.client.cancel(futs)
        self._ac = self._distributed.as_completed()

    def close(self):
        self.cancel_pending()
        if self._own:
            self.client.close()

    def describe(self):
        return f"dask ({self.client.scheduler.address}, {self.workers} threads)"


def make_executor(workers: Optional[int] = None, scheduler: Optional[str] = None) -> CellExecutor:
    """The executor for ``--workers``/``--scheduler``: dask when a scheduler address is given,
    in-process serial for ``workers=1``, else a local pool of ``workers`` processes."""
    if scheduler:
        return DaskExecutor(scheduler)
    if workers is not None and (not isinstance(workers, int) or workers < 1):
        raise ValueError(f"workers = {workers!r} is not allowed: must be an integer >= 1")
    if workers == 1:
        return SerialExecutor()
    return LocalPoolExecutor(workers)
