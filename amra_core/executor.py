"""Where map cells run: one small interface over a local process pool, in-process serial
execution, and a dask.distributed cluster.

Interface (:class:`CellExecutor`): ``submit(fn, arg, tag)`` queues ``fn(arg)``; ``wait(timeout)``
blocks until at least one queued call has finished (or ``timeout`` [s] passed) and returns the
finished ones as :class:`Outcome` (``tag``, ``ok``, ``value`` or the exception); ``cancel_pending()``
drops what has not started; ``close()`` releases the workers. ``map_unordered(fn, args)`` is the
batch form: submit them all and yield ``(arg, Outcome)`` as they complete.

* :class:`LocalPoolExecutor` (default): ``concurrent.futures.ProcessPoolExecutor`` with ``workers``
  processes (default ``os.cpu_count()``). Processes rather than threads: the kernels release the
  GIL, but trim and the eigen-analysis are largely Python/SciPy. How they start
  (:func:`start_method_for_pool`): forked from a single-threaded parent on Linux (``amra map``,
  a script), so they begin with the parent's imports and already loaded kernels; ``spawn`` from
  any parent holding threads (a dashboard, a dask client), which a forked child could deadlock on a
  lock some thread held. A spawned worker pays the import and loads the Numba-cached kernels
  (0.5-0.9 s) before its first task.
* :class:`SerialExecutor`: in the calling process, one call per ``wait`` (``workers=1``).
* :class:`DaskExecutor`: ``distributed.Client(address)`` (``pip install 'amra[dask]'``); the workers
  must be able to import ``amra_core``.

An exception inside ``fn`` becomes ``Outcome(ok=False)``; it never escapes ``wait``.

A call whose worker *died* (segfault, out of memory, ``kill -9``; a dask ``KilledWorker``) is not
the call's answer: the local pool and dask resubmit it on fresh workers, transparently, up to
``max_retries`` times (default :data:`MAX_RETRIES`). Only then ``wait`` returns
``Outcome(ok=False, value=WorkerDied(...))``; :attr:`Outcome.worker_died` tells such outcomes
apart, and callers must not store them as results.

Local pool workers watch their parent: when it dies (``kill -9``, SIGTERM), they exit within about
a second (:func:`_watch_parent`), so no orphaned workers or resource tracker are left behind.
"""
from __future__ import annotations

import concurrent.futures as cf
import multiprocessing as mp
import os
import sys
import threading
import time
from collections import deque
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Iterator, Optional


MAX_RETRIES = 3  #: resubmissions of a call whose worker died, before it is reported failed
#: ``--workers`` above this multiple of the CPU count only adds memory and contention
MAX_WORKERS_PER_CORE = 4


class WorkerDied(RuntimeError):
    """The worker process running a call died (crash, out of memory, killed) every time it was tried."""


def worker_cap() -> int:
    """The most local worker processes allowed: :data:`MAX_WORKERS_PER_CORE` per CPU core."""
    return MAX_WORKERS_PER_CORE * (os.cpu_count() or 1)


def cap_workers(workers: Optional[int]) -> tuple[Optional[int], str]:
    """``(workers, message)``: ``workers`` capped at :func:`worker_cap`; ``message`` says so (or is '')."""
    cap = worker_cap()
    if workers is not None and workers > cap:
        return cap, (f"--workers {workers} is more than {MAX_WORKERS_PER_CORE} per CPU core "
                     f"({os.cpu_count() or 1} cores): using {cap}")
    return workers, ""


def start_method_for_pool() -> str:
    """``'fork'`` on Linux when this process runs no other thread than the caller's, else
    ``'spawn'``. A forked worker skips the import and the kernel loading a spawned one pays first;
    a parent's other threads (Tornado's, a dask client's, an earlier pool's manager) may hold locks
    a forked child would wait on for ever, so any of them means ``spawn``. The numbers are the
    same either way (tests/core/test_executor.py)."""
    if sys.platform.startswith("linux") and threading.active_count() == 1 \
            and "fork" in mp.get_all_start_methods():
        return "fork"
    return "spawn"


