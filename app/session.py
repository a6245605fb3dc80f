"""One browser session's run: the thread that advances it, and the news it hands to the views.

The run thread trims the case (in the run process pool: the trim holds the GIL), advances the
:class:`~amra_core.simulation.Simulation` in chunks paced to the playback speed, applies live
GJ/EA/CG changes between chunks (the run continues from its state) and posts typed events
(:mod:`app.events`). Views subscribe to the types they draw; :meth:`Session.deliver` hands them
over on the event loop at most :data:`DELIVERY_PERIOD_S` apart. :meth:`Session.start`,
:meth:`~Session.stop` and :meth:`~Session.close` only signal, never wait for a thread; a replaced
run's late events are dropped by run id.
"""
from __future__ import annotations

import logging
import queue
import threading
import time
from collections import defaultdict
from typing import Callable, Optional

import numpy as np
import panel as pn
from panel.io.state import set_curdoc

from amra_core.model import Y_OMEGA
from amra_core.pose import rotor_pose
from amra_core.scenario import Scenario, apply_change
from amra_core.simulation import Case, Simulation

from .events import Applied, Disc, Finished, Notice, Pose, Rows, RunStatus, Started, VerdictNews

TICK_S = 0.06  #: wall-clock period of a chunk [s]
DELIVERY_PERIOD_S = 0.1  #: shortest interval between deliveries to the views [s]: 10 updates/s
TRIM_PROGRESS_PERIOD_S = 0.5  #: period of the trim's progress line [s]
STOPPED_IN_TRIM = "stopped while finding the trimmed autorotation (nothing was run)"  #: the run line then
VIEWS_PERIOD_S = 1.0  #: wall-clock period of the clock, the "so far" verdict and the disc during a run [s]
#: share of a core a run's "so far" verdict may take: the verdict reads the whole history (37 ms at
#: 120 s of a forward-flight run here), so on long runs it comes less often than every VIEWS_PERIOD_S
#: (32 sessions re-judging every second starved the server's event loop: no live change got through)
VERDICT_CPU_SHARE = 0.02
log = logging.getLogger("amra.session")


def end_status(sim: Simulation, stopped: bool) -> str:
    """The solver status of a run that ended: ``completed`` when it reached its end, ``stopped`` when
    the user stopped it first (it read "completed" at t = 6 s of a 20 s run), else the solver's own."""
    if sim.status != "running":
        return sim.status
    return "stopped" if stopped and sim.t < sim.case.t_end_s - 1e-9 else "completed"


def next_verdict_in_s(cost_s: float) -> float:
    """Wall time [s] until the next "so far" verdict of a run whose last one took ``cost_s`` [s]."""
    return max(VIEWS_PERIOD_S, cost_s / VERDICT_CPU_SHARE)


class Throttle:
    """The app's one rate limiter: ``fn`` runs on the session's event loop soon after a
    :meth:`kick` (from any thread; kicks during a wait coalesce), at most once per period, and
    never while nobody kicks. Without a served document a kick only marks the work as due, and
    :meth:`run_due` runs it in the caller's thread (tests, scripts)."""

    def __init__(self, fn: Callable[[], None], period_s: float, doc=None):
        self.fn, self.period_s, self.doc = fn, float(period_s), doc
        self._lock = threading.Lock()
        self._due, self._last, self.closed = False, -1e9, False

    def kick(self) -> None:
        with self._lock:
            if self._due or self.closed:
                return
            self._due = True
        if self.doc is not None:  # pn.state.execute: a next-tick callback, the document locked
            with set_curdoc(self.doc):
                pn.state.execute(self._arm, schedule=True)

    def _arm(self) -> None:  # on the event loop
        wait_s = self._last + self.period_s - time.monotonic()
        if wait_s > 0:
            self.doc.add_timeout_callback(self._timed, int(1000 * wait_s) + 1)
        else:
            self.run_due()

    def _timed(self) -> None:  # a Bokeh timeout callback: on the loop, document locked
        with set_curdoc(self.doc):
            self.run_due()

    def run_due(self) -> None:
        """Run the function if a kick asked for it."""
        with self._lock:
            if not self._due or self.closed:
                return
            self._due, self._last = False, time.monotonic()
        self.fn()


