"""Widget callbacks that touch plain Bokeh models run under the session's document lock."""
from __future__ import annotations

from bokeh.document import Document

from panel.io.state import set_curdoc

from app.doc_lock import with_document_lock


class _SessionDoc(Document):
    """A document as in a server session: it has a session context and collects next-tick callbacks."""

    def __init__(self):
        super().__init__()
        self.ticks = []

    @property
    def session_context(self):
        return object()

    def add_next_tick_callback(self, callback):
        self.ticks.append(callback)


def test_in_a_session_the_callback_waits_for_the_next_tick_where_bokeh_takes_the_lock():
    calls = []
    handler = with_document_lock(lambda *a: calls.append(a))
    doc = _SessionDoc()
    with set_curdoc(doc):
        assert handler("click") is None
    assert calls == [] and len(doc.ticks) == 1  # not run in the caller's (possibly unlocked) context
    doc.ticks[0]()
    assert calls == [("click",)]


def test_outside_a_session_the_callback_runs_at_once():
    calls = []
    handler = with_document_lock(lambda *a: calls.append(a) or "done")
    assert handler(1, 2) == "done" and calls == [(1, 2)]
