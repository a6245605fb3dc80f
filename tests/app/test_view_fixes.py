"""Four defects a tester met at 1280x720: the map's hover wrote "growth rate: NaN 1/s" for a cell
without one; the GJ slider read "1.50e+3" for 1500; the fidelity ladder's titles were clipped and
its legends lay on the curves; an out-of-range GJ in presentation mode said so in 9 px dark red on
the dark header, which grew taller (and the input's spinner arrows were white on white)."""
from __future__ import annotations

import json
import math
import re
import shutil
import subprocess
from types import SimpleNamespace

import holoviews as hv
import numpy as np
import panel as pn
import pytest
from bokeh.document import Document
from bokeh.models import HoverTool, Legend, Plot

from amra_core.simulation import COL
from amra_core.stability import CellResult
from app.controls import Controls
from app.inputs import GJ_READOUT_JS, checked_input, gj_readout, gj_slider
from app.session import Session
from app.views.ladder import LadderView
from app.views.map import MapView, cell_columns

HEADER_BACKGROUND = "#263238"  #: app/app.py's header_background

# -- 1. the map's hover


def _cell(cg, gj, verdict, growth_per_s):
    return CellResult(cg=cg, gj_nm2=gj, verdict=verdict, stable=verdict == "stable",
                      boundary_kind="" if verdict == "stable" else verdict, growth_rate_per_s=growth_per_s,
                      frequency_hz=None, omega_trim_rad_s=None)


def test_the_map_hover_writes_a_dash_for_a_cell_without_a_growth_rate():
    session = SimpleNamespace(doc=None, throttle=lambda fn, period_s: SimpleNamespace(kick=lambda: None))
    view = MapView(session, registry=None, who=0, on_pick=lambda cell: None)
    fig = view.figure()
    view.cells_source.stream(cell_columns([_cell(0.2, 41.0, "windmill-brake", None),
                                           _cell(0.4, 1500.0, "stable", -0.1234)]))
    (hover,) = [h for h in fig.select({"type": HoverTool}) if "growth rate (eigenvalue)" in dict(h.tooltips)]
    field = re.fullmatch(r"@\{?(\w+)\}?", dict(hover.tooltips)["growth rate (eigenvalue)"])  # a text column, as it is
    assert field is not None, hover.tooltips
    assert list(view.cells_source.data[field[1]]) == ["—", "-0.123 1/s"]


# -- 2. the GJ slider's readout


@pytest.mark.parametrize("gj_nm2, shown", [(10.0, "10"), (12.34, "12.3"), (30.0, "30"), (612.3, "612"),
                                           (1500.0, "1500"), (6100.0, "6100"), (10000.0, "10000")])
def test_the_gj_readout_is_written_out_to_3_significant_digits(gj_nm2, shown):
    assert gj_readout(math.log10(gj_nm2)) == shown


@pytest.mark.skipif(shutil.which("node") is None, reason="no node to run the formatter's JavaScript")
def test_the_gj_sliders_javascript_follows_the_python_rule():
    """The slider's own formatter code, run by node over the whole range, writes what gj_readout does
    (the browser test runs it in the page)."""
    code = gj_slider(Controls()).format.code
    assert code == GJ_READOUT_JS
    ticks = [float(t) for t in np.linspace(1.0, 4.0, 601)]  # log10 GJ [N m²/rad], the slider's range
    js = f"const f = (tick) => {{ {code} }};\nconsole.log(JSON.stringify({json.dumps(ticks)}.map(f)));"
    out = subprocess.run(["node", "-e", js], capture_output=True, text=True, timeout=60, check=True).stdout
    assert json.loads(out) == [gj_readout(t) for t in ticks]


# -- 3. the fidelity ladder

#: at 1280x720 each ladder plot is 287 px wide: its title has ~237 px (frame to canvas edge), about 26
#: characters of Bokeh's bold title ("Rotor speed: previous vs l" was cut there)
TITLE_MAX_CHARS = 22


