"""The page: sidebar of controls, live plots and verdict on top, the other views in tabs.

``BootstrapTemplate`` is used because it loads nothing from outside the server (the Fast
templates fetch Google fonts), so the page works offline.
"""
from __future__ import annotations

import math

import panel as pn
from bokeh.models import CustomJSTickFormatter

from . import exports
from .controls import GJ_BOUNDS
from .doc_lock import with_document_lock
from .presets import PRESETS

TITLE = "AMRA — aeroelastic model of a rotor in autorotation"


def _w(widget_cls, controls, name, **kw):
    p = controls.param[name]
    w = widget_cls.from_param(p, **kw)
    if "description" in w.param:
        w.description = p.doc  # the tooltip
    return w


def gj_log_slider(controls) -> pn.widgets.FloatSlider:
    """A slider over log10 GJ, labelled in N m²/rad, linked both ways to ``controls.gj_nm2``."""
    lo, hi = (math.log10(b) for b in GJ_BOUNDS)
    s = pn.widgets.FloatSlider(name="GJ (log scale) [N m²/rad]", start=lo, end=hi, step=0.005,
                               value=math.log10(controls.gj_nm2), sizing_mode="stretch_width",
                               format=CustomJSTickFormatter(code="return (10 ** tick).toPrecision(3)"),
                               css_classes=["amra-gj-slider"])
    if "description" in s.param:
        s.description = controls.param.gj_nm2.doc

    def to_controls(event):
        gj = float(f"{10 ** event.new:.4g}")
        if abs(math.log10(controls.gj_nm2) - event.new) > 1e-4:
            controls.gj_nm2 = min(max(gj, GJ_BOUNDS[0]), GJ_BOUNDS[1])

    def to_slider(event):
        v = math.log10(event.new)
        if abs(s.value - v) > 1e-4:
            s.value = v
    s.param.watch(to_controls, "value")
    controls.param.watch(to_slider, "gj_nm2")
    return s


def build_sidebar(d) -> list:
    c = d.controls
    explanation = pn.pane.Markdown("", sizing_mode="stretch_width", name="preset-explanation",
                                   styles={"font-size": "90%"})

    def explain(*_):
        explanation.object = f"*{PRESETS[c.preset].explanation}*"
    explain()
    c.param.watch(explain, "preset")
    upload = pn.widgets.FileInput(accept=".toml", multiple=False, name="Rotor file (TOML)",
                                  sizing_mode="stretch_width", css_classes=["amra-upload"])
    upload.param.watch(with_document_lock(lambda e: e.new is not None and d.upload(e.new, upload.filename
                                                                               or "upload.toml")), "value")
    run = pn.widgets.Button(name="▶ Run", button_type="primary", css_classes=["amra-run"])
    stop = pn.widgets.Button(name="■ Stop", button_type="warning", css_classes=["amra-stop"])
    reset = pn.widgets.Button(name="↺ Reset", button_type="light", css_classes=["amra-reset"])
    # the plots, map and markers are plain Bokeh models: change them under the lock (app.doc_lock)
    run.on_click(with_document_lock(d.start_run))
    stop.on_click(with_document_lock(d.stop_run))
    reset.on_click(with_document_lock(d.reset))
    ladder = pn.widgets.Button(name="Run fidelity ladder", button_type="default", sizing_mode="stretch_width",
                               css_classes=["amra-ladder"])
    ladder.on_click(with_document_lock(d.run_ladder))
    sel = pn.widgets.Select
    advanced = pn.Card(
        _w(pn.widgets.FloatInput, c, "airspeed_m_s"), _w(pn.widgets.FloatInput, c, "omega_hold_rad_s"),
        _w(pn.widgets.IntInput, c, "map_columns"), _w(pn.widgets.IntInput, c, "map_coarse"),
        title="Advanced: flight and map grid", collapsed=True, sizing_mode="stretch_width")
    return [
        _w(sel, c, "preset", sizing_mode="stretch_width"), explanation,
        _w(sel, c, "rotor", sizing_mode="stretch_width"), upload,
        gj_log_slider(c), _w(pn.widgets.FloatInput, c, "gj_nm2", sizing_mode="stretch_width"),
        _w(pn.widgets.FloatSlider, c, "ea_pct", sizing_mode="stretch_width"),
        _w(pn.widgets.FloatSlider, c, "cg_pct", sizing_mode="stretch_width"),
        _w(pn.widgets.FloatSlider, c, "mu", sizing_mode="stretch_width"),
        _w(sel, c, "fidelity", sizing_mode="stretch_width"),
        pn.Row(_w(sel, c, "aero", width=140), _w(sel, c, "inflow", width=140)),
        pn.Row(_w(pn.widgets.FloatInput, c, "run_s", width=140), _w(pn.widgets.FloatInput, c, "speed", width=140)),
        pn.Row(run, stop, reset), ladder, advanced,
        exports.export_bar(d.history_csv, d.modes_csv, d.map_csv),
    ]


def build_main(d) -> list:
    plots = [pn.pane.Bokeh(p, sizing_mode="stretch_width") for p in d.histories.plots()]
    top = pn.Row(pn.Column(d.verdict, d.run_status, d.live_note, width=380),
                 pn.Column(d.alert, sizing_mode="stretch_width"), sizing_mode="stretch_width")
    live = pn.GridBox(*plots, ncols=2, sizing_mode="stretch_width")
    tabs = pn.Tabs(
        ("Boundary map", d.map if d.map is not None else pn.pane.Markdown("map disabled")),
        ("Modes & root locus", d.modes),
        ("Rotor disc", d.disc),
        ("Fan plot", d.fan),
        ("Fidelity ladder", d.ladder),
        dynamic=True, sizing_mode="stretch_width", name="views")
    # rendered after the first paint (Panel's defer_load: placeholders, then the plots on page load)
    return [top, pn.panel(lambda: live, defer_load=True, sizing_mode="stretch_width"),
            pn.panel(lambda: tabs, defer_load=True, sizing_mode="stretch_width")]


def build_layout(d):
    # one root per template area: the template adds each item as a root of the document, and each
    # root added recomputes the references of every model (27 roots of 404 models: 1.9 s of the
    # server's event loop per new session, measured with cProfile; with two roots 0.2 s)
    sidebar = pn.Column(*build_sidebar(d), sizing_mode="stretch_width", name="sidebar")
    main = pn.Column(*build_main(d), sizing_mode="stretch_width", name="main")
    # No busy indicator: Panel keeps one busy flag per process and sets every session's indicator
    # from it, so each event of any session spun the spinner in all pages, and each spin changed
    # its CSS classes, which makes BokehJS lay out the whole page again (eight sessions: a third
    # of a page's main thread, CPU profile 2026-12-01). The run status and the map's progress
    # say what this session is doing.
    return pn.template.BootstrapTemplate(title=TITLE, sidebar=[sidebar], main=[main],
                                         sidebar_width=330, header_background="#263238", busy_indicator=None)
