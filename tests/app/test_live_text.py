"""Texts the pump rewrites while a run streams change their ``text`` alone (app.live_text)."""
from __future__ import annotations

from bokeh.document import Document
from bokeh.document.events import ModelChangedEvent

from app.dashboard import Dashboard
from app.live_text import LiveText
from app.settings import ServerSettings


def _changes(doc):
    seen = []
    doc.on_change(lambda event: seen.append(event))
    return seen


def test_a_new_text_sends_only_the_text_and_the_same_text_sends_nothing():
    box = LiveText("<b>Run:</b> idle", name="run-status", css_class="amra-run-status")
    doc = Document()
    doc.add_root(box.div)
    models_before = set(doc.models)
    seen = _changes(doc)
    box.object = "<b>Run:</b> running, t = 1.00 s"
    assert [(type(e), e.attr) for e in seen] == [(ModelChangedEvent, "text")]
    assert box.object == "<b>Run:</b> running, t = 1.00 s" and set(doc.models) == models_before
    box.object = "<b>Run:</b> running, t = 1.00 s"
    assert len(seen) == 1  # unchanged: nothing sent


def test_the_dashboard_status_texts_are_live_texts():
    dash = Dashboard(ServerSettings.from_env(), registry=None)
    for box in (dash.run_status, dash.live_note, dash.verdict.pane):
        assert isinstance(box, LiveText)
    dash._run_text("failed: <x> & y")
    assert dash.run_status.object == "<b>Run:</b> failed: &lt;x&gt; &amp; y"  # escaped, shown as typed