def _start_worker(parent_pid: int, nice: int = 0) -> None:
    """Worker initializer: ``nice`` added to the worker's niceness, one BLAS thread
    (:func:`~amra_core.blas_threads.use_one_blas_thread`), then :func:`_watch_parent`. A forked
    worker gets back the default SIGTERM action: a handler its parent installed (``amra map``
    stops the map on SIGTERM) must not run in it, so the pool's terminate stops it."""
    import signal
    try:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
    except (ValueError, OSError):
        pass
    from .blas_threads import use_one_blas_thread
    use_one_blas_thread()
    if nice > 0:
        try:
            os.nice(nice)
        except OSError:
            pass
    _watch_parent(parent_pid)


def _watch_parent(parent_pid: int, poll_s: float = 0.5) -> None:
    """Worker initializer: exit this worker as soon as ``parent_pid`` is no longer its parent.

    On Linux ``prctl(PR_SET_PDEATHSIG, SIGKILL)`` is not used on its own because it fires when the
    parent *thread* that started the worker ends (a dashboard thread can create a pool another one
    uses); a daemon thread polling ``os.getppid()`` is process-level and portable."""
    def watch():
        while True:
            if os.getppid() != parent_pid:
                os._exit(0)  # parent gone: we were re-parented (to init or a subreaper)
            time.sleep(poll_s)

    if os.getppid() != parent_pid:
        os._exit(0)
    try:  # Ctrl-C reaches the whole process group: the parent alone decides, and stops us
        import signal
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    except (ValueError, OSError):
        pass
    threading.Thread(target=watch, name="amra-parent-watch", daemon=True).start()


def _is_worker_death(exc: BaseException) -> bool:
    """True for the exceptions that mean "the worker died", not "the call failed"."""
    if isinstance(exc, cf.process.BrokenProcessPool):
        return True
    name = type(exc).__name__
    return name in ("KilledWorker", "CommClosedError", "WorkerDied") and not isinstance(exc, WorkerDied)


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

    @property
    def worker_died(self) -> bool:
        """The call has no answer because its worker died on every try (never store it)."""
        return not self.ok and isinstance(self.value, WorkerDied)


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
    """``workers`` local processes (default ``os.cpu_count()``, at most :func:`worker_cap`).

    A call whose worker died is resubmitted on a fresh pool up to ``max_retries`` times (every call
    in flight when a worker dies is lost with it, so all of them are retried); after that its
    outcome is ``WorkerDied``. Workers exit when this process dies."""

    name = "local"

    def __init__(self, workers: Optional[int] = None, start_method: str = "auto",
                 max_retries: int = MAX_RETRIES, nice: int = 0):
        n = (os.cpu_count() or 1) if workers is None else workers
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            raise ValueError(f"workers = {workers!r} is not allowed: must be an integer >= 1")
        if n > worker_cap():
            raise ValueError(f"workers = {workers!r} is not allowed: at most {worker_cap()} "
                             f"({MAX_WORKERS_PER_CORE} per CPU core)")
        self.workers = n
        self.nice = int(nice)  #: added to the workers' niceness (a server's maps yield to its runs)
        self.max_retries = int(max_retries)
        if start_method not in ("auto", *mp.get_all_start_methods()):
            raise ValueError(f"start_method = {start_method!r} is not allowed: choose 'auto' or one of "
                             f"{', '.join(mp.get_all_start_methods())}")
        self.start_method = start_method  #: 'auto': :func:`start_method_for_pool` at each (re)start
        self._futures: dict = {}  # future -> [fn, arg, tag, deaths]
        self._pool = self._new_pool()
        self.restarts = 0
        self._abandoned = False

    def _new_pool(self):
        method = start_method_for_pool() if self.start_method == "auto" else self.start_method
        return cf.ProcessPoolExecutor(max_workers=self.workers, mp_context=mp.get_context(method),
                                      initializer=_start_worker, initargs=(os.getpid(), self.nice))

    def _submit(self, item):
        try:
            fut = self._pool.submit(item[0], item[1])
        except (cf.process.BrokenProcessPool, RuntimeError):  # broken, or shut down by a restart
            self._restart()
            fut = self._pool.submit(item[0], item[1])
        self._futures[fut] = item

    def submit(self, fn, arg, tag=None):
        self._submit([fn, arg, tag, 0])

    def _restart(self):
        old = self._pool
        self._pool = self._new_pool()
        self.restarts += 1
        _terminate_pool(old)

    def wait(self, timeout=None):
        t_end = None if timeout is None else time.monotonic() + timeout
        while self._futures:
            left = None if t_end is None else max(0.0, t_end - time.monotonic())
            done, _ = cf.wait(list(self._futures), timeout=left, return_when=cf.FIRST_COMPLETED)
            out, retry, broken = [], [], False
            for fut in done:
                item = self._futures.pop(fut)
                if fut.cancelled():
                    continue
                exc = fut.exception()
                if exc is None:
                    out.append(Outcome(item[2], True, fut.result()))
                elif _is_worker_death(exc):
                    broken = True
                    item[3] += 1
                    if item[3] > self.max_retries:
                        out.append(Outcome(item[2], False, WorkerDied(
                            f"the worker process died on each of {item[3]} tries ({type(exc).__name__}); "
                            f"the call was not retried further")))
                    else:
                        retry.append(item)
                else:
                    out.append(Outcome(item[2], False, exc))
            if broken:
                # the broken pool fails every call it holds: collect them, then one fresh pool for all
                for fut in list(self._futures):
                    if fut.done() and fut.exception() is not None and _is_worker_death(fut.exception()):
                        item = self._futures.pop(fut)
                        item[3] += 1
                        retry.append(item)
                for fut, item in list(self._futures.items()):  # still queued on the broken pool
                    if not fut.done():
                        self._futures.pop(fut)
                        retry.append(item)
                self._restart()
                for item in retry:
                    self._submit(item)
            if out or (t_end is not None and time.monotonic() >= t_end):
                return out
        return []

    @property
    def n_pending(self):
        return len(self._futures)

    def cancel_pending(self):
        for fut in list(self._futures):
            if not fut.cancel():
                self._abandoned = True  # running: its result is dropped; close() stops the worker
        self._futures.clear()

    def close(self):
        """Release the workers: idle ones exit and are waited for (an interpreter that exits while
        the pool's manager thread still closes its pipes prints a ``Bad file descriptor`` traceback,
        Python 3.11); workers running cells nobody will read are stopped."""
        if self._abandoned or self._futures:
            _terminate_pool(self._pool)  # do not wait for cells nobody will read
        else:
            self._pool.shutdown(wait=True, cancel_futures=True)
        self._futures.clear()


