"""The live plots hold a min/max-preserving decimation of the run (at most MAX_POINTS per curve), stream
only new points, and show a zoomed range at full resolution."""
from __future__ import annotations

import numpy as np
import pytest

from amra_core.simulation import HISTORY_COLUMNS
from app.live import MAX_POINTS, PLOTS, LivePlots, columns_from_rows


def _chunk(t0: float, n: int, gj: float = 1500.0, dt: float = 0.0025):
    rows = np.zeros((n, len(HISTORY_COLUMNS)))
    t = t0 + dt * np.arange(n)
    rows[:, HISTORY_COLUMNS.index("t_s")] = t
    rows[:, HISTORY_COLUMNS.index("teeter_rad")] = np.sin(2 * np.pi * 7.0 * t) * (1 + t)  # growing 7 Hz
    rows[:, HISTORY_COLUMNS.index("omega_rad_s")] = 40 + t
    return columns_from_rows(rows, gj)


def _run(live, seconds: float, chunk_rows: int = 24):
    n = int(round(seconds / 0.0025))
    for k in range(0, n, chunk_rows):
        live.append(_chunk(k * 0.0025, min(chunk_rows, n - k)))


def test_a_short_run_is_shown_at_full_resolution_and_streamed():
    from bokeh.document import Document
    live = LivePlots()
    doc = Document()
    doc.add_root(live.sources[0])
    kinds = []
    doc.on_change(lambda event: kinds.append(type(event).__name__))
    _run(live, 2.0, chunk_rows=25)  # 800 rows, in chunks of an odd number of rows
    assert all(len(live.shown(i)["t_s"]) == 800 for i in range(len(PLOTS)))
    assert set(kinds) == {"ColumnsStreamedEvent"} and len(kinds) == 32  # one stream per chunk, no replacement


def test_a_40_s_run_holds_at_most_max_points_per_curve_and_keeps_the_peaks():
    live = LivePlots()
    _run(live, 40.0)  # 16 000 rows at 1x playback
    whole = live.frame()
    assert len(whole) == 16_000
    for i, (curves, _, _) in enumerate(PLOTS):
        shown = live.shown(i)
        assert len(shown["t_s"]) <= MAX_POINTS, curves
        assert np.all(np.diff(shown["t_s"]) > 0)
    teeter = live.shown(1)["teeter_deg"]
    # min/max-preserving: the extremes of the growing oscillation are in the page
    assert teeter.max() == pytest.approx(whole["teeter_deg"].max()) and teeter.min() == pytest.approx(
        whole["teeter_deg"].min())


def test_zooming_shows_the_range_at_full_resolution_and_reset_returns():
    live = LivePlots()
    _run(live, 40.0)
    live.show_range(10.0, 12.0)
    shown = live.shown(1)["t_s"]
    inside = shown[(shown >= 10.0) & (shown <= 12.0)]
    assert len(inside) == 801 and len(shown) <= MAX_POINTS  # every row of the 2 s (400 rows/s)
    live.append(_chunk(40.0, 24))  # while zoomed, the view stays
    assert live.shown(1)["t_s"].max() < 13.0
    live.reset()
    assert live.shown(1)["t_s"].max() == pytest.approx(40.0 + 23 * 0.0025)
    assert len(live.shown(1)["t_s"]) <= MAX_POINTS


def test_the_blades_legend_sits_above_the_plot_not_on_the_data():
    """Inside the plot (top left) it hid the first second of the tip twist: the kick's response."""
    from bokeh.models import Legend
    figs = LivePlots().figures()
    twist = next(f for f in figs if "twist" in f.title.text.lower())
    legends = [m for m in twist.above if isinstance(m, Legend)]
    assert len(legends) == 1 and [i.label["value"] for i in legends[0].items] == ["blade 0", "blade 1"]
    assert not any(isinstance(m, Legend) for f in figs for m in f.center)


def test_a_burst_of_live_changes_keeps_one_readable_label():
    """Ten arrow-key presses on the CG and EA sliders mid-run drew ten labels over each other
    ("CGCG4343%%..."): every change keeps its line, only the last of a burst its label."""
    live = LivePlots()
    live.mark(6.85, "GJ 300")
    for i, t in enumerate((11.2, 11.4, 11.6, 11.8)):
        live.mark(t, f"CG {41 + i} %")
    live.mark(15.15, "EA 30 %")
    assert list(live.markers.data["t_s"]) == [6.85, 11.2, 11.4, 11.6, 11.8, 15.15]
    assert list(live.markers.data["text"]) == ["GJ 300", "", "", "", "CG 44 %", "EA 30 %"]


def test_an_empty_plot_spans_a_typical_run_until_its_first_rows():
    """Before a run (and after Reset) the plots were blank boxes without axes, and each page load
    logged "could not set initial ranges" for them: a transparent frame spans time 0-10 s and a
    typical range of each quantity until the first rows come, and again after a clear."""
    from app.live import EMPTY_FRAME, PLOTS
    lp = LivePlots()
    lp.figures()
    for frame, (curves, _, _) in zip(lp.frames, PLOTS):
        assert list(frame.data["t_s"]) == [0.0, 10.0] and tuple(frame.data["y"]) == EMPTY_FRAME[curves[0]]
    lp.append(columns_from_rows(np.zeros((5, len(HISTORY_COLUMNS))), 1500.0))
    assert all(len(frame.data["t_s"]) == 0 for frame in lp.frames)
    lp.clear()
    assert all(list(frame.data["t_s"]) == [0.0, 10.0] for frame in lp.frames)