def test_the_ladders_titles_fit_and_its_legends_lie_outside_the_data():
    hv.extension("bokeh")
    view = LadderView(Session())
    t = np.linspace(0.0, 3.0, 50)
    view.show({"runs": {fid: {"t": t, "omega": 30 + 0 * t, "teeter_deg": 0 * t, "twist_deg": 9 + 0 * t}
                        for fid in ("rigid", "fem-torsion", "fem-coupled")}, "verdicts": []})
    rows = np.zeros((50, len(COL)))
    rows[:, COL["t_s"]] = t
    view.compare(rows, rows)
    root = pn.panel(view).get_root(Document())
    plots = [p for p in root.select({"type": Plot}) if p.title is not None and p.title.text]
    assert len(plots) == 6, [p.title.text for p in plots]
    for p in plots:
        assert len(p.title.text) <= TITLE_MAX_CHARS, p.title.text
        assert not [r for r in p.center if isinstance(r, Legend)], p.title.text  # not on the curves
        outside = [r for side in (p.below, p.right, p.left, p.above) for r in side if isinstance(r, Legend)]
        assert len(outside) == 1 and len(outside[0].items) in (2, 3), p.title.text


# -- 4. an input's message on the dark header


def _luminance(hex_colour: str) -> float:
    def lin(c):
        return c / 12.92 if c <= 0.03928 else ((c + 0.055) / 1.055) ** 2.4
    r, g, b = (int(hex_colour.lstrip("#")[i:i + 2], 16) / 255 for i in (0, 2, 4))
    return 0.2126 * lin(r) + 0.7152 * lin(g) + 0.0722 * lin(b)


def contrast(fg: str, bg: str) -> float:
    """WCAG contrast ratio of two colours ``#rrggbb``."""
    hi, lo = sorted((_luminance(fg), _luminance(bg)), reverse=True)
    return (hi + 0.05) / (lo + 0.05)


def _bad_value_message(box):
    box.objects[0].value = "5"
    widget, message = box.objects
    assert message.visible and "GJ [N m²/rad] = 5 is out of range: allowed 10 to 10000" in message.object
    return widget, message


def test_a_message_on_the_dark_header_is_legible_and_keeps_the_header_height():
    box = checked_input(Controls(), "gj_nm2", css_classes=["amra-present-gj"], width=170, on_dark=True,
                        styles={"font-size": "20px"}, stylesheets=[":host input {font-size: 20px; height: 40px}"])
    widget, message = _bad_value_message(box)
    st = message.styles
    background = st.get("background", st.get("background-color", HEADER_BACKGROUND))
    assert contrast(st["color"], background) >= 4.5, st  # WCAG AA (#b71c1c on #263238: 1.9)
    assert float(st["font-size"].removesuffix("px")) >= 14, st  # was 90 % of 10 px
    assert st["position"] == "absolute", st  # over the page below: the header keeps its height
    # the caller's stylesheet stays (a text input: no spinner arrows for the header's white to reach)
    assert ":host input {font-size: 20px; height: 40px}" in widget.stylesheets


def test_a_message_in_the_sidebar_stays_a_line_under_the_input():
    widget, message = _bad_value_message(checked_input(Controls(), "gj_nm2"))
    assert message.styles == {"color": "#b71c1c", "font-size": "90%"} and message.sizing_mode == "stretch_width"


def test_the_presentation_headers_gj_input_is_the_dark_variant(dash):
    """Needs app/app.py's _live_bar to pass ``on_dark=True`` to checked_input."""
    hv.extension("bokeh")
    bar = dash._live_bar()
    (box,) = [o for o in bar.objects if isinstance(o, pn.Column)
              and "amra-present-gj" in (o.objects[0].css_classes or [])]
    _, message = _bad_value_message(box)
    assert message.styles["position"] == "absolute" and contrast(message.styles["color"],
                                                                 message.styles["background"]) >= 4.5


# -- the root locus's summary and axes