def _terminate_pool(pool) -> None:
    """Shut ``pool`` down without waiting and stop its worker processes."""
    procs = list((getattr(pool, "_processes", None) or {}).values())
    try:
        pool.shutdown(wait=False, cancel_futures=True)
    except Exception:  # noqa: BLE001 - a broken pool may complain; its workers are stopped below
        pass
    for p in procs:
        try:
            if p.is_alive():
                p.terminate()
        except Exception:  # noqa: BLE001
            pass
    for p in procs:
        try:
            p.join(2.0)
            if p.is_alive():
                p.kill()
        except Exception:  # noqa: BLE001
            pass


#: scheduler address schemes accepted by :class:`DaskExecutor`
DASK_SCHEMES = ("tcp://", "tls://", "inproc://", "ucx://")


def dask_security(address: str, tls_ca_file=None, tls_cert=None, tls_key=None):
    """``distributed.Security`` for a ``tls://`` address, else None. The files come from the
    arguments, else the environment (``AMRA_DASK_TLS_CA``, ``AMRA_DASK_TLS_CERT``,
    ``AMRA_DASK_TLS_KEY``), else Dask's own configuration (``distributed.comm.tls.*``)."""
    if not address.startswith("tls://"):
        return None
    from distributed.security import Security
    ca = tls_ca_file or os.environ.get("AMRA_DASK_TLS_CA")
    cert = tls_cert or os.environ.get("AMRA_DASK_TLS_CERT")
    key = tls_key or os.environ.get("AMRA_DASK_TLS_KEY")
    if not (ca or cert):
        return Security(require_encryption=True)  # distributed.comm.tls.* from the Dask config
    for what, f in (("CA", ca), ("certificate", cert), ("key", key)):
        if f and not os.path.isfile(f):
            raise ValueError(f"scheduler = {address!r}: TLS {what} file {f!r} does not exist")
    return Security(tls_ca_file=ca, tls_client_cert=cert, tls_client_key=key or None, require_encryption=True)


