"""The controls' own widgets: number inputs that say what is wrong, and GJ's log-scale slider.

A widget made by ``from_param`` carries the parameter's bounds to the browser, which then clamps or
reverts a typed value without a word (GJ 0, 1e9, a run of -5 s). :func:`checked_input` gives the
browser no bounds: :class:`~app.controls.Controls` (param) validates the value, and a bad one
leaves the control as it was with a message under the input naming the allowed range, until the
next good value. Every tooltip states the unit and allowed range (:func:`tooltip`).
"""
from __future__ import annotations

import html
import math

import panel as pn
import param
from bokeh.models import CustomJSTickFormatter

from .controls import GJ_BOUNDS, allowed


def tooltip(p: param.Parameter) -> str:
    """The parameter's doc (with its unit) and, for a number, its allowed range."""
    return f"{p.doc} Allowed: {allowed(p)}." if isinstance(p, param.Number) and p.bounds else (p.doc or "")


def check_message(p: param.Parameter, label: str, raw) -> str:
    """Why ``raw`` cannot be the value of ``p`` ('' if it can)."""
    rng = allowed(p)
    if raw is None:  # the browser sends no value for an empty or non-numeric entry ("abc")
        return f"{label}: not a number (empty or not numeric); allowed {rng}"
    if isinstance(raw, bool) or not isinstance(raw, (int, float)):
        return f"{label}: {raw!r} is not a number; allowed {rng}"
    if not math.isfinite(raw):
        return f"{label}: {raw} is not a finite number; allowed {rng}"
    lo, hi = p.bounds or (None, None)
    if (lo is not None and raw < lo) or (hi is not None and raw > hi):
        return f"{label} = {raw:g} is out of range: allowed {rng}"
    return ""


#: the message line under an input in the sidebar (light background)
MSG_STYLES = {"color": "#b71c1c", "font-size": "90%"}
#: the message on a dark header (presentation mode): a light pill laid over what is below the input
#: (absolute: the header keeps its height), large enough for a projector
DARK_MSG_STYLES = {"position": "absolute", "top": "100%", "left": "0", "z-index": "1100", "width": "max-content",
                   "max-width": "none", "color": "#b71c1c", "background": "#ffebee", "font-size": "16px",
                   "font-weight": "600", "padding": "3px 10px", "border-radius": "12px",
                   "box-shadow": "0 1px 4px rgba(0, 0, 0, 0.5)"}
#: a dark header's light text colour reached the input's spinner arrows (the theme's body colour): white
#: on white; the arrows take the header's dark colour
DARK_SPINNER_CSS = ".bk-spin-btn {--bs-body-color: #263238; --color: #263238}"


def checked_input(controls: param.Parameterized, name: str, widget_cls=pn.widgets.FloatInput, on_dark: bool = False,
                  **kw) -> pn.Column:
    """An input for number parameter ``name`` of ``controls``, and its message line (class
    ``amra-msg``, made at the first bad value: one model less per input at page build). ``on_dark``:
    the input sits on a dark header (presentation mode), its message a light pill over the page."""
    p = controls.param[name]
    label = p.label or name
    if on_dark:
        kw["stylesheets"] = [*kw.get("stylesheets", []), DARK_SPINNER_CSS]
    widget = widget_cls(value=getattr(controls, name), label=label, description=tooltip(p), **kw)
    box = pn.Column(widget, sizing_mode=kw.get("sizing_mode", "stretch_width"), margin=0)

    reverting = []  # the box is being set back to the kept value: its message stays

    def typed(event):
        if reverting and event.new == reverting[-1]:
            reverting.clear()
            return
        bad = "" if event.new == getattr(controls, name) else check_message(p, label, event.new)
        if not bad:
            try:  # (a value the control already has: set from elsewhere, or typed again)
                controls.param.update({name: event.new})
            except Exception as exc:  # noqa: BLE001 - what param refuses is said, not swallowed
                bad = f"{label}: {exc}"
        if len(box) == 1 and bad:
            box.append(pn.pane.HTML("", css_classes=["amra-msg"], sizing_mode=None if on_dark else "stretch_width",
                                    styles=DARK_MSG_STYLES if on_dark else MSG_STYLES, margin=(0, 10, 4, 10)))
        if len(box) > 1:
            box[1].param.update(object=html.escape(bad), visible=bool(bad))
        if event.new is None:  # emptied (or not numeric): the box shows the value kept, not "NaN"
            reverting[:] = [getattr(controls, name)]
            pn.state.execute(lambda: setattr(widget, "value", reverting[-1]) if reverting else None,
                             schedule=True)  # after this change has reached the widget

    widget.param.watch(typed, "value")
    # a preset, a link or the slider moved the value: the input shows it, and its message goes
    controls.param.watch(lambda e: setattr(widget, "value", e.new), name)
    return box


#: the GJ slider's readout of its log10 value: 3 significant digits written out ("1500", "612", "30",
#: "12.3"); toPrecision alone wrote 1500 as "1.50e+3". :func:`gj_readout` is the same rule in Python.
GJ_READOUT_JS = "return String(Number((10 ** tick).toPrecision(3)))"


def gj_readout(log10_gj: float) -> str:
    """What the slider shows for ``log10_gj`` (:data:`GJ_READOUT_JS`): GJ [N m²/rad] to 3
    significant digits, no exponent and no trailing zeros."""
    return repr(float(f"{10 ** log10_gj:.3g}")).removesuffix(".0")


def gj_slider(controls: param.Parameterized) -> pn.widgets.FloatSlider:
    """GJ on a log10 scale, labelled in N m²/rad, a second view of ``controls.gj_nm2``. No echo: a
    handle moved from the server changes ``value`` only, and only a release in the browser changes
    ``value_throttled``, which sets GJ."""
    lo, hi = (math.log10(b) for b in GJ_BOUNDS)
    s = pn.widgets.FloatSlider(name="GJ (log scale) [N m²/rad]", start=lo, end=hi, step=0.005,
                               value=math.log10(controls.gj_nm2), sizing_mode="stretch_width",
                               format=CustomJSTickFormatter(code=GJ_READOUT_JS),
                               css_classes=["amra-gj-slider"])

    def released(event):
        controls.gj_nm2 = min(max(float(f"{10 ** event.new:.4g}"), GJ_BOUNDS[0]), GJ_BOUNDS[1])
    s.param.watch(released, "value_throttled")
    controls.param.watch(lambda e: setattr(s, "value", math.log10(e.new)), "gj_nm2")
    return s
