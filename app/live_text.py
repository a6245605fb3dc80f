"""Short texts the pump rewrites while a run streams (run clock, "so far" verdict, live-change note).

Each is a plain Bokeh ``Div`` whose ``text`` alone changes, rather than a Panel ``Markdown`` or
``HTML`` pane: a pane update re-sends the pane's other properties too (its stylesheets among them,
which are models), so on a served page each one made Bokeh recompute the references of every model
in the session's document (about 350), on the event loop that all sessions share. py-spy of the
server with eight sessions streaming (2026-12-02): pane updates were a quarter of the event loop's
time, and the users' slider moves queued behind them. A ``text`` change holds no models, so it is
sent as is. In the page, the text is set in place, without a layout of the whole page
(:mod:`app.browser_tuning`, class :data:`~app.browser_tuning.LIVE_TEXT_CLASS`): so a live text
must change nothing but its text.
"""
from __future__ import annotations

import panel as pn
from bokeh.models import Div

from .browser_tuning import LIVE_TEXT_CLASS


class LiveText(pn.viewable.Viewer):
    """An HTML snippet shown in the page; ``object`` reads and sets it (a same-text set sends nothing).

    Set it on the session's event loop (the dashboard's pump or a locked callback), like any model."""

    def __init__(self, html: str = "", name: str = "", css_class: str = "", **params):
        super().__init__(**params)
        self.div = Div(text=html, sizing_mode="stretch_width", name=name or None,
                       css_classes=[LIVE_TEXT_CLASS] + ([css_class] if css_class else []))

    @property
    def object(self) -> str:
        return self.div.text

    @object.setter
    def object(self, html: str) -> None:
        if html != self.div.text:
            self.div.text = html

    def __panel__(self):
        return pn.pane.Bokeh(self.div, sizing_mode="stretch_width")
