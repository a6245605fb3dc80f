"""One session's dashboard: the :class:`Dashboard` viewer composes the controls, the session and
the views, and turns the controls' actions into work.

Reading order for a newcomer: :mod:`app.controls` (what the user sets: the single source of
truth), :mod:`app.session` (the run thread and the events it posts, :mod:`app.events`), then
each view in :mod:`app.live` and :mod:`app.views` (each subscribes to the events it draws).
Server-wide parts (map jobs, process pools, settings) are in :mod:`app.server`.
"""
from __future__ import annotations

import json
from typing import Optional

import numpy as np
import panel as pn

from amra_core.boundary import MapSpec
from amra_core.paper_cases import NOMINAL_GJ_NM2
from amra_core.shapes import FIDELITIES
from amra_core.verdict import teeter_amplitude_rad

from . import compute, exports
from .controls import LIVE_PARAMETERS, LIVE_VALUE_OF, PRESETS, UPLOADED, Controls, UploadError, parse_rotor_upload
from .events import Applied, Fan, Finished, Ladder, Locus, ModeFrames, Modes, Notice, Rows, live_values_text
from .inputs import checked_input, gj_slider, tooltip
from .live import LivePlots, columns_from_rows
from .server.pool import LatestTasks, get_analysis_pool
from .server.settings import ServerSettings
from .session import Session
from .views.disc import DiscView
from .views.fan import FanView
from .views.help import help_pane
from .views.ladder import LadderView
from .views.map import MapView, map_csv
from .views.modes import ModesView
from .views.rotor import LiveRotor
from .views.sensitivity import SensitivityView
from .views.status import TRIMMING_WORDS, StatusView, run_html, units_as_shown

TITLE = "AMRA — aeroelastic model of a rotor in autorotation"
CASE_PARAMETERS = ("rotor", "gj_nm2", "ea_pct", "cg_pct", "mu", "airspeed_m_s", "omega_hold_rad_s", "fidelity",
                   "aero", "inflow", "map_columns", "map_coarse")
MAP_GJ_RANGE = (30.0, 3000.0)  #: GJ range of the boundary map [N m²/rad]
REFRESH_PERIOD_S = 0.3  #: the analyses follow the controls at most this often [s]
PAPER_CG = 0.40  #: the paper's CG (Figs 10-13) [chord fraction]: every map has a column there
#: in the browser, when presentation mode is toggled: the Bootstrap template's sidebar shown exactly
#: when it is off (pressing the template's own sidebar button), and the short title while it is on
PRESENT_LAYOUT_JS = """
const sidebar = document.getElementById("sidebar"), button = document.getElementById("sidebar-toggle");
if (sidebar && button && sidebar.classList.contains("show") === cb_obj.active) { button.click(); }
const title = document.querySelector("#header .app-header .title");
if (title) { title.textContent = "\\u00a0" + (cb_obj.active ? "AMRA" : %s); }
""" % json.dumps(TITLE)


def map_columns(n: int) -> tuple:
    """``n`` CG columns [chord fractions] from 20 to 50 % chord, always including the paper's 40 %."""
    cgs = {round(float(x), 4) for x in np.linspace(0.20, 0.50, n)}
    return tuple(sorted(cgs | {PAPER_CG}))


def case_label(c: Controls, scenario) -> str:
    """One line naming a run's case, for its verdict card."""
    flight = f"μ {c.mu:g}" if not c.airspeed_m_s else f"{c.airspeed_m_s:g} m/s"
    gj = (f"GJ {NOMINAL_GJ_NM2:g} → {c.gj_nm2:.4g} N m²/rad at {c.soften_at_s:g} s" if scenario.changes
          else f"GJ {c.gj_nm2:.4g} N m²/rad")
    name = PRESETS[c.preset].label if c.preset != "custom" else c.rotor
    # a quantity and its value stay on one line (the card wrapped "μ" and its "0" apart); the line
    # breaks between the fields
    fields = [c.fidelity, gj, f"EA {c.ea_pct:g} %", f"CG {c.cg_pct:g} %", flight]
    return " · ".join([name] + [f.replace(" ", "\u00a0") for f in fields])


