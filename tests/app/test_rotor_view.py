"""The rotor drawn from the solver (issue 23 §3): the live drawing follows the run's poses, and a
mode picked in the modes table is computed in the pool and played frame by frame."""
from __future__ import annotations

import math

import numpy as np
import pytest

from amra_core.flight import FlightCondition, SolverSettings
from amra_core.rotor_io import load_preset
from app import compute
from app.app import Dashboard
from app.views.rotor import naca0012, side_view, tip_section

from test_dashboard import pump_until


def test_drawing_geometry():
    """Blade 1 is drawn to the left, the exaggeration is the stated one, a nose-up twist raises the
    leading edge, and the section turns about its elastic axis."""
    r = np.array([0.4, 2.0, 3.8])
    flap = np.array([[0.01, 0.02, 0.04], [-0.01, -0.02, -0.04]])
    lines = side_view(r, flap, 0.01, flap_scale=10.0)
    np.testing.assert_allclose(lines["blade0"][0][1:], r)
    np.testing.assert_allclose(lines["blade1"][0][1:], -r)
    np.testing.assert_allclose(lines["blade0"][1][1:], 10 * flap[0])
    assert lines["hub"][1][1] == pytest.approx(math.tan(0.1) * 0.4)
    x0, y0 = naca0012()
    assert x0.min() == 0.0 and x0.max() == pytest.approx(1.0) and y0.max() == pytest.approx(0.06, abs=2e-3)
    x, y = tip_section(0.02, 0.2, 0.32, twist_scale=10.0)  # 0.2 rad nose up as drawn
    le = np.argmin(x)
    assert y[le] > 0 and x[le] == pytest.approx(-0.32 * 0.2 * math.cos(0.2), rel=1e-6)
    xs, ys = tip_section(0.0, 0.2, 0.32)
    assert xs.min() == pytest.approx(-0.32 * 0.2) and xs.max() == pytest.approx(0.68 * 0.2)  # EA at the origin


def test_the_drawing_turns_the_drawn_rotor_s_section_about_its_own_elastic_axis():
    """The tip section is the rotor's own (chord and elastic axis of the outermost station, from the
    pose) and the side view spans its radius: it was always the default rotor's (EA 32 %, chord
    0.197 m, R 3.81 m), whatever the EA control or an uploaded rotor said."""
    from amra_core.model import Y_OMEGA, compile_model
    from amra_core.pose import rotor_pose
    from app.views.rotor import RotorDrawing
    rotor = load_preset("paper-boundary").with_overrides(x_ea=0.40)
    model = compile_model(rotor, FlightCondition(), SolverSettings("rigid"))
    y = np.zeros(model.n_y); y[Y_OMEGA] = 38.0
    pose = rotor_pose(model, y)
    assert pose.x_ea == pytest.approx(0.40) and pose.radius_m == rotor.radius_m
    assert pose.chord_m == pytest.approx(rotor.stations.at("chord_m", pose.r_m[-1]))
    drawing = RotorDrawing()
    side, tips = drawing.figures
    drawing.draw(pose.r_m, pose.flap_m, pose.twist_rad, pose.teeter_rad, pose.chord_m, pose.x_ea, pose.radius_m)
    x = np.asarray(drawing.sections[0].data["x"])
    assert x.min() == pytest.approx(-0.40 * pose.chord_m) and x.max() == pytest.approx(0.60 * pose.chord_m)
    assert side.x_range.end == pytest.approx(1.05 * rotor.radius_m)
    assert tips.x_range.end == pytest.approx(0.8 * pose.chord_m)


@pytest.mark.parametrize("fidelity", ["rigid", "fem-coupled"])
def test_mode_frames_are_visible_and_say_the_mode(fidelity):
    rotor = load_preset("paper-boundary").with_overrides(gj_nm2=1500.0, x_ea=0.32, x_cg=0.40)
    from amra_core.stability import analyse
    from amra_core.model import compile_model
    res = analyse(compile_model(rotor, FlightCondition(), SolverSettings(fidelity=fidelity)))
    flap_mode = next(m for m in res.modes if m.label == "flap")
    out = compute.mode_frames(rotor, FlightCondition(), SolverSettings(fidelity=fidelity),
                              flap_mode.real_part_per_s, flap_mode.frequency_hz, "flap")
    flap = np.array(out["flap"])
    assert flap.shape == (compute.MODE_FRAMES, 2, len(out["r_m"]))
    assert np.abs(flap).max() == pytest.approx(compute.MODE_FLAP_DRAWN * rotor.radius_m)
    assert np.abs(np.array(out["twist"])).max() == pytest.approx(compute.MODE_TWIST_DRAWN_RAD)
    assert f"{flap_mode.frequency_hz:.3g} Hz" in out["text"] and "cm of tip flap per degree" in out["text"]
    assert out["x_ea"] == pytest.approx(0.32) and out["radius_m"] == rotor.radius_m