def test_the_locus_summary_puts_the_fold_where_the_branch_ends_not_at_a_lower_island():
    """fem-coupled, axial, CG 40 %: "no trim (fold) below about 50 N m²/rad", from an isolated set of
    violently unstable trims at GJ 50-79, while the branch ends near 700 (as the map says)."""
    from app.compute import LocusPoint, locus_text
    pts = [LocusPoint(g, True, (), -0.5, True) for g in (3000.0, 1500.0, 900.0)]
    pts += [LocusPoint(g, True, (), 0.3, False) for g in (800.0, 706.0)]
    pts += [LocusPoint(g, False, (), None, False) for g in (680.0, 300.0, 81.0)]
    pts += [LocusPoint(78.75, True, (), 218.0, False), LocusPoint(50.0, True, (), 248.0, False)]
    text = locus_text(pts)
    assert "no trim (fold) below about 706 N m²/rad (it lies between the locus's grid points 680 and 706)" in text
    assert "trims again at GJ 50-78.75 N m²/rad, cut off from the branch (σ up to +248 1/s)" in text
    assert "unstable trims on the branch at GJ 706-800 N m²/rad" in text


def test_a_locus_with_no_trim_at_its_stiff_end_says_so_not_nan():
    from app.compute import LocusPoint, locus_text
    pts = [LocusPoint(g, False, (), None, False) for g in (3000.0, 1000.0)] + [LocusPoint(500.0, True, (), -0.2, True)]
    text = locus_text(pts)
    assert "no trim at the stiff end, GJ 3000 N m²/rad" in text and "nan" not in text
    assert "trims again at GJ 500 N m²/rad, cut off" in text


def test_the_locus_summary_gives_the_unstable_stretches_not_everything_below_the_highest():
    """fem-coupled, CG 40 %: "unstable trims on the branch at GJ ≤ 667.8" read as unstable all the way
    down, while the map's cells at 416-623 are stable and only 633-668 flutters."""
    from app.compute import LocusPoint, locus_text
    pts = [LocusPoint(g, True, (), -0.5, True) for g in (3000.0, 1200.0, 700.0)]
    pts += [LocusPoint(g, True, (), 0.9, False) for g in (667.8, 640.0)]
    pts += [LocusPoint(g, True, (), -0.4, True) for g in (600.0, 450.0)]
    pts += [LocusPoint(300.0, True, (), 0.2, False), LocusPoint(200.0, False, (), None, False)]
    text = locus_text(pts)
    assert "unstable trims on the branch at GJ 300, 640-667.8 N m²/rad (the locus's grid points)" in text
    assert "≤" not in text


def test_the_least_damped_plot_keeps_its_own_real_part_range():
    """Linked by their shared σ dimension, the least-damped plot spanned the root locus's -50..0 1/s."""
    from app.views.modes import ModesView
    session = SimpleNamespace(subscribe=lambda *a, **k: None)
    panes = ModesView(session).__panel__().select(pn.pane.HoloViews)
    assert len(panes) == 2 and not any(p.linked_axes for p in panes)


def test_the_locus_plots_follow_a_locus_that_arrives_after_they_are_drawn():
    """fem-coupled forward flight (mu 0.3): the locus arrived after the tab was drawn; the plots kept
    their empty 0..1 ranges (not framewise) and the colour-mapped points failed in the browser
    ("invalid color array"): both plots looked empty."""
    from app.compute import LocusPoint
    from app.views.modes import ModesView
    from amra_core.stability import Mode
    view = ModesView(SimpleNamespace(subscribe=lambda *a, **k: None))
    locus = hv.DynamicMap(view._locus, streams=[view.points_pipe, view.current])
    crit = hv.DynamicMap(view._critical, streams=[view.points_pipe, view.current])
    plots = [hv.renderer("bokeh").get_plot(dm) for dm in (locus, crit)]
    modes = (Mode("torsion", 24.6, 0.01, -2.0, {}), Mode("lag", 8.6, 0.02, -0.9, {}))
    view.show_locus([LocusPoint(3000.0, True, modes, -0.9, True), LocusPoint(2176.0, True, modes, 2.4, False),
                     LocusPoint(2000.0, False, (), None, False)], "")
    x = plots[0].handles["x_range"]
    assert x.start <= -2.0 and x.end >= -0.9  # the locus's real parts, not 0..1
    y = plots[1].handles["y_range"]
    assert y.start <= -0.9 and y.end >= 2.4
    pts = plots[0].subplots[list(plots[0].subplots)[0]].handles["source"].data
    assert all(isinstance(c, str) and c.startswith("#") for c in pts["colour"])  # colours, not a mapped column


