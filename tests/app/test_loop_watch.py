"""The stream budget follows the event loop's lag (app.server_limits.StreamBudget.observe_lag), and
the watcher (app.loop_watch) measures the lag of a loop that is held up."""
from __future__ import annotations

import asyncio
import sys
import time
from pathlib import Path

import pytest

from app import loop_watch
from app.server_limits import ADJUST_PERIOD_S, LAG_HIGH_S, LAG_LOW_S, MAX_SLOWDOWN, MIN_SESSION_HZ, StreamBudget

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "scripts"))
from load_test import run_async  # noqa: E402 - asyncio.run in a thread of its own (a test's loop may run)


def _budget(sessions: int, total_hz: float = 160.0) -> StreamBudget:
    b = StreamBudget(total_hz=total_hz)
    for who in range(sessions):
        b.join(who)
    return b


def _feed(b: StreamBudget, lag_s: float, seconds: float, t0: float = 0.0, step_s: float = 0.05) -> float:
    t = t0
    while t < t0 + seconds:
        b.observe_lag(lag_s, t)
        t += step_s
    return t


def test_a_lagging_loop_cuts_the_rate_to_one_update_per_session_and_second_at_least():
    b = _budget(8)
    assert b.rate_hz == 160.0 and b.min_interval_s() == pytest.approx(0.05)
    t = _feed(b, 0.4, 1.0)  # a starved loop: 0.4 s late
    assert b.lag_s > LAG_HIGH_S and 0.3 * 160.0 <= b.rate_hz < 160.0  # cut, step by step
    t = _feed(b, 0.4, 20.0, t)
    assert b.rate_hz == pytest.approx(8 * MIN_SESSION_HZ)  # the floor: 1 update/s for each session
    assert b.min_interval_s() == pytest.approx(1.0 / MIN_SESSION_HZ)


def test_the_rate_changes_at_most_every_adjust_period():
    b = _budget(4)
    rates, t = [], 0.0
    while t < 3.0:
        b.observe_lag(1.0, t)
        rates.append((t, b.rate_hz))
        t += 0.01
    changes = [t for (t, r), (_, r0) in zip(rates[1:], rates) if r != r0]
    assert len(changes) >= 4
    assert all(b_ - a >= ADJUST_PERIOD_S - 1e-9 for a, b_ in zip(changes, changes[1:]))


def test_a_responsive_loop_gets_the_full_rate_back_and_a_middling_one_keeps_its_rate():
    b = _budget(8)
    t = _feed(b, 0.4, 20.0)
    low = b.rate_hz
    t = _feed(b, (LAG_LOW_S + LAG_HIGH_S) / 2, 10.0, t)  # between the thresholds: no change
    assert b.rate_hz == low
    _feed(b, 0.001, 60.0, t)
    assert b.lag_s < LAG_LOW_S and b.rate_hz == 160.0  # back to the configured budget, not above


def test_one_late_wake_up_does_not_cut_the_rate():
    b = _budget(8)
    t = _feed(b, 0.001, 2.0)
    b.observe_lag(0.3, t)  # one hiccup (a page build): smoothed, under the threshold
    assert b.lag_s < LAG_HIGH_S and b.rate_hz == 160.0


def test_the_watcher_measures_a_loop_held_up_by_a_blocking_callback():
    b = _budget(2)
    seen = []
    b.observe_lag = lambda lag, now: seen.append(lag)

    async def go():
        task = asyncio.get_running_loop().create_task(loop_watch.watch(b, sample_s=0.02, samples=6))
        await asyncio.sleep(0.05)
        time.sleep(0.3)  # a callback that holds the loop
        await task
    run_async(go())
    assert len(seen) == 6 and max(seen) >= 0.2 and min(seen) < 0.1, seen


def test_start_once_runs_one_watcher_per_loop_and_budget():
    import panel as pn

    class Doc:  # the part of a Bokeh document start_once uses
        def __init__(self):
            self.callbacks = []

        def add_next_tick_callback(self, cb):
            self.callbacks.append(cb)

    async def go():
        doc, first, second = Doc(), _budget(1), _budget(1)
        fed_first, fed_second = [], []
        first.observe_lag = lambda lag, now: fed_first.append(lag)
        second.observe_lag = lambda lag, now: fed_second.append(lag)
        for budget in (first, first, second):
            loop_watch.start_once(doc, budget)
        doc.callbacks[0]()
        task, fed = pn.state.cache[loop_watch.WATCH_KEY]
        doc.callbacks[1]()  # the same loop and budget: the same watcher
        assert pn.state.cache[loop_watch.WATCH_KEY] == (task, first) and not task.done()
        doc.callbacks[2]()  # a new budget: a new watcher, the old one stopped
        new_task, new_fed = pn.state.cache[loop_watch.WATCH_KEY]
        await asyncio.sleep(0.12)
        assert new_task is not task and new_fed is second and task.cancelled()
        n_first = len(fed_first)
        await asyncio.sleep(0.12)
        assert len(fed_second) >= 2 and len(fed_first) == n_first  # only the new budget is fed
        new_task.cancel()
    run_async(go())


def test_the_slowdown_follows_the_cut_and_is_capped():
    b = _budget(8)
    assert b.slowdown() == 1.0
    t = _feed(b, 0.4, 20.0)  # at the floor: 160 -> 8 updates/s
    assert b.rate_hz == pytest.approx(8.0) and b.slowdown() == MAX_SLOWDOWN
    _feed(b, 0.001, 60.0, t)
    assert b.slowdown() == 1.0


def test_sessions_that_join_after_a_cut_still_get_one_update_a_second():
    b = _budget(4)
    _feed(b, 0.4, 20.0)
    assert b.rate_hz == pytest.approx(4.0)
    for who in range(4, 16):  # twelve more sessions start streaming; the lag stays in the middle band
        b.join(who)
    assert b.min_interval_s() == pytest.approx(1.0 / MIN_SESSION_HZ)
