"""The server's event-loop lag, measured once per process and fed to the stream budget.

A coroutine on the server's event loop sleeps :data:`SAMPLE_S` and measures how late it woke up;
each sample goes to :meth:`app.server_limits.StreamBudget.observe_lag`, which slows the live plots'
updates while the loop lags (that docstring says why). It is started by the first session, on the
loop that runs the sessions' documents, and runs until the server stops.
"""
from __future__ import annotations

import asyncio
import time

SAMPLE_S = 0.05  #: the watcher's sleep between samples [s]
WATCH_KEY = "amra-loop-watch"  #: in ``pn.state.cache``: (the watcher's task, the budget it feeds): one per process and loop


async def watch(budget, sample_s: float = SAMPLE_S, samples: int | None = None) -> None:
    """Sample the running loop's lag into ``budget`` (forever, or ``samples`` times)."""
    n = 0
    while samples is None or n < samples:
        t0 = time.monotonic()
        await asyncio.sleep(sample_s)
        now = time.monotonic()
        budget.observe_lag(now - t0 - sample_s, now)
        n += 1


def start_once(doc, budget) -> None:
    """Start :func:`watch` on ``doc``'s event loop unless it already runs there (one watcher per
    process and loop: a test process may run several servers one after another)."""
    import panel as pn

    def start():
        loop = asyncio.get_running_loop()
        task, fed = pn.state.cache.get(WATCH_KEY) or (None, None)
        running_here = task is not None and not task.done() and task.get_loop() is loop
        if running_here and fed is budget:
            return
        if running_here:
            task.cancel()  # a new budget (the cache was reset): feed that one
        pn.state.cache[WATCH_KEY] = (loop.create_task(watch(budget)), budget)
    doc.add_next_tick_callback(start)