def test_the_live_rotor_follows_the_run_and_a_picked_mode_plays(dash, wait):
    dash.controls.param.update(run_s=0.6, speed=10.0)
    dash.controls.param.trigger("run")
    pump_until(dash, lambda: dash.last_history is not None, wait, what="the run")
    view = dash.rotor_view
    assert view.poses >= 1 and "t = 0.60 s" in view.info.object  # the last pose of the run is drawn
    from amra_core.simulation import COL
    from app.views.rotor import FLAP_SCALE
    last = dash.last_history[-1]
    # what is drawn is the final state's pose, and the rigid blade is straight: its stations (after
    # the hub point) lie on a line in r, which reaches the history's tip flap at R = 3.81 m
    from amra_core.pose import rotor_pose
    sim = dash.session.sim
    final = rotor_pose(sim.model, sim.y)
    assert not len(view.drawing.blades[0].data["x"])  # the tab was never shown: nothing drawn yet
    view.__panel__()  # shown: the last pose is drawn
    for b in (0, 1):
        r = np.abs(np.asarray(view.drawing.blades[b].data["x"])[1:])
        w = np.asarray(view.drawing.blades[b].data["y"])[1:] / FLAP_SCALE
        np.testing.assert_allclose(w, final.flap_m[b], rtol=1e-12)
        slope, intercept = np.polyfit(r, w, 1)
        assert np.abs(slope * r + intercept - w).max() < 1e-9
        assert slope * 3.81 + intercept == pytest.approx(last[COL[f"tip_flap_{b}_m"]], rel=1e-4)
    assert f"{math.degrees(last[COL['tip_twist_0_rad']]):+.2f}°" in view.info.object
    # the modes table offers its modes; picking one computes and plays its frames
    pump_until(dash, lambda: len(dash.modes.pick.options) > 1, wait, what="the modes")
    choice = next(v for k, v in dash.modes.pick.options.items() if v is not None and v[2] == "flap")
    dash.modes.pick.value = choice
    pump_until(dash, lambda: dash.modes.animation.frames is not None, wait, what="the mode's frames")
    anim = dash.modes.animation
    anim.__panel__()  # its tab shown: the frames are drawn
    first = np.array(anim.drawing.blades[0].data["y"])
    assert len(first)
    anim.player.value = compute.MODE_FRAMES // 4  # a quarter cycle on, the blade has moved
    assert not np.allclose(np.array(anim.drawing.blades[0].data["y"]), first)
    assert anim.player.visible and "flap" in anim.info.object


def test_the_rotor_drawings_legends_sit_above_them():
    """Inside the side view (top left) the legend covered blade 1's outer span."""
    from bokeh.models import Legend
    from app.views.rotor import RotorDrawing
    figs = RotorDrawing().figures
    for fig in figs:
        assert [type(m) for m in fig.above].count(Legend) == 1
        assert not any(isinstance(m, Legend) for m in fig.center)
    assert [i.label["value"] for i in next(m for m in figs[0].above if isinstance(m, Legend)).items] == \
        ["hub bar", "blade 0", "blade 1"]


def test_a_pose_that_rounds_to_zero_reads_plus_zero():
    """The live rotor read "teeter -0.00°" for a teeter of -2e-6 deg."""
    from types import SimpleNamespace
    from app.views.rotor import pose_line
    p = SimpleNamespace(teeter_rad=-3e-8, twist_rad=[[0.049], [-1e-9]], flap_m=[[0.295], [-0.0001]])
    line = pose_line(3.0, p)
    assert "teeter +0.00°" in line and "/ +0.00° (blade 0 / 1)" in line and "/ +0.0 cm" in line and "-0." not in line
