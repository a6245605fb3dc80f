"""The live plots' data source: rows in order, and flow control (at most WINDOW_BATCHES batches the
browser has not confirmed drawing; then one batch per ACK_TIMEOUT_S)."""
from __future__ import annotations

import time

import numpy as np
import pytest

from amra_core.simulation import HISTORY_COLUMNS
from app.server_limits import StreamBudget
from app.streams import ACK_TIMEOUT_S, WINDOW_BATCHES, TimeHistories, frame_from_rows


def _frame(t0: float, n: int, gj: float = 1500.0):
    rows = np.zeros((n, len(HISTORY_COLUMNS)))
    rows[:, HISTORY_COLUMNS.index("t_s")] = t0 + 0.005 * np.arange(n)
    return frame_from_rows(rows, gj)


def test_without_flow_control_every_batch_is_sent_at_once():
    h = TimeHistories()
    assert h.send(_frame(0.0, 5)) == 5 and h.send(_frame(0.025, 5)) == 5
    assert h.pending_rows == 0 and len(h.frame()) == 10 and h.batches_sent == 2


def test_a_batch_waits_for_the_browser_to_draw_the_last_ones():
    h = TimeHistories()
    h.enable_flow_control()
    assert "streaming" in h.source.js_property_callbacks  # the browser side of the handshake
    assert [h.send(_frame(0.005 * 5 * k, 5)) for k in range(WINDOW_BATCHES)] == [5] * WINDOW_BATCHES
    assert h.in_flight == WINDOW_BATCHES
    t_next = 0.025 * WINDOW_BATCHES
    assert h.send(_frame(t_next, 4)) == 0 and h.send(_frame(t_next + 0.02, 3)) == 0  # window full: queued
    assert h.pending_rows == 7 and len(h.frame()) == 5 * WINDOW_BATCHES
    h.ack.tags = [1]  # what the browser's callback reports once the first batch is on screen
    assert h.batches_confirmed == 1 and h.in_flight == WINDOW_BATCHES - 1
    assert h.flush() == 7  # the queued rows go as one batch
    t = h.frame()["t_s"].to_numpy()
    assert len(t) == 5 * WINDOW_BATCHES + 7 and np.all(np.diff(t) > 0)  # nothing lost, nothing reordered
    h.ack.tags = [h.batches_sent]  # all drawn
    assert h.in_flight == 0
    h.ack.tags = ["nonsense"]  # not a count: ignored
    h.ack.tags = [10 ** 6]  # never more confirmed than sent
    assert h.in_flight == 0 and h.batches_confirmed == h.batches_sent


def test_a_browser_that_never_confirms_gets_one_batch_per_timeout():
    h = TimeHistories()
    h.enable_flow_control()
    for k in range(WINDOW_BATCHES):
        h.send(_frame(0.025 * k, 5))
    t0 = time.monotonic()
    assert h.send(_frame(0.025 * WINDOW_BATCHES, 5)) == 0
    assert h.flush(now=t0 + 0.5 * ACK_TIMEOUT_S) == 0
    assert h.flush(now=t0 + ACK_TIMEOUT_S + 0.01) == 5
    h.send(_frame(0.025 * WINDOW_BATCHES + 0.1, 5))
    assert h.flush(now=t0 + 1.5 * ACK_TIMEOUT_S) == 0  # the next one a timeout later
    assert h.flush(now=t0 + 2 * ACK_TIMEOUT_S + 0.02) == 5


def test_clear_drops_what_is_queued_for_the_old_run():
    h = TimeHistories()
    h.enable_flow_control()
    for k in range(WINDOW_BATCHES + 1):
        h.send(_frame(0.025 * k, 5))
    assert h.pending_rows == 5
    h.clear()
    assert h.pending_rows == 0 and len(h.frame()) == 0


def test_the_stream_budget_shares_the_servers_updates_among_streaming_sessions():
    budget = StreamBudget(total_hz=100.0)
    for who in range(10):
        budget.join(who)
    budget.join(3)
    assert budget.streaming == 10 and budget.min_interval_s() == pytest.approx(0.1)
    budget.leave(3)
    budget.leave(3)
    assert budget.streaming == 9
    h = TimeHistories()
    h.min_interval_s = 0.1
    assert h.send(_frame(0.0, 5)) == 5
    t_sent = time.monotonic()
    assert h.send(_frame(0.025, 5)) == 0 and h.pending_rows == 5  # too soon after the last batch
    assert h.flush(now=t_sent + 0.11) == 5


def test_the_first_rows_with_the_users_change_skip_flow_control_and_the_budget():
    """A slider release is answered at once: its rows wait neither for the browser's confirmation
    of earlier batches nor for the stream budget's interval; later rows wait again."""
    h = TimeHistories()
    h.enable_flow_control()
    for k in range(WINDOW_BATCHES):
        h.queue(_frame(0.025 * k, 5))
        assert h.flush(now=100.0 * k) == 5
    assert h.in_flight == WINDOW_BATCHES
    h.min_interval_s = 10.0
    t_next = 0.025 * WINDOW_BATCHES
    h.queue(_frame(t_next, 5))
    assert h.flush() == 0
    assert h.flush(urgent=True) == 5 and h.in_flight == WINDOW_BATCHES + 1
    h.queue(_frame(t_next + 0.025, 5))
    assert h.flush() == 0 and h.pending_rows == 5
    t = np.asarray(h.source.data["t_s"])
    assert len(t) == 5 * (WINDOW_BATCHES + 1) and np.all(np.diff(t) > 0)


