"""Running a map: columns handed to an executor (or walked in this process, point by point), the
result store read and written per column, cancellation, progress (:class:`MapRun`)."""
from __future__ import annotations

import math
import threading
import time
import uuid
from dataclasses import replace
from typing import Callable, Iterator, Optional

from ..executor import CellExecutor, LocalPoolExecutor, SerialExecutor
from ..stability import CellResult
from .result import BoundaryMap, _summarise
from .spec import MapSpec, _gj_round, solver_fingerprint
from .tasks import ColumnResult, cells_of_walk, compute_column, failed_cell

#: cells per column assumed by the progress estimate until a column is finished
CELLS_PER_COLUMN_GUESS = 30


class MapRun:
    """Iterate to get each finished cell (:class:`CellResult`) as soon as it is known; then
    :meth:`result` gives the :class:`BoundaryMap` (partial if cancelled or stopped early).
    ``done``: cells handed out so far; ``estimated_total``: a rough total for progress bars."""

    def __init__(self, spec: MapSpec, executor: Optional[CellExecutor] = None, store=None,
                 cancel: Optional[threading.Event] = None, workers: Optional[int] = None):
        self.spec = spec
        self.store = store
        self.cancel = cancel or threading.Event()
        self._own_executor = executor is None
        self._executor = executor
        self._workers = workers
        self.by_col: dict = {cg: {} for cg in spec.cg_values}
        self.info: dict = {}
        self.cached = 0
        self.done = 0
        self.in_flight = 0
        #: this run's mark on the columns it hands to the executor: an executor shared with other
        #: runs (a server's pool, a Dask cluster) may return their results too, which this run skips
        self._token = uuid.uuid4().hex
        self._t0 = None
        self.wall_time_s = 0.0
        self.cancelled = False
        self.phases: dict = {}
        self._finished = False
        self.n_trims = 0

    @property
    def estimated_total(self) -> int:
        open_cols = [cg for cg in self.spec.cg_values if cg not in self.info]
        partial = sum(len(self.by_col[cg]) for cg in open_cols)
        return self.done - partial + sum(max(CELLS_PER_COLUMN_GUESS, len(self.by_col[cg]) + 1) for cg in open_cols)

    def _cached_column(self, cg) -> Optional[ColumnResult]:
        """A finished column from the store: its record rides on the cell at ``gj_max`` (always part
        of a walk), so the store holds one row per cell; None if absent or for another range/tolerance."""
        if self.store is None:
            return None
        spec = self.spec
        top = self.store.get(spec.key(cg, _gj_round(spec.gj_max)))
        rec = None if top is None else top.get("column")
        if not isinstance(rec, dict) or rec.get("key") != spec.column_key(cg):
            return None
        keys = [spec.key(cg, g) for g in rec.get("gj", [])]
        got = self.store.get_many(keys) if hasattr(self.store, "get_many") else {k: self.store.get(k) for k in keys}
        if not keys or any(got.get(k) is None for k in keys):
            return None
        cells = [replace(CellResult.from_dict(got[k]), cg=cg, gj_nm2=g) for k, g in zip(keys, rec["gj"])]
        crit = rec.get("critical_gj")
        crit = math.inf if crit == "inf" else crit
        return ColumnResult(cg, cells, rec.get("intervals", []), crit, rec.get("fold_gj"))

    def _store_column(self, col: ColumnResult) -> None:
        if self.store is None or col.failed or col.cancelled:
            return
        spec = self.spec
        top_gj = _gj_round(spec.gj_max)
        crit = "inf" if col.critical_gj is not None and math.isinf(col.critical_gj) else col.critical_gj
        record = {"key": spec.column_key(col.cg), "gj": [c.gj_nm2 for c in col.cells], "intervals": col.intervals,
                  "critical_gj": crit, "fold_gj": col.fold_gj}
        items, top = [], None
        for c in col.cells:  # the top cell last: its column record says the column is complete
            if c.gj_nm2 == top_gj:
                top = c
            else:
                items.append((spec.key(col.cg, c.gj_nm2), spec.case_params(col.cg, c.gj_nm2), c))
        if top is not None:
            items.append((spec.key(col.cg, top_gj), spec.case_params(col.cg, top_gj), {**top.to_dict(), "column": record}))
        self._put(items)

    def _finish_column(self, col: ColumnResult, cached: bool, streamed: bool):
        """Record a finished column; yields the cells not handed out yet."""
        self.info[col.cg] = {"intervals": col.intervals, "critical_gj": col.critical_gj, "fold_gj": col.fold_gj,
                             "failed": col.failed, "cancelled": col.cancelled}
        self.n_trims += col.n_trims
        if streamed:  # cells already handed out point by point: take the final (time-judged) versions
            self.by_col[col.cg] = {c.gj_nm2: c for c in col.cells}
            return []
        out = []
        for c in col.cells:
            self.by_col[col.cg][c.gj_nm2] = c
            self.done += 1
            self.cached += bool(cached)
            out.append(c)
        return out

    def _crashed_column(self, cg: float, reason: str) -> ColumnResult:
        """A column whose worker died: failed cells on the probe grid, shown in this run only."""
        cells = [failed_cell(cg, _gj_round(g), f"worker: {reason}") for g in self.spec.coarse_gj]
        return ColumnResult(cg, cells, [], None, None, failed=True)

    def __iter__(self) -> Iterator[CellResult]:
        if self._finished:
            return
        spec = self.spec
        self._t0 = time.perf_counter()
        if self._executor is None:
            w = self._workers
            self._executor = SerialExecutor() if w == 1 else LocalPoolExecutor(w)
        ex = self._executor
        self._ex_name = ex.describe()
        try:
            todo = []
            for cg in spec.cg_values:
                hit = self._cached_column(cg)
                if hit is not None:
                    for c in self._finish_column(hit, True, False):
                        yield c
                        if self.cancel.is_set():
                            self.cancelled = True
                            return
                else:
                    todo.append(cg)
            if isinstance(ex, SerialExecutor):
                yield from self._run_inline(todo)
                return
            for cg in todo:
                ex.submit(compute_column, spec.column_task(cg), (self._token, cg))
                self.in_flight += 1
            while self.in_flight:
                if self.cancel.is_set():
                    self.cancelled = True
                    return
                for out in ex.wait(timeout=0.1):
                    if not (isinstance(out.tag, tuple) and out.tag[0] == self._token):
                        continue  # another run's column, on a shared executor
                    self.in_flight -= 1
                    col = out.value if out.ok else self._crashed_column(out.tag[1], out.reason)
                    if out.ok:
                        self._store_column(col)
                    for c in self._finish_column(col, False, False):
                        yield c
                        if self.cancel.is_set():
                            self.cancelled = True
                            return
        finally:
            if self.cancelled or self.in_flight:
                ex.cancel_pending()
                self.in_flight = 0
            if self._own_executor:
                ex.close()
            self.wall_time_s = time.perf_counter() - self._t0
            self._finished = True

    def _run_inline(self, todo: list) -> Iterator[CellResult]:
        """Serial execution in this process: the column walks in a helper thread and every point is
        handed out as it is found (the dashboard's progressive map)."""
        import queue
        spec = self.spec
        for cg in todo:
            q: queue.Queue = queue.Queue()
            task = spec.column_task(cg)
            col_cancel = threading.Event()

            def on_point(p, q=q):
                q.put(("point", p))

            def work(task=task, q=q, col_cancel=col_cancel):
                try:
                    q.put(("done", compute_column(task, on_point=on_point, cancel=col_cancel)))
                except BaseException as exc:  # noqa: BLE001 - reported as a crashed column
                    q.put(("crash", f"{type(exc).__name__}: {exc}"))

            th = threading.Thread(target=work, name=f"amra-column-{cg}", daemon=True)
            th.start()
            top_omega = None
            try:
                while True:
                    if self.cancel.is_set():
                        self.cancelled = True
                        return
                    try:
                        kind, item = q.get(timeout=0.1)
                    except queue.Empty:
                        continue
                    if kind == "point":
                        if item.branch == "normal" and top_omega is None:
                            top_omega = item.trim.omega_rad_s
                        cell = cells_of_walk(cg, [item], top_omega)[0]
                        if spec.method == "time":
                            continue  # judged by time marching at the end of the column
                        self.by_col[cg][cell.gj_nm2] = cell
                        self.done += 1
                        yield cell
                        if self.cancel.is_set():
                            self.cancelled = True
                            return
                        continue
                    col = item if kind == "done" else self._crashed_column(cg, item)
                    if kind == "done":
                        self._store_column(col)
                    streamed = spec.method != "time" and kind == "done"
                    for c in self._finish_column(col, False, streamed):
                        yield c
                    break
            finally:
                col_cancel.set()  # a walk still running (cancelled, or the consumer stopped) ends at its next point
                th.join(timeout=30.0)

    def _put(self, items: list) -> None:
        """Store a finished column's cells ``(key, params, cell)`` (one transaction where the store
        has ``put_many``); a store that fails while writing (disk full, locked for longer than its
        busy timeout) is reported once and the map carries on without it."""
        try:
            if hasattr(self.store, "put_many"):
                self.store.put_many(items)
            else:
                for key, params, cell in items:
                    self.store.put(key, params, cell)
        except Exception as exc:  # noqa: BLE001 - the map is worth more than its cache
            import warnings
            self.store_error = f"result store write failed ({type(exc).__name__}: {exc}); continuing without it"
            warnings.warn(self.store_error, RuntimeWarning, stacklevel=2)
            self.store = None

    def result(self) -> BoundaryMap:
        """The map: drains the iteration first if it has not started; called while the cells are
        still being iterated (a consumer's progress view), it summarises the cells found so far
        without restarting the walk (a second pass would count this map's own stored columns as
        read from the store)."""
        if not self._finished and self._t0 is None:
            for _ in self:
                pass
        columns, boundaries = _summarise(self.spec, self.by_col, self.info)
        cells = [c for cg in self.spec.cg_values for c in sorted(self.by_col[cg].values(), key=lambda c: c.gj_nm2)]
        return BoundaryMap(self.spec, cells, columns, boundaries, len(cells), self.cached, self.wall_time_s,
                           self.cancelled, getattr(self, "_ex_name", ""), dict(self.phases))


