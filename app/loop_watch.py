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
WATCH_KEY = "amra-loop-watch"  #: in ``pn.state.cache``: the watcher's task (one per process)


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
    """Start :func:`watch` on ``doc``'s event loop unless this process already runs it."""
    import panel as pn
    if pn.state.cache.get(WATCH_KEY) is not None:
        return
    pn.state.cache[WATCH_KEY] = "starting"

    def start():
        pn.state.cache[WATCH_KEY] = asyncio.get_running_loop().create_task(watch(budget))
    doc.add_next_tick_callback(start)