def test_the_pages_rest_after_drawing_follows_the_draw_duty():
    """The confirmation JS rests (1 - duty) / duty times the drawing beyond FAST_DRAW_MS, capped below the server's
    patience (a rest longer than ACK_TIMEOUT_S would be overtaken by the next batch anyway)."""
    from app import streams
    js = streams._ack_js()
    ratio = (1.0 - streams.DRAW_DUTY) / streams.DRAW_DUTY
    assert f"Math.max(0, drawn_ms - {streams.FAST_DRAW_MS!r}) * {ratio!r}" in js and "REST" not in js
    cap = float(js.split("Math.min(")[1].split(",")[0])
    assert 0 < cap < 1000.0 * ACK_TIMEOUT_S


@pytest.fixture
def dash(server_settings, analysis_pool):
    from app.dashboard import Dashboard
    d = Dashboard(server_settings, registry=None, pool=analysis_pool)
    yield d
    d.close()


def test_a_session_joins_the_budget_while_it_streams(dash, wait):
    dash.budget = StreamBudget(total_hz=100.0)
    dash.controls.param.update(run_s=1.0, speed=4.0)
    dash.start_run()

    def step():
        dash.pump()
        return dash.budget.streaming == 1
    wait(step, 60, what="the session to join the budget")
    assert dash.histories.min_interval_s == pytest.approx(0.01)

    def finished():
        dash.pump()
        return dash.last_history is not None and not dash.worker.running
    wait(finished, 60, what="the run's end")
    dash.pump()
    dash.pump()
    assert dash.budget.streaming == 0 and dash.histories.min_interval_s == 0.0


def test_the_load_factor_stretches_secondary_updates_with_the_streaming_sessions():
    budget = StreamBudget(total_hz=160.0)
    assert budget.load_factor() == 1.0
    for who in range(2):
        budget.join(who)
    assert budget.load_factor() == 1.0
    for who in range(2, 8):
        budget.join(who)
    assert budget.load_factor() == pytest.approx(4.0)


class _Verdict:
    def __init__(self, verdict="stable"):
        self.verdict, self.explanation = verdict, "test"
        self.growth_rate_per_s = self.frequency_hz = self.collapse_time_s = None


def test_a_loaded_server_shows_so_far_verdicts_less_often_and_the_final_one_at_once(dash):
    from app.dashboard import VERDICT_PERIOD_S
    dash.budget = StreamBudget(total_hz=160.0)
    for who in range(8):  # eight sessions streaming: load factor 4
        dash.budget.join(who)
    shown = []
    dash.verdict.show = lambda v, final, *a: shown.append((v.verdict, final))
    run = dash.current_run
    dash.outbox.put(("verdict", {"run_id": run, "verdict": _Verdict("stable"), "final": False, "status": "running",
                                 "start_note": ""}))
    dash.pump()
    dash.outbox.put(("verdict", {"run_id": run, "verdict": _Verdict("flutter"), "final": False, "status": "running",
                                 "start_note": ""}))
    dash.pump()  # within 4 x VERDICT_PERIOD_S of the first: not shown
    assert shown == [("stable", False)]
    dash._verdict_at -= 4 * VERDICT_PERIOD_S + 0.01  # as if that time had passed
    dash.outbox.put(("verdict", {"run_id": run, "verdict": _Verdict("flutter"), "final": False, "status": "running",
                                 "start_note": ""}))
    dash.outbox.put(("verdict", {"run_id": run, "verdict": _Verdict("divergence"), "final": True,
                                 "status": "completed", "start_note": ""}))
    dash.pump()
    assert shown == [("stable", False), ("flutter", False), ("divergence", True)]


def test_a_lagging_server_stretches_the_so_far_verdicts_by_its_slowdown(dash):
    """When the event loop lags, the budget's cut (app.server_limits.StreamBudget.slowdown)
    stretches the secondary updates too (the clock, the "so far" verdict; the map polls by the same
    factor): here eight sessions (load factor 4) and a cut of 4."""
    from app.dashboard import VERDICT_PERIOD_S
    dash.budget = StreamBudget(total_hz=160.0)
    for who in range(8):
        dash.budget.join(who)
    dash.budget.rate_hz = 40.0  # as after the loop lagged
    assert dash.budget.slowdown() == pytest.approx(4.0)
    shown = []
    dash.verdict.show = lambda v, final, *a: shown.append(v.verdict)
    run = dash.current_run

    def so_far(verdict):
        dash.outbox.put(("verdict", {"run_id": run, "verdict": _Verdict(verdict), "final": False,
                                     "status": "running", "start_note": ""}))
        dash.pump()
    so_far("stable")
    dash._verdict_at -= 4 * VERDICT_PERIOD_S + 0.01  # enough without the cut, not with it
    so_far("flutter")
    assert shown == ["stable"]
    dash._verdict_at -= 12 * VERDICT_PERIOD_S  # 16 periods in all: load factor 4 x slowdown 4
    so_far("divergence")
    assert shown == ["stable", "divergence"]


def test_the_plot_ranges_stay_in_the_browser_and_the_drawing_count_comes_back():
    """The ranges follow the data in the browser; synced back they cost the server a message per
    drawing and range. The ack source must sync: it is the flow control."""
    h = TimeHistories()
    plots = h.plots()
    ranges = {id(r): r for p in plots for r in (p.x_range, p.y_range)}
    assert len(ranges) == 1 + len(plots)  # one shared time axis, a value axis each
    assert all(r.syncable is False for r in ranges.values())
    assert h.ack.syncable is True and h.source.syncable is True
