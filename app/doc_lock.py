"""Widget callbacks that change plain Bokeh models must hold the session's document lock.

Panel runs a widget's callback at once, with the lock, once the session is connected. Before that
(a click while the page is still loading, or on a loaded server) it schedules the callback as a
coroutine *without* the lock, and relies on its own panes to write their changes directly. This
dashboard's live plots, map and markers are plain Bokeh models: changing one there raised
Bokeh's ``RuntimeError: _pending_writes should be non-None when we have a document lock``, and the
click was lost. Measured: 6 of 8 sessions got no run from their first Run click in a load test
(``scripts/load_test.py --sessions 8``, page not deferred, 2026-12-01).

:func:`with_document_lock` wraps such a callback: in a server session it runs it on the next tick
of the session's event loop, where Bokeh takes the lock first; elsewhere (tests, notebooks) it
runs it at once.
"""
from __future__ import annotations

from typing import Callable

__all__ = ["with_document_lock"]


def with_document_lock(callback: Callable) -> Callable:
    """``callback(*args)`` run under the document lock of the current session (see the module)."""
    import panel as pn

    def locked(*args):
        doc = pn.state.curdoc
        if doc is None or doc.session_context is None:
            return callback(*args)
        doc.add_next_tick_callback(lambda: callback(*args))
        return None

    locked.__wrapped__ = callback
    return locked