def new_simulation(case: Case) -> Simulation:
    """The trimmed Simulation of ``case`` (run in the run pool: picklable in and out)."""
    with np.errstate(all="ignore"):
        return Simulation(case)


class Session:
    def __init__(self, doc=None, run_pool=None):
        self.doc = doc if doc is not None and doc.session_context is not None else None
        self._inbox: queue.SimpleQueue = queue.SimpleQueue()
        self._handlers: dict = defaultdict(list)
        self._throttles: list = []
        self.delivery = self.throttle(self.deliver, DELIVERY_PERIOD_S)
        self.run_pool = run_pool
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: Optional[threading.Thread] = None
        self._pending: dict = {}
        self._speed = 1.0
        self.run_id = 0
        self.sim: Optional[Simulation] = None
        self._live_since: Optional[tuple] = None  #: (GJ, perf_counter) of a live change not yet delivered
        self.live_latencies_s: list = []  #: live change received -> first rows with it sent [s]

    # ------------------------------------------------------------------ the event loop
    def throttle(self, fn: Callable[[], None], period_s: float) -> Throttle:
        """A :class:`Throttle` on this session's loop, run by :meth:`pump` and closed with the session."""
        t = Throttle(fn, period_s, self.doc)
        self._throttles.append(t)
        return t

    def pump(self) -> None:
        """Run whatever is due now, in the caller's thread (tests and scripts without a server)."""
        for t in self._throttles:
            t.run_due()

    def soon(self, fn: Callable[[], None]) -> None:
        """Run ``fn`` on the event loop with the document locked (``pn.state.execute``), or at once
        without a served document: Panel hands a click to its watchers without the lock, and the
        plots' Bokeh sources may change only with it held."""
        if self.doc is None:
            fn()
        else:
            with set_curdoc(self.doc):
                pn.state.execute(fn, schedule=True)

    # ------------------------------------------------------------------ news
    def subscribe(self, event_type, handler) -> None:
        self._handlers[event_type].append(handler)

    def post(self, event) -> None:
        """Queue an event for the views (any thread)."""
        self._inbox.put(event)
        self.delivery.kick()

    def nobody_watches(self) -> bool:
        """True once the page's browser has gone: its last connection to this served session closed
        (a closed or crashed tab, a lost network). Bokeh destroys such a session (and so calls
        :meth:`close`) only after its unused-session lifetime, 15 s and more, while the run went on
        computing and pushing rows to the closed socket ("Failed sending message ...")."""
        ctx = self.doc.session_context if self.doc is not None else None
        served = getattr(ctx, "session", None)  # bokeh's ServerSession, its connection_count public
        return served is not None and served.connection_count == 0

    def deliver(self) -> None:
        """Hand the queued events to their subscribers, in order (event loop); consecutive rows
        computed with the same GJ go as one batch, and only the latest pose is drawn. With nobody
        watching (:meth:`nobody_watches`) the run is stopped and its news dropped."""
        if self.nobody_watches():
            self._stop.set()
            while True:
                try:
                    self._inbox.get_nowait()
                except queue.Empty:
                    return
        rows, pose = [], None
        while True:
            try:
                ev = self._inbox.get_nowait()
            except queue.Empty:
                break
            if getattr(ev, "run_id", self.run_id) != self.run_id:
                continue  # from a run that was replaced
            if isinstance(ev, Rows) and (not rows or rows[-1].gj_nm2 == ev.gj_nm2):
                rows.append(ev)
            elif isinstance(ev, Pose):
                pose = ev
            else:
                self._dispatch_rows(rows)
                rows = [ev] if isinstance(ev, Rows) else []
                if not rows:
                    self._dispatch(ev)
        self._dispatch_rows(rows)
        if pose is not None:
            self._dispatch(pose)

    def _dispatch(self, ev) -> None:
        for handler in self._handlers[type(ev)]:
            handler(ev)

    def _dispatch_rows(self, rows: list) -> None:
        rows = [r for r in rows if len(r.rows)]  # a chunk shorter than the output step has none
        if not rows:
            return
        ev = rows[0] if len(rows) == 1 else Rows(rows[-1].run_id, np.concatenate([r.rows for r in rows]),
                                                 rows[-1].gj_nm2, rows[-1].t_s)
        self._dispatch(ev)
        if self._live_since is not None and abs(ev.gj_nm2 - self._live_since[0]) <= 1e-9 * self._live_since[0]:
            self.live_latencies_s.append(time.perf_counter() - self._live_since[1])
            self._live_since = None
            log.info("live change to GJ %.4g N m²/rad: first rows with it sent %.3f s after it reached "
                     "the server", ev.gj_nm2, self.live_latencies_s[-1])

    # ------------------------------------------------------------------ control (never waits)
    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive() and not self._stop.is_set()

    def start(self, case: Case, speed: float = 1.0, changes: tuple = ()) -> int:
        """Start a run of ``case`` (the current one is told to stop), applying the scripted
        ``changes`` (``amra_core.scenario.LiveChange``) at their times; returns its run id."""
        self._stop.set()
        with self._lock:
            self.run_id += 1
            self._pending, self._speed = {}, float(speed)
            self._stop = stop = threading.Event()
            run_id = self.run_id
        self._thread = threading.Thread(target=self._loop, args=(case, tuple(changes), run_id, stop),
                                        name=f"amra-run-{run_id}", daemon=True)
        self._thread.start()
        return run_id

    def stop(self) -> None:
        """Stop the run at its next chunk (does not wait)."""
        self._stop.set()

    def forget(self) -> None:
        """Stop, and drop whatever the run still sends (Reset)."""
        self._stop.set()
        with self._lock:
            self.run_id += 1

    def close(self) -> None:
        self.stop()
        for t in self._throttles:
            t.closed = True

    def set_live(self, **values) -> None:
        """Queue GJ [N m²/rad], EA and CG [chord fractions] for the running Simulation."""
        with self._lock:
            self._pending.update({k: v for k, v in values.items() if v is not None})
        if "gj_nm2" in values:
            self._live_since = (float(values["gj_nm2"]), time.perf_counter())
        log.debug("live change received: %s", values)

    def set_speed(self, speed: float) -> None:
        with self._lock:
            self._speed = float(speed)

    # ------------------------------------------------------------------ the run thread
    def _loop(self, case: Case, changes: tuple, run_id: int, stop: threading.Event) -> None:
        post = self.post
        post(RunStatus(run_id, "trimming", "finding the trimmed autorotation ..."))
        try:
            scenario = Scenario(case, changes)
            if self.run_pool is not None:
                fut, t0 = self.run_pool.submit(new_simulation, case), time.perf_counter()
                while not fut.done():  # the trim's progress: its time so far, twice a second
                    if stop.wait(TRIM_PROGRESS_PERIOD_S):
                        post(RunStatus(run_id, "idle", STOPPED_IN_TRIM))
                        return
                    post(RunStatus(run_id, "trimming", f"finding the trimmed autorotation ... "
                                                       f"{time.perf_counter() - t0:.0f} s"))
                sim = fut.result()
            else:
                sim = new_simulation(case)
        except Exception as exc:  # noqa: BLE001 - shown in the page, the session carries on
            post(Notice(f"the run could not start: {exc}"))
            post(RunStatus(run_id, "idle", "not started"))
            return
        if stop.is_set():
            post(RunStatus(run_id, "idle", STOPPED_IN_TRIM))
            return
        self.sim = sim
        gj = float(np.mean(case.rotor.stations.gj_nm2))
        post(Started(run_id, sim.start_note))
        post(RunStatus(run_id, "running", "running"))
        post(Rows(run_id, sim.history, gj, sim.t))
        t_end = case.t_end_s
        next_tick = last_views = next_verdict = time.perf_counter()
        try:
            while not stop.is_set() and sim.status == "running" and sim.t < t_end - 1e-9:
                with self._lock:
                    pend, self._pending, speed = self._pending, {}, self._speed
                if pend:
                    try:
                        sim.set_parameters(**pend)
                        gj = float(np.mean(sim.case.rotor.stations.gj_nm2))
                        post(Applied(run_id, pend, sim.t))
                    except Exception as exc:  # noqa: BLE001
                        post(Notice(f"could not apply {pend} mid-run: {exc}"))
                t_before, t_next = sim.t, scenario.next_change_s(sim.t) or t_end  # chunks end at a change
                with np.errstate(all="ignore"):
                    rows = sim.advance(span_s=max(min(speed * TICK_S, t_end - sim.t, t_next - sim.t), 1e-6))
                post(Rows(run_id, rows, gj, sim.t))
                for change in scenario.due(t_before, sim.t):
                    apply_change(sim, change)
                    gj = float(np.mean(sim.case.rotor.stations.gj_nm2))
                    post(Applied(run_id, {"gj_nm2": change.gj_nm2, "scripted": True}, sim.t))
                post(Pose(run_id, rotor_pose(sim.model, sim.y), sim.t))
                if time.perf_counter() - last_views >= VIEWS_PERIOD_S:
                    last_views = time.perf_counter()
                    post(RunStatus(run_id, "running", f"running, t = {sim.t:.2f} s", float(sim.y[Y_OMEGA])))
                    cost_s = self._post_views(sim, run_id, final=False, verdict=last_views >= next_verdict)
                    if cost_s is not None:
                        next_verdict = last_views + next_verdict_in_s(cost_s)
                next_tick += TICK_S
                delay = next_tick - time.perf_counter()
                if delay > 0:
                    stop.wait(delay)
                else:
                    next_tick = time.perf_counter()  # the solver is behind the playback speed
        except Exception as exc:  # noqa: BLE001
            post(Notice(f"the run failed at t = {sim.t:.2f} s: {exc}"))
        self._post_views(sim, run_id, final=True, stopped=stop.is_set())
        status = end_status(sim, stop.is_set())
        post(Finished(run_id, sim.history, status, stop.is_set(), sim.t))
        log.info("run %d ended at t = %.2f s (%s%s)", run_id, sim.t, status, ", stopped" if stop.is_set() else "")
        line = (f"stopped at t = {sim.t:.2f} s of {t_end:g} s" if status == "stopped" else
                f"{'stopped' if stop.is_set() else 'finished'} at t = {sim.t:.2f} s ({status})")
        post(RunStatus(run_id, "idle", line, float(sim.y[Y_OMEGA]) if len(sim.history) else None))

    def _post_views(self, sim: Simulation, run_id: int, final: bool, verdict: bool = True,
                    stopped: bool = False) -> Optional[float]:
        """Post the verdict (if ``verdict``) and the disc; returns the verdict's time [s], or None."""
        status = end_status(sim, stopped) if final else sim.status
        cost_s = None
        if verdict:
            t0 = time.perf_counter()
            try:
                with np.errstate(all="ignore"):
                    self.post(VerdictNews(run_id, sim.verdict(), final, status, sim.start_note))
            except Exception as exc:  # noqa: BLE001 - too short a run to judge
                if final:
                    self.post(Notice(f"no verdict: {exc}"))
            cost_s = time.perf_counter() - t0
        try:
            disc = sim.spanwise_last_revolution()
            if disc:
                self.post(Disc(run_id, disc))
        except Exception:  # noqa: BLE001 - the disc plots are optional
            pass
        return cost_s