def iter_map(spec: MapSpec, executor: Optional[CellExecutor] = None, store=None,
             cancel: Optional[threading.Event] = None, workers: Optional[int] = None) -> MapRun:
    """The map as an iterator of finished cells; ``.result()`` afterwards gives the map."""
    return MapRun(spec, executor, store, cancel, workers)


def run_map(spec: MapSpec, executor: Optional[CellExecutor] = None, store=None,
            on_cell: Optional[Callable[[CellResult], None]] = None,
            cancel: Optional[threading.Event] = None, workers: Optional[int] = None) -> BoundaryMap:
    """Compute the map (see the module docstring). ``executor``: where columns run (default: a local
    pool of ``workers`` processes, closed at the end; ``workers=1``: in this process, cells handed
    out point by point); ``store``: a :class:`~amra_core.store.CellStore` (or a path to one);
    ``on_cell(cell)``: called with every finished cell; ``cancel``: a ``threading.Event`` -- when
    set, the partial map is returned."""
    own_store = False
    if store is not None and not hasattr(store, "get"):
        from ..store import CellStore
        store = CellStore(store, solver=solver_fingerprint())
        own_store = True
    try:
        run = MapRun(spec, executor, store, cancel, workers)
        for cell in run:
            if on_cell is not None:
                on_cell(cell)
        return run.result()
    finally:
        if own_store:
            store.close()