def map_elsewhere(c: Controls) -> str:
    """How the case's flight differs from its map's (maps have an advance ratio and a free rotor speed
    only), or "" when the map is the case's."""
    parts = ([f"it flies at {c.airspeed_m_s:g} m/s"] if c.airspeed_m_s else []) + (
        [f"its rotor speed is held at {c.omega_hold_rad_s:g} rad/s"] if c.omega_hold_rad_s else [])
    if not parts:
        return ""
    return (f"this case is not on the map: {' and '.join(parts)}, while the map is at μ {c.mu:g} with a free "
            f"rotor speed (a map has no airspeed or held rotor speed; set μ and Airspeed 0 to map a forward flight)")


def ladder_case_text(c: Controls) -> str:
    """What the ladder runs, in words: the case, and its softening when there is one."""
    if c.soften_at_s:
        return f"{c.run_s:g} s, GJ {NOMINAL_GJ_NM2:g} → {c.gj_nm2:.4g} N m²/rad at {c.soften_at_s:g} s as in the run"
    return f"{c.run_s:g} s, GJ {c.gj_nm2:.4g} N m²/rad"


def teeter_note(model_rad: float, measured_rad: float, amra_rad: float) -> str:
    """Table 1's comparison, in the paper's radians and the teeter plot's degrees."""
    def both(x):
        return f"{x:.3f} rad ({np.degrees(x):.2f}°)"
    return (f"Teeter amplitude (1/rev, last revolution): this model {both(model_rad)}; measured in flight "
            f"{both(measured_rad)}; original AMRA {both(amra_rad)}")


