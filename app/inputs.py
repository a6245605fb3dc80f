"""The controls' own widgets: number inputs that say what is wrong, and GJ's log-scale slider.

A widget made by ``from_param`` carries the parameter's bounds to the browser, which then clamps or
reverts a typed value without a word (GJ 0, 1e9, a run of -5 s). A number input drops what it
does not take as a key is pressed, as silently: "1,5" became 15, "12abc" 12, "abc" nothing.
:func:`checked_input` is therefore a text input read here: :class:`~app.controls.Controls` (param)
validates the number, and anything else (not a number, a decimal comma, out of range) leaves the
control as it was with a message under the input naming what was typed and the allowed range, until
the next good value. Every tooltip states the unit and allowed range (:func:`tooltip`).
"""
from __future__ import annotations

import html
import math
import re

import panel as pn
import param
from bokeh.models import CustomJSTickFormatter

from .controls import GJ_BOUNDS, allowed


def tooltip(p: param.Parameter) -> str:
    """The parameter's doc (with its unit) and, for a number, its allowed range."""
    return f"{p.doc} Allowed: {allowed(p)}." if isinstance(p, param.Number) and p.bounds else (p.doc or "")


def check_message(p: param.Parameter, label: str, raw) -> str:
    """Why the number ``raw`` (None: nothing typed; :func:`read_number` reads text) cannot be the value
    of ``p`` ('' if it can)."""
    rng = allowed(p)
    if raw is None:
        return f"{label}: not a number (empty); allowed {rng}"
    if not math.isfinite(raw):
        return f"{label}: {raw} is not a finite number; allowed {rng}"
    if isinstance(p, param.Integer) and raw != int(raw):
        return f"{label} = {raw:g} is not a whole number; allowed {rng}"
    lo, hi = p.bounds or (None, None)
    if (lo is not None and raw < lo) or (hi is not None and raw > hi):
        return f"{label} = {raw:g} is out of range: allowed {rng}"
    return ""


def read_number(p: param.Parameter, label: str, text) -> tuple:
    """(the number typed as ``text``, '') or (None, why it is none): a decimal comma is named as such
    (a number input had made "1,5" 15 without a word)."""
    raw = "" if text is None else str(text).strip()
    if not raw:
        return None, check_message(p, label, None)
    try:
        value = float(raw)
    except ValueError:
        hint = ""
        if re.fullmatch(r"[-+]?[0-9]*,[0-9]+(?:[eE][-+]?[0-9]+)?", raw):
            hint = f" (write decimals with a point: {raw.replace(',', '.')})"
        return None, f"{label}: {raw!r} is not a number{hint}; allowed {allowed(p)}"
    whole = isinstance(p, param.Integer) and math.isfinite(value) and value == int(value)
    return (int(value) if whole else value), ""


def shown(value) -> str:
    """A control's number as its input shows it: 1500, 0.45, 1e-05 (up to 10 significant digits)."""
    return f"{value:.10g}"


#: the message line under an input in the sidebar (light background)
MSG_STYLES = {"color": "#b71c1c", "font-size": "90%"}
#: the message on a dark header (presentation mode): a light pill laid over what is below the input
#: (absolute: the header keeps its height), large enough for a projector
DARK_MSG_STYLES = {"position": "absolute", "top": "100%", "left": "0", "z-index": "1100", "width": "max-content",
                   "max-width": "none", "color": "#b71c1c", "background": "#ffebee", "font-size": "16px",
                   "font-weight": "600", "padding": "3px 10px", "border-radius": "12px",
                   "box-shadow": "0 1px 4px rgba(0, 0, 0, 0.5)"}
def checked_input(controls: param.Parameterized, name: str, on_dark: bool = False, refused: dict | None = None,
                  **kw) -> pn.Column:
    """An input for number parameter ``name`` of ``controls`` (a text input: what is typed reaches
    :func:`read_number` as typed), and its message line (class ``amra-msg``, made at the first bad
    value: one model less per input at page build). ``on_dark``: the input sits on a dark header
    (presentation mode), its message a light pill over the page. ``refused``: a dict that holds this
    input's message while it has one (under ``name``), so a Run can say it uses the value kept."""
    p = controls.param[name]
    label = p.label or name
    widget = pn.widgets.TextInput(value=shown(getattr(controls, name)), name=label, description=tooltip(p), **kw)
    box = pn.Column(widget, sizing_mode=kw.get("sizing_mode", "stretch_width"), margin=0)

    reverting = []  # the box is being set back to the kept value: its message stays

    def typed(event):
        if reverting and event.new == reverting[-1]:
            reverting.clear()
            return
        value, bad = read_number(p, label, event.new)
        if not bad and value != getattr(controls, name):
            bad = check_message(p, label, value)
            if not bad:
                try:
                    controls.param.update({name: value})
                except Exception as exc:  # noqa: BLE001 - what param refuses is said, not swallowed
                    bad = f"{label}: {exc}"
        if len(box) == 1 and bad:
            box.append(pn.pane.HTML("", css_classes=["amra-msg"], sizing_mode=None if on_dark else "stretch_width",
                                    styles=DARK_MSG_STYLES if on_dark else MSG_STYLES, margin=(0, 10, 4, 10)))
        if len(box) > 1:
            box[1].param.update(object=html.escape(bad), visible=bool(bad))
        if refused is not None:
            if bad:
                refused[name] = bad
            else:
                refused.pop(name, None)
        if value is None:  # not a number: the box shows the value kept (a number out of range stays shown)
            reverting[:] = [shown(getattr(controls, name))]
            pn.state.execute(lambda: setattr(widget, "value", reverting[-1]) if reverting else None,
                             schedule=True)  # after this change has reached the widget

    widget.param.watch(typed, "value")
    # a preset, a link or the slider moved the value: the input shows it, and its message goes
    controls.param.watch(lambda e: setattr(widget, "value", shown(e.new)), name)
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
