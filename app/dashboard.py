"""One session's dashboard: the controls, the run worker, the views, and the message pump.

Built fresh per session by :func:`app.main.create_app`. Worker threads post ``(kind, payload)``
messages to :attr:`Dashboard.outbox`; :meth:`Dashboard.pump` (a 25 ms periodic callback on the
session's event loop) drains it, streams rows into the plots' data source (as fast as the
browser draws them, :mod:`app.streams`), and updates the panes, so the
document is only touched on its own loop. Closing the session stops the worker and releases the
map subscription (:meth:`Dashboard.close`).
"""
from __future__ import annotations

import html
import logging
import queue
import time
from typing import Optional

import numpy as np
import panel as pn

from amra_core.boundary import MapSpec

from . import exports
from . import analysis
from .background import LatestTasks, get_analysis_pool
from .controls import LIVE_PARAMETERS, UPLOADED, Controls
from .disc_view import DiscView
from .fan_view import FanView
from .ladder import LadderView, ladder_cases
from .live_text import LiveText
from .map_view import MapView
from .modes_view import ModesView
from .rotor_upload import UploadError, parse_rotor_upload
from .run_worker import RunWorker
from .settings import ServerSettings
from .streams import TimeHistories, columns_from_rows, frame_from_rows
from .verdict_card import VerdictCard

PUMP_MS = 25  #: pump period [ms]: more than twice the worker's chunk rate, so each chunk is sent on its own
REFRESH_DELAY_MS = 300  #: a parameter change re-runs the analyses this long after the last change [ms]
RUN_TEXT_PERIOD_S = 0.5  #: wall-clock period of the "running, t = ..." status text [s], times the load factor
VERDICT_PERIOD_S = 1.0  #: shortest wall-clock interval between "so far" verdicts shown [s], times the load factor
MAP_POLL_S = 0.4  #: wall-clock period of the map poll [s], times the map's load factor
CASE_PARAMETERS = ("rotor", "gj_nm2", "ea_pct", "cg_pct", "mu", "airspeed_m_s", "omega_hold_rad_s", "fidelity",
                   "aero", "inflow", "map_columns", "map_coarse")
MAP_GJ_RANGE = (30.0, 3000.0)
log = logging.getLogger("amra.dashboard")


def _run_html(text: str) -> str:
    """The run status line: "Run:" and what the run is doing."""
    return f"<b>Run:</b> {html.escape(text)}"


def _same_gj(a: float, b: float) -> bool:
    """Whether two GJ values [N m²/rad] are the same setting (to rounding)."""
    return abs(float(a) - float(b)) <= 1e-9 * abs(float(b))


