"""Number inputs that say what is wrong: every bad value gets a visible message next to its control.

A widget made by ``from_param`` carries the parameter's bounds to the browser, which then clamps or
reverts a typed value without a word (GJ 0, 1e9, a run of -5 s). :func:`checked_input` gives the
browser no bounds: the value comes to the server, :class:`Controls` (param) validates it, and a bad
one leaves the control as it was with a message under the input naming the allowed range, until
the next good value. The tooltip of every control states its unit and allowed range
(:func:`tooltip`).
"""
from __future__ import annotations

import html
import math

import panel as pn
import param


def allowed_range(p: param.Parameter) -> str:
    """``"10 to 10000"`` for a bounded number parameter ('' otherwise)."""
    if isinstance(p, param.Number) and p.bounds:
        lo, hi = p.bounds
        return f"{lo:g} to {hi:g}"
    return ""


def tooltip(p: param.Parameter) -> str:
    """The parameter's doc (with its unit) and its allowed range."""
    rng = allowed_range(p)
    return f"{p.doc} Allowed: {rng}." if rng else (p.doc or "")


def check_message(p: param.Parameter, label: str, raw) -> str:
    """Why ``raw`` cannot be the value of ``p`` ('' if it can)."""
    rng = allowed_range(p)
    if raw is None or isinstance(raw, bool) or not isinstance(raw, (int, float)):
        return f"{label}: {raw!r} is not a number; allowed {rng}"
    if not math.isfinite(raw):
        return f"{label}: {raw} is not a finite number; allowed {rng}"
    lo, hi = p.bounds or (None, None)
    if (lo is not None and raw < lo) or (hi is not None and raw > hi):
        return f"{label} = {raw:g} is out of range: allowed {rng}"
    return ""


def checked_input(controls: param.Parameterized, name: str, widget_cls=pn.widgets.FloatInput, **kw) -> pn.Column:
    """An input for number parameter ``name`` of ``controls``, and its message line (class
    ``amra-msg``, empty while the value is good)."""
    p = controls.param[name]
    label = p.label or name
    widget = widget_cls(value=getattr(controls, name), label=label, description=tooltip(p), **kw)
    box = pn.Column(widget, sizing_mode=kw.get("sizing_mode", "stretch_width"), margin=0)
    state = {"setting": False, "message": None}

    def show(text: str) -> None:  # the message line is made at the first bad value (page build: one model less)
        message = state["message"]
        if message is None and text:
            message = state["message"] = pn.pane.HTML("", css_classes=["amra-msg"], sizing_mode="stretch_width",
                                                      styles={"color": "#b71c1c", "font-size": "90%"},
                                                      margin=(0, 10, 4, 10))
            box.append(message)
        if message is not None:
            message.object = html.escape(text)
            message.visible = bool(text)

    def typed(event):
        if state["setting"]:
            return
        bad = check_message(p, label, event.new)
        if not bad:
            try:
                controls.param.update({name: event.new})
            except Exception as exc:  # noqa: BLE001 - what param refuses is said, not swallowed
                bad = f"{label}: {exc}"
        show(bad)

    def follow(event):  # a preset, a link or the slider moved the value: show it, clear the message
        state["setting"] = True
        try:
            widget.value = event.new
        finally:
            state["setting"] = False
        show("")

    widget.param.watch(typed, "value")
    controls.param.watch(follow, name)
    return box