class Dashboard(pn.viewable.Viewer):
    def __init__(self, settings: Optional[ServerSettings] = None, registry=None, pool=None, run_pool=None,
                 doc=None, **params):
        super().__init__(**params)
        self.settings = settings or ServerSettings.from_env()
        self.controls = c = Controls(max_run_s=self.settings.max_run_s)
        self.session = s = Session(doc, run_pool)
        self.tasks = LatestTasks(s.post, pool if pool is not None else get_analysis_pool())
        self.messages: list = []
        self.alert = pn.pane.Alert("", alert_type="danger", visible=False, sizing_mode="stretch_width",
                                   name="messages")
        self.live = LivePlots()
        self.status = StatusView(s, self.notify)
        self.modes, self.disc, self.fan, self.ladder = ModesView(s), DiscView(s), FanView(s), LadderView(s)
        self.rotor_view = LiveRotor(s)
        self.exports = exports.ExportBar(history=self.history_csv, modes=self.modes_csv, map=self.map_csv)
        self.modes.on_pick = self.animate_mode
        self.map = MapView(s, registry, who=id(self), on_pick=self.load_cell) if registry is not None else None
        self.uploaded = None
        self.uploaded_name = ""  #: the file the uploaded rotor came from
        self.sensitivity = (SensitivityView(s, self._sensitivity_case, self.tasks.submit, self.map.show_sensitivity,
                                            self.notify) if self.map is not None else None)
        if self.sensitivity is not None:  # its text changes: on the event loop, with the lock
            self.sensitivity.button.on_click(lambda e: s.soon(self.sensitivity.start))
        self.last_history: Optional[np.ndarray] = None
        self._run_on_screen = False  #: a run started and not reset: what the history export saves
        self.refused: dict = {}  #: the number inputs' messages about values they refused, by control
        self._locus_key = None
        self._run_preset = "custom"  #: the preset the current run was started with
        self.live_bar: Optional[pn.Row] = None  #: presentation mode's header bar, made when first shown
        self.refresh = s.throttle(self.refresh_analyses, REFRESH_PERIOD_S)
        s.subscribe(Rows, lambda ev: self.live.append(columns_from_rows(ev.rows, ev.gj_nm2)))
        s.subscribe(Finished, self._finished)
        s.subscribe(Applied, lambda ev: self.live.mark(ev.t_s, ev.text()))
        s.subscribe(Notice, lambda ev: self.notify(ev.text, ev.level))
        # Run and Reset clear the plots' Bokeh sources: on the event loop, with the document lock
        c.param.watch(lambda e: s.soon(self.start_run), "run")
        c.param.watch(lambda e: s.stop(), "stop")
        c.param.watch(lambda e: s.soon(self.reset), "reset")
        c.param.watch(self.run_ladder, "ladder")
        c.param.watch(self._on_live, list(LIVE_PARAMETERS))
        c.param.watch(self._on_case, list(CASE_PARAMETERS))
        c.param.watch(lambda e: s.set_speed(e.new), "speed")
        c.param.watch(self._rotor_needs_its_file, "rotor")

    # ------------------------------------------------------------------ messages
    def notify(self, text: str, level: str = "error") -> None:
        """A visible message: the alert pane (the last three messages, until Reset) and a toast."""
        text = units_as_shown(text)
        self.messages.append((level, text))
        self.alert.alert_type = {"error": "danger", "warning": "warning", "info": "info"}.get(level, "danger")
        self.alert.object = "\n\n".join(f"**{lv}:** {t}" for lv, t in self.messages[-3:])
        self.alert.visible = True
        if pn.state.curdoc is not None and pn.state.notifications is not None:
            getattr(pn.state.notifications, level if level in ("error", "warning", "info") else "error")(
                text, duration=6000)

    def _clear_messages(self) -> None:
        self.messages.clear()
        self.alert.visible = False

    # ------------------------------------------------------------------ actions
    def _parts(self):
        """(rotor, flight, settings) of the current case, or None after a message saying why not."""
        c = self.controls
        try:
            return c.rotor_obj(self.uploaded), c.flight(), c.settings()
        except Exception as exc:  # noqa: BLE001 - RotorError, SettingsError, ValueError
            self.notify(f"invalid case: {exc}")
            return None

    def start_run(self, *_) -> bool:
        try:
            scenario = self.controls.scenario(self.uploaded)
        except Exception as exc:  # noqa: BLE001 - RotorError, SettingsError, ValueError
            self.notify(f"cannot run this case: {exc}")
            return False
        self.live.clear()
        self.status.reset()
        self._clear_messages()  # each run starts with a clean message area
        if self.refused:  # a box still shows a refused value (scrolled out of view, it went unseen)
            self.notify("this run uses the values kept, not the ones refused: " + "; ".join(self.refused.values()),
                        "warning")
        self.status.case = case_label(self.controls, scenario)
        self.status.pending(TRIMMING_WORDS)
        self.status.gj_nm2 = float(np.mean(scenario.case.rotor.stations.gj_nm2))  # the softening moves it
        self.status.run.value = run_html("starting ...")
        self.session.start(scenario.case, self.controls.speed, scenario.changes)
        self._run_on_screen = True
        self._run_preset = self.controls.preset
        self.exports.rename({"history": exports.names_for(self.controls)["history"]})
        return True

    def _finished(self, ev) -> None:
        self.last_history = ev.history
        # a note about changes to the running run ("applied live at the next chunk: EA 34.5 %", "the preset's
        # case takes effect at the next run") is stale once it ended (the card's case line keeps its changes);
        # a scripted softening's stays, it tells the paper's story
        if self.status.note.value.startswith(("applied live", "the preset's case", "this change takes effect")):
            self.status.note.value = ""
        ref = PRESETS[self._run_preset].teeter_reference_rad
        if ref is not None and len(ev.history):
            beta = teeter_amplitude_rad(ev.history)
            self.status.note.value = teeter_note(beta, *ref)

    def reset(self, *_) -> None:
        self.last_history, self._run_on_screen = None, False  # a download after Reset gave the cleared run's rows
        self.session.forget()
        self.live.clear()
        self.ladder.previous = None
        self.ladder.compare(None, None)
        self.status.reset()
        self._clear_messages()

    def run_ladder(self, *_) -> None:
        """The run's case at the three fidelities, softened as the run is (it ran the softened GJ from
        the start: Fig. 10's ladder showed no collapse time)."""
        try:
            scenarios = {fid: self.controls.scenario(self.uploaded, fidelity=fid) for fid in FIDELITIES}
        except Exception as exc:  # noqa: BLE001
            self.notify(f"cannot run the ladder: {exc}")
            return
        self.ladder.running(ladder_case_text(self.controls))
        self.tasks.submit("ladder", Ladder, compute.run_ladder, scenarios)

    def animate_mode(self, real_part_per_s: float, frequency_hz: float, label: str) -> None:
        """Compute the frames of a mode of the current case's trim (analysis pool)."""
        parts = self._parts()
        if parts is not None:
            self.tasks.submit("mode-frames", ModeFrames, compute.mode_frames, *parts, real_part_per_s,
                              frequency_hz, label)

    def upload(self, data: bytes, filename: str) -> bool:
        try:
            rotor = parse_rotor_upload(data, filename)
        except UploadError as exc:  # says what stays in use (a failed upload left "uploaded file" shown)
            stays = (f"the rotor stays the earlier file {self.uploaded_name!r}" if self.controls.rotor == UPLOADED
                     and self.uploaded is not None else f"the rotor stays {self.controls.rotor}")
            self.notify(f"{exc}; {stays}")
            return False
        self.uploaded, self.uploaded_name = rotor, filename
        if self.controls.rotor == UPLOADED:
            self.refresh.kick()
        else:
            self.controls.rotor = UPLOADED
        st = rotor.stations
        self.notify(f"rotor file {filename!r} loaded: {rotor.name}, R = {rotor.radius_m:g} m. Its own GJ "
                    f"{st.mean('gj_nm2'):.4g} N m²/rad, EA {100 * st.mean('x_ea'):.1f} % and CG "
                    f"{100 * st.mean('x_cg'):.1f} % chord (span means) are overridden by the controls' uniform "
                    f"GJ, EA and CG", "info")
        return True

    def _rotor_needs_its_file(self, event) -> None:
        """'uploaded file' chosen (in the select, or by a link's value) with no file uploaded in this
        session: the rotor stays as it was, and the message says how to get one."""
        if self._file_missing(event.new):
            keep = event.old if event.old != UPLOADED else Controls.param.rotor.default

            def revert():  # after this change has reached the widgets (set inside it, the select kept it)
                self.controls.rotor = keep
                self.notify(f"no rotor file uploaded in this session: the rotor stays {keep}; upload a TOML "
                            f"file with 'Rotor file (TOML)' to use your own", "warning")
            self.session.soon(revert)

    def _file_missing(self, rotor: str) -> bool:
        """True for 'uploaded file' while this session has no rotor file."""
        return rotor == UPLOADED and self.uploaded is None

    def _chosen_file(self, upload: pn.widgets.FileInput) -> None:
        """A file was chosen: read it (an empty one arrives as no value, and is named as empty). A
        rejected file is cleared from the widget, so it does not stand there as if in use; the
        clearing's own echo (no name) is no choice."""
        if not upload.filename:
            return
        if not self.upload(upload.value or b"", upload.filename):
            upload.clear()

    def load_cell(self, cell) -> None:
        """A map cell as the case: its CG and GJ, run from its own trim. A preset's softening stays off
        (after Fig. 10 a cell at GJ 1720 ran as "GJ 1500 → 1720 at 2 s", not the case the map classified)."""
        gj = float(f"{cell.gj_nm2:.3g}")  # the grid's resolution, not 487.58387005217355
        softened = self.controls.soften_at_s
        self.controls.param.update(cg_pct=round(100.0 * cell.cg, 1), gj_nm2=gj, soften_at_s=0.0)
        self.status.show(None, False)  # the card spoke of another case
        self.notify(f"loaded map cell CG {100 * cell.cg:.1f} % chord, GJ {gj:g} N m²/rad "
                    f"({cell.verdict}); press Run to simulate it" +
                    (f" from its own trim ('Soften at {softened:g} s' set to 0)" if softened else ""), "info")

    # ------------------------------------------------------------------ parameter changes
    def _on_live(self, *events) -> None:
        if self.controls.applying_preset:  # a new case, not a change to the running one: a preset's GJ,
            return  # EA and CG went live into a run of another rotor and flight (_on_case says so)
        if self.session.running:  # only what moved (the card named EA and CG changes nobody made)
            moved = {LIVE_VALUE_OF[e.name] for e in events if e.name in LIVE_VALUE_OF}
            values = {k: v for k, v in self.controls.live_values().items() if k in moved}
            if values:
                self.session.set_live(**values)
                self.status.note.value = f"applied live at the next chunk: {live_values_text(values, ', ', True)}"

    def _on_case(self, *events) -> None:
        if self.session.running and self.controls.applying_preset:
            self.status.note.value = ("the preset's case takes effect at the next run: this run goes on with its "
                                      "own values")
        elif self.session.running and any(e.name not in LIVE_PARAMETERS for e in events):
            self.status.note.value = "this change takes effect at the next run (only GJ, EA and CG apply live)"
        self.refresh.kick()

    def _sensitivity_case(self):
        """(rotor, flight, settings, CG [chord fraction], map spec) of the current case."""
        c = self.controls
        return c.rotor_obj(self.uploaded), c.flight(), c.settings(), c.cg_pct / 100.0, self.map_spec()

    def map_spec(self) -> MapSpec:
        c = self.controls
        rotor = self.uploaded if c.rotor == UPLOADED else c.rotor
        if rotor is None:
            raise ValueError("no rotor file uploaded")
        return MapSpec(rotor=rotor, fidelity=c.fidelity, aero=c.aero, mu=float(c.mu), ea=c.ea_pct / 100.0,
                       cg_values=map_columns(c.map_columns), gj_min=MAP_GJ_RANGE[0], gj_max=MAP_GJ_RANGE[1],
                       n_coarse=c.map_coarse)

    def refresh_analyses(self) -> None:
        """Recompute the modes, root locus and fan plot; follow the map for the current case."""
        c = self.controls
        self.modes.set_gj(c.gj_nm2)
        names = exports.names_for(c)
        self.exports.rename({"modes": names["modes"], "map": names["map"]})
        if self.map is not None:
            self.map.mark(c.cg_pct, c.gj_nm2, map_elsewhere(c))
        if self._file_missing(c.rotor):
            return  # no case yet: _rotor_needs_its_file puts a rotor back, which refreshes again
        parts = self._parts()
        if parts is None:
            return
        rotor, flight, settings = parts
        self.tasks.submit("modes", Modes, compute.modes_result, rotor, flight, settings)
        key = (c.rotor, id(self.uploaded), c.ea_pct, c.cg_pct, flight, settings)
        if key != self._locus_key:
            self._locus_key = key
            self.tasks.submit("locus", Locus, compute.locus_result, rotor, flight, settings, c.cg_pct / 100.0)
        self.tasks.submit("fan", Fan, compute.fan_data, rotor, settings.fidelity)
        if self.map is not None:
            try:
                self.map.follow(self.map_spec())
            except Exception as exc:  # noqa: BLE001
                self.notify(f"no map for this case: {exc}")

    # ------------------------------------------------------------------ exports
    def history_csv(self):
        sim = self.session.sim if self._run_on_screen else None  # after Reset: not the cleared run's rows
        state = None
        if sim is not None and self.status.verdict is not None:
            if not self.status.final:
                state = f"running: saved at t = {sim.t:.2f} s of {sim.case.t_end_s:g} s (the verdict is so far)"
            elif self.status.solver_status == "stopped":
                state = f"stopped by its user at t = {sim.t:.2f} s of {sim.case.t_end_s:g} s"
        return exports.history_csv(sim, self.last_history, self.status.verdict, state)

    def modes_csv(self):
        return exports.modes_csv(self.modes.full_frame, self.controls, self.modes.about)

    def map_csv(self):
        return self.map.csv() if self.map is not None else map_csv([], complete=False)

    # ------------------------------------------------------------------ lifecycle
    def close(self, *args) -> None:
        """The session ended: stop the run (without waiting), drop its analyses, leave the map."""
        self.session.close()
        self.tasks.close()
        if self.map is not None:
            self.map.release()

    # ------------------------------------------------------------------ the page
    def sidebar(self) -> pn.Column:
        c = self.controls
        explanation = pn.pane.Markdown(pn.bind(lambda p: PRESETS[p].explanation, c.param.preset),
                                       sizing_mode="stretch_width", name="preset-explanation",
                                       styles={"font-size": "90%"})
        upload = pn.widgets.FileInput(accept=".toml", multiple=False, name="Rotor file (TOML)",
                                      sizing_mode="stretch_width", css_classes=["amra-upload"])
        upload.param.watch(lambda *events: self._chosen_file(upload), ["value", "filename"])  # once per choice

        def w(cls, name, **kw):  # tooltip: the parameter's doc, unit and allowed range
            tip = {"description": tooltip(c.param[name])} if "description" in cls.param else {}
            return cls.from_param(c.param[name], **tip, **kw)

        def num(name, css=None, **kw):  # typed numbers: a bad one gets a message under its input
            return checked_input(c, name, css_classes=[css] if css else [], refused=self.refused, **kw)
        full, sel, slider = {"sizing_mode": "stretch_width"}, pn.widgets.Select, pn.widgets.FloatSlider
        button = pn.widgets.Button.from_param
        return pn.Column(
            w(sel, "preset", **full), explanation, w(sel, "rotor", **full), upload,
            gj_slider(c), num("gj_nm2", "amra-gj", **full),
            *[w(slider, name, **full) for name in ("ea_pct", "cg_pct", "mu")], w(sel, "fidelity", **full),
            pn.Row(w(sel, "aero", width=140), w(sel, "inflow", width=140)),
            pn.Row(num("run_s", "amra-run-s", width=140), num("speed", "amra-speed", width=140)),
            num("soften_at_s", "amra-soften", **full),
            pn.Row(button(c.param.run, button_type="primary", css_classes=["amra-run"]),
                   button(c.param.stop, button_type="warning", css_classes=["amra-stop"]),
                   button(c.param.reset, button_type="light", css_classes=["amra-reset"])),
            button(c.param.ladder, sizing_mode="stretch_width", css_classes=["amra-ladder"]),
            self._advanced(num),
            self.exports.panel(), sizing_mode="stretch_width", name="sidebar")

    @staticmethod
    def _advanced(num) -> pn.Card:
        """The collapsed card of flight and map-grid inputs; its inputs are made when it is first opened."""
        card = pn.Card(title="Advanced: flight and map grid", collapsed=True, sizing_mode="stretch_width",
                       css_classes=["amra-advanced"])

        def opened(event):
            if not event.new and not len(card):
                card.extend([num("airspeed_m_s"), num("omega_hold_rad_s"), num("map_columns"), num("map_coarse")])
        card.param.watch(opened, "collapsed")
        return card

    def header(self) -> pn.Row:
        """The presentation toggle; in presentation mode also the live bar (:meth:`_live_bar`)."""
        toggle = pn.widgets.Toggle.from_param(self.controls.param.present, button_type="light", width=170,
                                              css_classes=["amra-present"], margin=(10, 10))
        # the template sets its sidebar and title only when the page is built (?present=true): a
        # toggle mid-session presses the template's own sidebar button, as the user would
        toggle.jscallback(value=PRESENT_LAYOUT_JS)
        self.head = pn.Row(toggle, sizing_mode="stretch_width")
        return self.head

    def _live_bar(self) -> pn.Row:
        """Run, Stop, a large GJ input and the verdict, for a projector (made when first shown)."""
        c = self.controls
        big = {"styles": {"font-size": "20px"}, "stylesheets": [":host input {font-size: 20px; height: 40px}"]}
        button = pn.widgets.Button.from_param
        return pn.Row(
            button(c.param.run, button_type="primary", css_classes=["amra-present-run"], width=110, height=44,
                   description=None),
            button(c.param.stop, button_type="warning", width=110, height=44, description=None),
            checked_input(c, "gj_nm2", css_classes=["amra-present-gj"], width=170, on_dark=True, refused=self.refused,
                          **big),
            self.status.badge, margin=0)

    def main(self) -> pn.Column:
        self.top = pn.Row(self.status, pn.Column(self.alert, sizing_mode="stretch_width"),
                          sizing_mode="stretch_width")
        # the live plots are shown at once (deferred, the first Run waited 1.4 s longer for them to
        # reach the page); the views' tabs come after the first paint, each built when first shown
        grid = pn.GridBox(*[pn.pane.Bokeh(f, sizing_mode="stretch_width") for f in self.live.figures()], ncols=2,
                          sizing_mode="stretch_width")
        return pn.Column(self.top, grid, pn.panel(self.views, defer_load=True, sizing_mode="stretch_width"),
                         sizing_mode="stretch_width", name="main")

    def present(self, on: bool) -> None:
        """Presentation mode on or off: taller live plots and larger fonts, the header's live bar shown
        and the top status row stepping aside."""
        self.live.present(on)
        self.top.visible = not on
        if on and self.live_bar is None:
            self.live_bar = self._live_bar()
            self.head.append(self.live_bar)
        if self.live_bar is not None:
            self.live_bar.visible = on

    def views(self) -> pn.Tabs:
        """The analysis views, one tab each; a tab's models are built when it is first shown."""
        def lazy(make):  # evaluated when the tab is first shown
            return pn.param.ParamFunction(make, lazy=True, sizing_mode="stretch_width")
        the_map = pn.Column(self.map, self.sensitivity, sizing_mode="stretch_width") if self.map is not None \
            else pn.pane.Markdown("map disabled")
        return pn.Tabs(("Boundary map", the_map), ("Modes & root locus", lazy(lambda: self.modes)),
                       ("Live rotor", lazy(lambda: self.rotor_view)), ("Rotor disc", lazy(lambda: self.disc)),
                       ("Fan plot", lazy(lambda: self.fan)), ("Fidelity ladder", lazy(lambda: self.ladder)),
                       ("Help", lazy(lambda: help_pane(self.controls))),
                       dynamic=True, sizing_mode="stretch_width", name="views")

    def __panel__(self):
        # one root per template area (each root added to a document makes Bokeh recompute its
        # references); no busy indicator (Panel's busy flag is per process: every session's events
        # would spin every page's indicator)
        c = self.controls
        header, main = self.header(), self.main()
        self.present(c.present)
        c.param.watch(lambda e: self.present(e.new), "present")
        title = "AMRA" if c.present else TITLE  # room for the header's controls on a projector
        return pn.template.BootstrapTemplate(title=title, sidebar=[self.sidebar()], main=[main], header=[header],
                                             sidebar_width=330, header_background="#263238", busy_indicator=None,
                                             collapsed_sidebar=c.present)
