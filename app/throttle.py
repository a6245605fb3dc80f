"""The one rate limiter of the app: run a function on the session's event loop soon after it is
asked for, at most once per period, and never while nobody asks (no periodic callback).

``kick()`` may be called from any thread, as often as it likes; kicks during a wait coalesce.
The call goes through ``pn.state.execute`` (a next-tick callback with the document lock held),
so the function may change any model. Without a served document (tests, scripts) a kick only
marks the work as due, and :meth:`run_due` runs it in the caller's thread.

:func:`on_event_loop` is the same hop without the rate limit, for button clicks: Panel hands a
click to its watchers without the document lock, and the plots' raw Bokeh sources may change only
with it held.
"""
from __future__ import annotations

import threading
import time
from typing import Callable

import panel as pn
from panel.io.state import set_curdoc


def on_event_loop(doc, fn: Callable[[], None]) -> None:
    """Run ``fn`` as a next-tick callback of the served document ``doc`` (``pn.state.execute``:
    the document lock held, Panel's documented way to change Bokeh models from a callback that
    does not hold it); at once without a served document (tests, scripts)."""
    if doc is None or doc.session_context is None:
        fn()
        return
    with set_curdoc(doc):
        pn.state.execute(fn, schedule=True)


class Throttle:
    def __init__(self, fn: Callable[[], None], period_s: float, doc=None):
        self.fn = fn
        self.period_s = float(period_s)
        self.doc = doc if doc is not None and doc.session_context is not None else None
        self._lock = threading.Lock()
        self._due = False
        self._last = -1e9
        self.closed = False

    def kick(self) -> None:
        """Ask for a call (any thread)."""
        with self._lock:
            if self._due or self.closed:
                return
            self._due = True
        if self.doc is not None:
            with set_curdoc(self.doc):
                pn.state.execute(self._arm, schedule=True)

    def _arm(self) -> None:  # on the event loop
        wait_s = self._last + self.period_s - time.monotonic()
        if wait_s > 0:
            self.doc.add_timeout_callback(self._timed, int(1000 * wait_s) + 1)
        else:
            self.run_due()

    def _timed(self) -> None:  # a Bokeh timeout callback: on the loop, document locked
        with set_curdoc(self.doc):
            self.run_due()

    def run_due(self) -> None:
        """Run the function if a kick asked for it (on the event loop, or in tests)."""
        with self._lock:
            if not self._due or self.closed:
                return
            self._due = False
            self._last = time.monotonic()
        self.fn()

    def close(self) -> None:
        self.closed = True