class Dashboard(pn.viewable.Viewer):
    def __init__(self, settings: Optional[ServerSettings] = None, registry=None, pool=None, **params):
        super().__init__(**params)
        self.settings = settings or ServerSettings.from_env()
        self.controls = Controls(max_run_s=self.settings.max_run_s)
        self.outbox: queue.SimpleQueue = queue.SimpleQueue()
        self.worker = RunWorker(self._post)
        self.tasks = LatestTasks(self._post, pool if pool is not None else get_analysis_pool())
        self.histories = TimeHistories()
        self.verdict = VerdictCard()
        self.modes = ModesView()
        self.disc = DiscView()
        self.fan = FanView()
        self.ladder = LadderView()
        self.map = MapView(registry, who=id(self), on_pick=self.load_cell) if registry is not None else None
        self.uploaded = None
        self.last_history: Optional[np.ndarray] = None
        self._previous_frame = None
        self.current_run = 0
        self.messages: list = []
        self.alert = pn.pane.Alert("", alert_type="danger", visible=False, sizing_mode="stretch_width",
                                   name="messages")
        self.run_status = LiveText(_run_html("idle"), name="run-status", css_class="amra-run-status")
        self.live_note = LiveText("", name="live-note", css_class="amra-live-note")
        self._ticks = 0
        self._run_text_at = 0.0
        self._verdict_at = -1e9
        self._refresh_pending = None
        self._next_pump = 0.0
        self._next_map_poll = 0.0
        self.budget = None  #: the server's StreamBudget, in a served session (start_periodic)
        self._live_since: Optional[tuple] = None  #: (GJ, perf_counter) of a live change not yet streamed
        self.live_latencies_s: list = []  #: server side: live change received -> first rows with it sent [s]
        self._in_budget = False
        self._period_s = PUMP_MS / 1000.0
        self._locus_key = None
        self._periodic = None
        self._closed = False
        self.controls.param.watch(self._on_live, list(LIVE_PARAMETERS))
        self.controls.param.watch(self._on_case, list(CASE_PARAMETERS))
        self.controls.param.watch(lambda e: self.worker.set_speed(e.new), ["speed"])
        # the analyses start once the page has loaded (pn.state.onload in main), or on first change

    # ------------------------------------------------------------------ messages
    def _post(self, kind: str, payload: dict) -> None:
        self.outbox.put((kind, payload))

    def notify(self, text: str, level: str = "error") -> None:
        """A visible message: the alert pane (the last three messages, until Reset) and a toast."""
        self.messages.append((level, text))
        self.alert.alert_type = {"error": "danger", "warning": "warning", "info": "info"}.get(level, "danger")
        self.alert.object = "\n\n".join(f"**{lv}:** {t}" for lv, t in self.messages[-3:])
        self.alert.visible = True
        notes = pn.state.notifications if pn.state.curdoc is not None else None
        if notes is not None:
            getattr(notes, level if level in ("error", "warning", "info") else "error")(text, duration=6000)

    # ------------------------------------------------------------------ actions
    def start_run(self, event=None) -> bool:
        try:
            case = self.controls.case(self.uploaded)
        except Exception as exc:  # noqa: BLE001 - RotorError, SettingsError, ValueError
            self.notify(f"cannot run this case: {exc}")
            return False
        self.histories.clear()
        self.verdict.reset()
        self._verdict_at = -1e9
        self.current_run = self.worker.run_id + 1  # before the thread can post anything
        self.worker.start(case, self.controls.speed)
        self.run_status.object = _run_html("starting ...")
        return True

    def stop_run(self, event=None) -> None:
        self.worker.stop(timeout=1.0)

    def reset(self, event=None) -> None:
        self.worker.stop(timeout=1.0)
        self.current_run = self.worker.run_id + 1  # ignore anything the old run still posts
        self.histories.clear()
        self._previous_frame = None
        self.ladder.compare(None, None)
        self.verdict.reset()
        self.messages.clear()
        self.alert.visible = False
        self.run_status.object = _run_html("idle")

    def run_ladder(self, event=None) -> None:
        try:
            cases = ladder_cases(self.controls, self.uploaded)
        except Exception as exc:  # noqa: BLE001
            self.notify(f"cannot run the ladder: {exc}")
            return
        self.ladder.info.object = "Running the case at rigid, fem-torsion and fem-coupled ..."
        self.tasks.submit("ladder", analysis.run_ladder, cases)

    def upload(self, data: bytes, filename: str) -> bool:
        try:
            rotor = parse_rotor_upload(data, filename)
        except UploadError as exc:
            self.notify(str(exc))
            return False
        self.uploaded = rotor
        if self.controls.rotor == UPLOADED:
            self.refresh_analyses()
        else:
            self.controls.rotor = UPLOADED
        self.notify(f"rotor file {filename!r} loaded: {rotor.name}, R = {rotor.radius_m:g} m", "info")
        return True

    def load_cell(self, cell) -> None:
        self.controls.param.update(cg_pct=round(100.0 * cell.cg, 4), gj_nm2=float(cell.gj_nm2))
        self.notify(f"loaded map cell CG {100 * cell.cg:.1f} % chord, GJ {cell.gj_nm2:.4g} N m²/rad "
                    f"({cell.verdict}); press Run to simulate it", "info")

    # ------------------------------------------------------------------ parameter changes
    def _on_live(self, *events) -> None:
        if self.worker.running:
            self._live_since = (float(self.controls.gj_nm2), time.perf_counter())
            self.worker.set_live(**self.controls.live_values())
            self.live_note.object = (f"applied live at the next chunk: GJ {self.controls.gj_nm2:.4g} N m²/rad, "
                                     f"EA {self.controls.ea_pct:g} %, CG {self.controls.cg_pct:g} %")

    def _on_case(self, *events) -> None:
        if self.worker.running and any(e.name not in LIVE_PARAMETERS for e in events):
            self.live_note.object = "this change takes effect at the next run (only GJ, EA and CG apply live)"
        doc = pn.state.curdoc
        if doc is None or doc.session_context is None:
            self.refresh_analyses()
            return
        # in a session: after the pump has sent the run's first rows with the new value (the
        # markers and the map re-render the document, tens of ms each), and once per burst of changes
        if self._refresh_pending is not None:
            try:
                doc.remove_timeout_callback(self._refresh_pending)
            except ValueError:
                pass
        self._refresh_pending = doc.add_timeout_callback(self._refresh_deferred, REFRESH_DELAY_MS)

    def _refresh_deferred(self) -> None:
        self._refresh_pending = None
        if not self._closed:
            self.refresh_analyses()

    def map_spec(self) -> MapSpec:
        c = self.controls
        rotor = self.uploaded if c.rotor == UPLOADED else c.rotor
        if rotor is None:
            raise ValueError("no rotor file uploaded")
        cgs = tuple(round(float(x), 4) for x in np.linspace(0.20, 0.50, c.map_columns))
        return MapSpec(rotor=rotor, fidelity=c.fidelity, aero=c.aero, mu=float(c.mu), ea=c.ea_pct / 100.0,
                       cg_values=cgs, gj_min=MAP_GJ_RANGE[0], gj_max=MAP_GJ_RANGE[1], n_coarse=c.map_coarse)

    def refresh_analyses(self) -> None:
        """Recompute the modes, root locus and fan plot; follow the map for the current case."""
        c = self.controls
        self.modes.set_gj(c.gj_nm2)
        if self.map is not None:
            self.map.mark(c.cg_pct, c.gj_nm2)
        try:
            rotor = c.rotor_obj(self.uploaded)
            flight, settings = c.flight(), c.settings()
        except Exception as exc:  # noqa: BLE001
            self.notify(f"invalid case: {exc}")
            return
        self.tasks.submit("modes", analysis.modes_result, rotor, flight, settings)
        key = (c.rotor, id(self.uploaded), c.ea_pct, c.cg_pct, flight, settings)
        if key != self._locus_key:
            self._locus_key = key
            self.tasks.submit("locus", analysis.locus_result, rotor, flight, settings, c.cg_pct / 100.0)
        self.tasks.submit("fan", analysis.fan_data, rotor, settings.fidelity)
        if self.map is not None:
            try:
                self.map.follow(self.map_spec())
            except Exception as exc:  # noqa: BLE001
                self.notify(f"no map for this case: {exc}")

    # ------------------------------------------------------------------ the pump (event loop)
    def tick(self) -> None:
        """The periodic callback: pump, but leave the event loop at least half of its time for
        user input (a slider release must not queue behind plot updates on a loaded server)."""
        now = time.perf_counter()
        if now < self._next_pump:
            return
        self.pump()
        spent = time.perf_counter() - now
        # idle for as long as the pump took (capped, so a slow update cannot starve the stream)
        self._next_pump = now + min(0.25, max(0.0, 2.0 * spent - self._period_s))

    def pump(self) -> int:
        """Drain the outbox and update the page; returns the number of rows streamed.

        (Not under ``pn.io.hold``: held ``ColumnsStreamed`` events lost their binary buffers'
        offsets in the browser, "Offset is outside the bounds of the DataView". Nor under a
        document freeze: leaving one recomputes the references of every model in the page,
        0.06-0.12 s here, and the streamed rows change no references.)"""
        frames = []
        run_text, clock_only = None, False  # the newest status text; a running clock is rate-limited
        # A pane update costs the event loop ~10 ms (Panel's property and design resolution); with
        # eight sessions streaming, the clock and the verdict card took 20 % of the loop (py-spy,
        # 2026-12-01), ahead of the streamed rows and the users' input. So a loaded server shows
        # the running clock and the "so far" verdict less often (final ones always at once).
        slowdown = self.budget.slowdown() if self.budget is not None else 1.0  # the loop lags: fewer redraws
        load = self.budget.load_factor() * slowdown if self.budget is not None else 1.0
        now = time.perf_counter()
        while True:
            try:
                kind, p = self.outbox.get_nowait()
            except queue.Empty:
                break
            if "run_id" in p and p["run_id"] != self.current_run:
                continue
            if kind == "rows":
                if len(p["rows"]):
                    frames.append(columns_from_rows(p["rows"], p["gj_nm2"]))
                run_text, clock_only = f"running, t = {p['t_s']:.2f} s", True
            elif kind == "status":
                run_text, clock_only = p["text"], False
            elif kind == "started":
                self.verdict.show(None, False)
                if p["start_note"].startswith("no steady"):
                    self.notify(f"no trim exists for this case: {p['start_note']}", "warning")
            elif kind == "verdict":
                if not p["final"] and now - self._verdict_at < VERDICT_PERIOD_S * load:
                    continue
                self._verdict_at = now
                self.verdict.show(p["verdict"], p["final"], p["status"], p["start_note"])
                if p["final"] and p["status"] == "numerical-failure":
                    self.notify(f"the run failed numerically: {p['verdict'].explanation}")
            elif kind == "disc":
                self.disc.show(p["data"])
            elif kind == "finished":
                self.last_history = p["history"]
                if len(p["history"]):
                    frame_all = frame_from_rows(p["history"], float("nan"))
                    self.ladder.compare(self._previous_frame, frame_all)
                    self._previous_frame = frame_all
            elif kind == "applied":
                v = p["values"]
                self.live_note.object = (f"applied live at t = {p['t_s']:.2f} s: GJ {v['gj_nm2']:.4g} N m²/rad, "
                                         f"EA {100 * v['x_ea']:.3g} %, CG {100 * v['x_cg']:.3g} %")
            elif kind == "modes":
                self.modes.show_modes(p)
            elif kind == "locus":
                self.modes.show_locus(p["points"], p["text"])
            elif kind == "fan":
                self.fan.show(p)
            elif kind == "ladder":
                self.ladder.show(p)
                self.ladder.info.object = "Fidelity ladder: the current case at the three fidelities."
            elif kind == "error":
                self.notify(p["text"])
        if run_text is not None and (not clock_only
                                     or time.perf_counter() - self._run_text_at >= RUN_TEXT_PERIOD_S * load):
            # the clock twice a second, less often on a loaded server: a Markdown update costs the
            # server ~5 ms, and each page a re-layout (~0.1 s of a starved page's main thread)
            self._run_text(run_text)
        if self.budget is not None:  # the server's updates per second, shared by the streaming sessions
            streaming = self.worker.running or self.histories.pending_rows > 0
            if streaming != self._in_budget:
                (self.budget.join if streaming else self.budget.leave)(id(self))
                self._in_budget = streaming
            self.histories.min_interval_s = self.budget.min_interval_s() if streaming else 0.0
        for cols in frames:
            self.histories.queue(cols)
        live_gj = self._live_since[0] if self._live_since is not None else None
        # the first rows with the user's change go at once (rows come in time order, so the newest
        # one carries the change if any does)
        urgent = live_gj is not None and bool(frames) and _same_gj(frames[-1]["gj_nm2"][-1], live_gj)
        n = self.histories.flush(urgent=urgent)  # sent now, or once the browser has drawn the last batch
        if frames:
            self.fan.set_omega(float(frames[-1]["omega_rad_s"][-1]))
        if n and live_gj is not None:
            gj, since = self._live_since
            if _same_gj(self.histories.last_sent_gj, gj):
                self._live_since = None
                self.live_latencies_s.append(time.perf_counter() - since)
                log.info("live change to GJ %.4g N m²/rad: first rows with it sent %.3f s after it reached "
                         "the server", gj, self.live_latencies_s[-1])
        self._ticks += 1
        now = time.perf_counter()
        if self.map is not None and now >= self._next_map_poll:
            self.map.poll()
            # every session polls its map, so a loaded server polls each less often
            self._next_map_poll = now + MAP_POLL_S * self.map.load_factor() * slowdown
        return n

    def _run_text(self, text: str) -> None:
        self._run_text_at = time.perf_counter()
        self.run_status.object = _run_html(text)  # (a same-text set sends nothing)

    # ------------------------------------------------------------------ exports
    def history_csv(self):
        return exports.history_csv(self.last_history if self.last_history is not None else
                                   (self.worker.sim.history if self.worker.sim is not None else None))

    def modes_csv(self):
        return self.modes.csv()

    def map_csv(self):
        from .map_view import map_csv
        return map_csv(self.map.cells if self.map is not None else [])

    # ------------------------------------------------------------------ lifecycle
    def start_periodic(self) -> None:
        from .server_limits import stream_period_ms
        self._period_s = stream_period_ms(PUMP_MS) / 1000.0
        self.histories.enable_flow_control()  # a browser is attached: send what it can draw
        from .server_limits import get_stream_budget
        self.budget = get_stream_budget()
        if pn.state.curdoc is not None and pn.state.curdoc.session_context is not None:
            from .loop_watch import start_once
            start_once(pn.state.curdoc, self.budget)  # the budget follows the event loop's lag
        from panel.io.callbacks import PeriodicCallback
        # background: a periodic pump must not flag the page busy (the busy indicator would send
        # two extra messages per tick and the page would look permanently loading)
        self._periodic = PeriodicCallback(callback=self.tick, period=stream_period_ms(PUMP_MS), background=True,
                                          log=False)
        self._periodic.start()

    def close(self, *args) -> None:
        if self._closed:
            return
        self._closed = True
        if self._periodic is not None:
            self._periodic.stop()
        self.worker.stop(timeout=5.0)
        if self.budget is not None:
            self.budget.leave(id(self))
        self.tasks.close()
        if self.map is not None:
            self.map.release()

    def __panel__(self):
        from .layout import build_layout
        return build_layout(self)