def test_a_case_without_a_trim_says_it_has_no_modes_to_watch():
    """Fig. 10 at GJ 100 has no trim: the select offered "(choose a mode)" over nothing."""
    from amra_core.stability import Mode
    from app.views.modes import ModesView
    view = ModesView(SimpleNamespace(subscribe=lambda *a, **k: None))
    view.show_modes({"modes": [], "text": "**No trim** for this case, so no modes"})
    assert list(view.pick.options) == ["(no modes: this case has no trim)"]
    assert view.animation.info.object == "No modes to watch: this case has no trimmed autorotation."
    view.show_modes({"modes": [Mode("torsion", 27.9, 0.083, -14.5)], "text": "Modes of the trim"})
    assert list(view.pick.options) == ["(choose a mode)", "torsion, 27.9 Hz, σ -14.5 1/s"]
    assert view.animation.info.object == "Pick a mode to watch its shape."


def test_the_locus_circle_names_the_sampled_gj_it_shows():
    """At a GJ without a trim the circle sat on the modes of the nearest trimmed GJ, read as the case's."""
    from app.compute import LocusPoint
    from amra_core.stability import Mode
    from app.views.modes import ModesView
    hv.extension("bokeh")
    view = ModesView(SimpleNamespace(subscribe=lambda *a, **k: None))
    pts = [LocusPoint(424.0, True, (Mode("torsion", 27.9, 0.083, -14.5),), -14.5, True),
           LocusPoint(100.0, False, (), None, False)]
    overlay = view._locus(pts, 100.0)
    circle = [el for el in overlay if el.label == "nearest sampled GJ with a trim"]
    assert len(circle) == 1 and list(circle[0].dimension_values("gj_nm2")) == [424.0]


def test_the_help_gives_the_windmill_brake_threshold_the_solver_uses():
    """The Help said windmill-brake meant a descent of 4-5 v_h; the trims and the runs call every
    equilibrium beyond 2 v_h so (map cells sit at 2.05-2.9 v_h). The Help now states the solver's own
    ratio, and a cell just beyond it is one."""
    from amra_core import equilibrium, verdict
    from app.views.help import VERDICTS
    text = dict(VERDICTS)["windmill-brake"]
    assert "4-5 times" not in text
    assert f"faster than {equilibrium.WINDMILL_BRAKE_RATIO:g} times the hover induced velocity" in text
    assert equilibrium.WINDMILL_BRAKE_RATIO == 2.0 and 2.0 <= verdict.WINDMILL_BRAKE_RATIO <= 2.1


def test_two_close_modes_are_two_choices():
    """Fem-coupled GJ 1500, mu 0.1: torsion 28.954 Hz, -17.71 1/s and 28.957 Hz, -17.73 1/s were one option
    ("torsion, 29 Hz, σ -17.7 1/s"): 28 rows in the table, 27 choices, one mode that could not be picked."""
    from amra_core.stability import Mode
    from app.views.modes import ModesView
    view = ModesView(SimpleNamespace(subscribe=lambda *a, **k: None))
    view.show_modes({"modes": [Mode("torsion", 28.954, 0.1, -17.71), Mode("torsion", 28.957, 0.1, -17.73)],
                     "text": "Modes of the trim"})
    picks = [v for v in view.pick.options.values() if v is not None]
    assert picks == [(-17.71, 28.954, "torsion"), (-17.73, 28.957, "torsion")]