class DaskExecutor(CellExecutor):
    """Calls run on a dask.distributed cluster: ``address`` of its scheduler (``tcp://host:8786``,
    ``tls://host:8786`` with certificates, see :func:`dask_security`) or an existing
    ``distributed.Client`` (``client=``, not closed by :meth:`close`).

    Dask deserialises (unpickles) what it receives: use a cluster you trust, and ``tls://`` on a
    shared network. A call whose worker died (``KilledWorker``, lost connection) is resubmitted up
    to ``max_retries`` times, then reported as ``WorkerDied``."""

    name = "dask"

    def __init__(self, address: Optional[str] = None, client=None, timeout_s: float = 30.0,
                 max_retries: int = MAX_RETRIES, security=None):
        try:
            import distributed
        except ImportError:
            raise ImportError("running on a dask scheduler needs the 'distributed' package: "
                              "pip install 'amra[dask]'") from None
        self._distributed = distributed
        self.max_retries = int(max_retries)
        if client is None:
            if not address or not isinstance(address, str):
                raise ValueError("scheduler = '' is not allowed: give the scheduler address, e.g. tcp://host:8786")
            if "://" in address and not address.startswith(DASK_SCHEMES):
                raise ValueError(f"scheduler = {address!r} is not allowed: the address must start with "
                                 f"{', '.join(DASK_SCHEMES)} (or be host:port)")
            if security is None:
                security = dask_security(address)
            try:
                kw = {"security": security} if security is not None else {}
                client = distributed.Client(address, timeout=timeout_s, **kw)
            except (OSError, TimeoutError, ValueError, TypeError) as exc:
                raise ValueError(f"scheduler = {address!r}: cannot connect ({type(exc).__name__}: {exc})") from None
            self._own = True
        else:
            self._own = False
        self.client = client
        self.workers = max(1, sum(w.get("nthreads", 1) for w in client.scheduler_info().get("workers", {}).values()))
        self._futures: dict = {}  # key -> (future, [fn, arg, tag, deaths])
        self._ac = distributed.as_completed()

    def _submit(self, item):
        fut = self.client.submit(item[0], item[1], pure=False)
        self._futures[fut.key] = (fut, item)
        self._ac.add(fut)

    def submit(self, fn, arg, tag=None):
        self._submit([fn, arg, tag, 0])

    def wait(self, timeout=None):
        if not self._futures:
            return []
        t_end = None if timeout is None else time.monotonic() + timeout
        out = []
        while not out:
            batch = self._ac.next_batch(block=False)
            if not batch:
                if not self._futures or (t_end is not None and time.monotonic() >= t_end):
                    return []
                time.sleep(0.01)
                continue
            for fut in batch:
                entry = self._futures.pop(fut.key, None)
                if entry is None:  # cancelled earlier
                    continue
                item = entry[1]
                tag = item[2]
                if fut.status == "finished":
                    out.append(Outcome(tag, True, fut.result()))
                elif fut.status == "cancelled":
                    continue
                else:
                    try:
                        exc = fut.exception()
                    except Exception as e:  # noqa: BLE001
                        exc = e
                    if not isinstance(exc, BaseException):
                        exc = RuntimeError(str(exc))
                    if _is_worker_death(exc):
                        item[3] += 1
                        if item[3] <= self.max_retries:
                            self._submit(item)
                            continue
                        exc = WorkerDied(f"the dask worker running it died on each of {item[3]} tries "
                                         f"({type(exc).__name__}: {exc}); the call was not retried further")
                    out.append(Outcome(tag, False, exc))
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
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise ValueError(f"workers = {workers!r} is not allowed: must be an integer >= 1")
    if workers == 1:
        return SerialExecutor()
    return LocalPoolExecutor(workers)
