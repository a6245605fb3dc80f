"""The comparison views show their data (issue 23 §7): the ladder's and the previous-vs-last plots
take their axis ranges from the runs sent (they kept the empty plot's 0-1), carry a legend entry
per run, and the verdict table prints numbers to 3 significant digits and no 'None'."""
from __future__ import annotations

import holoviews as hv
import numpy as np

from amra_core.simulation import COL
from app.session import Session
from app.views.ladder import COMPARED, LadderView, verdict_table


def _runs():
    t = np.linspace(0, 5, 200)
    return {"rigid": {"t": t, "omega": 34 + 0.5 * np.sin(t), "teeter_deg": 0.3 * np.sin(9 * t),
                      "twist_deg": 2 + 0.1 * np.sin(30 * t)},
            "fem-coupled": {"t": t, "omega": 33 - 3 * t, "teeter_deg": 0.2 * np.sin(9 * t),
                            "twist_deg": 3 + 0.2 * np.sin(30 * t)}}


def test_ladder_plots_range_over_their_data():
    hv.extension("bokeh")
    view = LadderView(Session())
    dmap = hv.DynamicMap(lambda data: view._plot(data, "omega", hv.Dimension("omega_rad_s"), "t"),
                         streams=[view.pipe])
    plot = hv.renderer("bokeh").get_plot(dmap)
    view.show({"runs": _runs(), "verdicts": [("rigid", "stable", -0.123456789, None, None, "")]})
    yr = plot.state.y_range
    assert yr.start <= 18.0 and yr.end >= 34.5  # fem-coupled falls to 18 rad/s, rigid reaches 34.5
    legend = [item.label["value"] for item in plot.state.legend[0].items]
    assert legend == ["rigid", "fem-torsion", "fem-coupled"]


def test_previous_vs_last_overlay_ranges_over_the_runs():
    hv.extension("bokeh")
    view = LadderView(Session())
    dmap = hv.DynamicMap(lambda data: view._plot(data, "omega", hv.Dimension("omega_rad_s"), "t", COMPARED),
                         streams=[view.compare_pipe])
    plot = hv.renderer("bokeh").get_plot(dmap)
    rows = np.zeros((50, len(COL)))
    rows[:, COL["t_s"]], rows[:, COL["omega_rad_s"]] = np.linspace(0, 1, 50), 33.9
    slower = rows.copy()
    slower[:, COL["omega_rad_s"]] -= 10
    view.compare(rows, slower)
    assert plot.state.y_range.start <= 23.9 and plot.state.y_range.end >= 33.9


def test_verdict_table_precision():
    table = verdict_table([("rigid", "stable", -0.123456789, 12.3456, None, "decays")])
    assert table.iloc[0].tolist() == ["rigid", "stable", "-0.123", "12.3", "—", "decays"]


def test_the_two_rows_keep_their_own_axes():
    """Panel links the axes of HoloViews panes with the same dimensions: the previous-vs-last rotor
    speed (two runs at 33.9 rad/s) shared its y range with the empty ladder plot below and was drawn
    on 0-34 rad/s, its curve hidden under the frame."""
    import panel as pn
    from bokeh.document import Document
    from bokeh.models import Plot
    hv.extension("bokeh")
    view = LadderView(Session())
    root = pn.panel(view).get_root(Document())
    plots = [p for p in root.select({"type": Plot}) if p.title is not None and p.title.text.startswith("Rotor speed")]
    assert len(plots) == 2
    assert plots[0].y_range is not plots[1].y_range and plots[0].x_range is not plots[1].x_range


def test_the_ladder_runs_the_softening_the_run_has():
    """Fig. 10's ladder ran GJ 100 from the start (rigid: "no-autorotation", no collapse time, the
    rotor speed from 24.7 rad/s), while its run is softened from GJ 1500 at 2 s and collapses at
    3.3 s. The ladder runs the run's scenario, and says so."""
    from app.app import ladder_case_text
    from app.compute import run_ladder
    from app.controls import Controls
    from amra_core.scenario import run_scenario
    c = Controls(preset="fig10")
    c.run_s = 6.0
    assert "1500 → 100 N m²/rad at 2 s as in the run" in ladder_case_text(c)
    scenario = c.scenario(fidelity="rigid")
    (fid, verdict, growth, freq, collapse_s, _), = run_ladder({"rigid": scenario})["verdicts"]
    run = run_scenario(scenario).verdict()
    assert (fid, verdict, collapse_s) == ("rigid", run.verdict, run.collapse_time_s)
    assert 2.0 < collapse_s < 6.0
