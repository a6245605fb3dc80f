"""The dashboard without a browser: a run reaches the plots, apply-live from the controls, stop on
close, verdicts, modes/locus/fan analyses, map cells, exports, bad input as messages."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import panel as pn
import pytest

from amra_core.simulation import HISTORY_COLUMNS
from app.controls import PRESETS


def pump_until(d, pred, wait, timeout_s=60, what="condition"):
    def step():
        d.session.pump()
        return pred()
    wait(step, timeout_s, what=what)


def test_a_run_streams_into_the_plots_and_ends_with_a_verdict(dash, wait):
    dash.controls.param.update(run_s=1.0, speed=10.0)
    dash.controls.param.trigger("run")
    pump_until(dash, lambda: dash.last_history is not None, wait, what="the run")
    data = dash.live.frame()
    assert len(data) > 20 and list(data.columns)[:2] == ["t_s", "omega_rad_s"]
    assert data["t_s"].iloc[-1] == pytest.approx(1.0, abs=0.01) and (data["gj_nm2"] == 1500.0).all()
    # a 1 s run is too short to call stable (issue 21 §7): its final verdict says so
    v = dash.status.verdict
    assert v.verdict == "undetermined" and "run too short" in v.explanation, v
    assert "data-final='true'" in dash.status.card.value
    assert "finished" in dash.status.run.value
    csv = dash.history_csv().getvalue().splitlines()
    meta = [ln for ln in csv if ln.startswith("# ")]
    assert meta[0].startswith("# AMRA ") and "# fidelity: rigid" in meta and "# verdict: undetermined" in meta
    # how the run started and what its verdict says, beside the rows (an untrimmed run's t = 0 read
    # as a trim of the case)
    assert "# start: started from the trimmed steady autorotation plus the perturbation" in meta
    assert "# run_state: reached its end" in meta
    t_reached = float(next(ln for ln in meta if ln.startswith("# t_reached_s: ")).split(": ")[1])
    assert t_reached == pytest.approx(1.0, abs=0.01) and t_reached == pytest.approx(dash.last_history[-1, 0], abs=0.01)
    assert "# outcome: undetermined" in meta and any(ln.startswith("# growth_rate_per_s (run's fit): ") for ln in meta)
    assert any(ln.startswith("# rotor_speed: rotor speed kept") for ln in meta)
    assert csv[len(meta)] == ",".join(HISTORY_COLUMNS) and len(csv) == len(meta) + len(dash.last_history) + 1
    assert dash.exports.buttons["history"].filename == "amra-paper-boundary-rigid-gj1500-cg40-history.csv"
    from app.exports import names_for  # a map per EA and aero model: two EAs were one file name
    assert names_for(dash.controls)["map"] == "amra-paper-boundary-rigid-theodorsen-ea32-map.csv"


def test_a_history_saved_mid_run_after_a_stop_or_after_reset_says_how_far_the_run_got(dash, wait):
    """A file saved at t = 12 s of a 30 s run said '# verdict: stable' and '# run_s: 30' and nothing
    of the run still going; after Stop, nothing of the stop; after Reset it still held the cleared
    run's rows (an engineer's find)."""
    def header():
        return [ln for ln in dash.history_csv().getvalue().splitlines() if ln.startswith("# ")]

    dash.controls.param.update(run_s=30.0, speed=1.0)
    dash.start_run()
    pump_until(dash, lambda: dash.status.verdict is not None and not dash.status.final, wait, what="a verdict so far")
    meta = header()
    state = next(ln for ln in meta if ln.startswith("# run_state: "))
    assert state.startswith("# run_state: running: saved at t = ") and state.endswith(" of 30 s (the verdict is so far)")
    dash.controls.param.trigger("stop")
    pump_until(dash, lambda: dash.last_history is not None, wait, what="the stop")
    meta = header()
    t_end = float(next(ln for ln in meta if ln.startswith("# t_reached_s: ")).split(": ")[1])
    assert 0.0 < t_end < 30.0
    assert f"# run_state: stopped by its user at t = {t_end:.2f} s of 30 s" in meta
    dash.reset()
    csv = dash.history_csv().getvalue().splitlines()
    assert "# run_state: no run (none yet, or reset)" in csv and csv[-1] == ",".join(HISTORY_COLUMNS)


def test_moving_gj_mid_run_applies_live_and_the_run_continues(dash, wait):
    dash.controls.param.update(run_s=4.0, speed=4.0)
    dash.start_run()
    pump_until(dash, lambda: len(dash.live.frame()) and dash.live.frame()["t_s"].iloc[-1] > 0.5,
               wait, what="0.5 s of run")
    t_change = dash.live.frame()["t_s"].iloc[-1]
    dash.controls.gj_nm2 = 700.0
    pump_until(dash, lambda: (dash.live.frame()["gj_nm2"] == 700.0).any(), wait, what="the new GJ")
    data = dash.live.frame()
    first_new = data[data["gj_nm2"] == 700.0]["t_s"].iloc[0]
    assert first_new > t_change and np.all(np.diff(data["t_s"]) > 0)  # the same run, continuing
    assert "applied live" in dash.status.note.value
    # the server's share of the slider latency is measured (change received -> first rows sent)
    assert len(dash.session.live_latencies_s) == 1 and 0.0 < dash.session.live_latencies_s[0] < 30.0
    dash.controls.param.trigger("stop")
    assert not dash.session.running


def test_a_live_gj_change_is_told_as_what_moved(dash, wait):
    """After GJ alone was moved mid-run, the card's case line still read GJ 1500, and the verdict said
    "since the change to GJ 300 N m^2/rad, EA 32.0 % chord, CG 40.0 % chord" (EA and CG had not moved)
    and that "the rotor speed decayed from the start" (it had been steady until the change)."""
    dash.controls.param.update(run_s=3.0, speed=4.0)
    dash.start_run()
    pump_until(dash, lambda: len(dash.live.frame()) and dash.live.frame()["t_s"].iloc[-1] > 0.5,
               wait, what="0.5 s of run")
    dash.controls.gj_nm2 = 100.0
    assert dash.status.note.value == "applied live at the next chunk: GJ 100 N m²/rad"
    pump_until(dash, lambda: dash.last_history is not None, wait, what="the run's end")
    card = dash.status.card.value.replace("\u00a0", " ")
    assert "GJ 1500 N m²/rad" in card and "· live: GJ 100 N m²/rad at " in card
    assert "since the change to GJ 100 N m²/rad at t = " in card
    assert "EA 32.0 % chord" not in card and "CG 40.0 % chord" not in card
    assert "decayed from the start" not in dash.status.verdict.explanation


def test_a_preset_chosen_mid_run_is_the_next_run_not_a_live_change(dash, wait):
    """Fig. 10 running, "Table 1 A" chosen: the preset's GJ, EA and CG (1471, 31.4, 33) went live into
    the paper-boundary run, whose export then described neither case (paper-boundary at the McCutcheon
    values, airspeed 0)."""
    dash.controls.preset = "fig10"
    dash.controls.param.update(run_s=4.0, speed=4.0)
    dash.start_run()
    pump_until(dash, lambda: len(dash.live.frame()) and dash.live.frame()["t_s"].iloc[-1] > 0.5,
               wait, what="0.5 s of run")
    dash.controls.preset = "table1a"
    assert dash.controls.gj_nm2 == 1471.0 and dash.controls.rotor == "mccutcheon"
    assert dash.status.note.value.startswith("the preset's case takes effect at the next run")
    pump_until(dash, lambda: dash.last_history is not None, wait, what="the run's end")
    assert not dash.session.sim.changes or all("1471" not in what for _, _, what in dash.session.sim.changes)
    meta = [ln for ln in dash.history_csv().getvalue().splitlines() if ln.startswith("#")]
    assert "# rotor: paper-boundary" in meta and not any("1471" in ln for ln in meta), meta


def test_the_card_says_a_run_is_starting_until_its_first_verdict(dash, wait):
    """About a second after Run the card read "no run yet. Press Run." beside "Run: running, t = 0.44 s"
    (and after a preset change it kept the last case's "stable (final)"); a note about the running run
    stayed after it ended."""
    from app.views.status import RUNNING_WORDS, TRIMMING_WORDS
    dash.controls.param.update(run_s=3.0, speed=4.0)
    dash.start_run()
    assert TRIMMING_WORDS in dash.status.card.value and "no run yet" not in dash.status.card.value
    assert "running" in dash.status.badge.value
    pump_until(dash, lambda: RUNNING_WORDS in dash.status.card.value or dash.status.verdict is not None, wait,
               what="the run's start")
    dash.controls.gj_nm2 = 1400.0
    assert dash.status.note.value.startswith("applied live")
    pump_until(dash, lambda: dash.last_history is not None, wait, what="the run's end")
    assert dash.status.verdict is not None and dash.status.note.value == ""


def test_close_stops_the_worker_and_releases_the_map(dash, wait):
    dash.controls.param.update(run_s=30.0, speed=1.0)
    dash.refresh_analyses()
    dash.start_run()
    wait(lambda: dash.session.running, 10, what="the run")
    job = dash.map.job
    assert job is not None and id(dash) in job.subscribers
    dash.close()
    assert not dash.session.running
    assert id(dash) not in job.subscribers


def test_fig10_preset_tells_the_papers_story(dash, wait):
    """Steady autorotation at the nominal GJ, softened to GJ 100 at t = 2 s, then flutter and the
    rotor speed below half its trim within a few seconds (paper Fig. 10)."""
    from amra_core.simulation import COL
    dash.controls.preset = "fig10"
    assert dash.controls.soften_at_s == 2.0 and dash.controls.gj_nm2 == 100.0
    assert "**The paper:**" in PRESETS["fig10"].explanation and "GJ ≈ 414" in PRESETS["fig10"].explanation
    dash.controls.param.update(speed=50.0)
    assert dash.controls.preset == "fig10"  # the playback speed is not part of the case
    dash.start_run()
    pump_until(dash, lambda: dash.last_history is not None, wait, 180, what="the Fig. 10 run")
    h = dash.last_history
    omega0 = h[0, COL["omega_rad_s"]]
    assert h[h[:, 0] < 2.0, COL["omega_rad_s"]].min() > 0.97 * omega0  # steady until the softening
    v = dash.status.verdict
    assert v.verdict in ("flutter", "divergence", "no-autorotation") and 2.0 < v.collapse_time_s < 8.0, v
    assert v.outcome == "rotor-speed-collapse", v  # no autorotation at GJ 100: the rotor speed is lost
    assert "softened as scripted at t = 2.0" in dash.status.note.value and "GJ 100 N m²/rad" in dash.status.note.value
    assert (dash.live.frame()["gj_nm2"] == 100.0).any() and (dash.live.frame()["gj_nm2"] == 1500.0).any()
    card = dash.status.card.value.replace("\u00a0", " ")  # the card names the case it belongs to (a field unbroken)
    assert "Fig. 10: rigid, axial, GJ 100" in card and "GJ 1500 → 100 N m²/rad at 2 s" in card
    marks = dash.live.markers.data  # a vertical marker with the new value in every live plot
    assert list(marks["text"]) == ["GJ 100"] and abs(marks["t_s"][0] - 2.0) < 0.01


def test_table1_shows_the_teeter_beside_the_flight_measurement(dash, wait):
    dash.controls.preset = "table1a"
    dash.controls.param.update(run_s=1.0, speed=50.0)
    dash.start_run()
    pump_until(dash, lambda: dash.last_history is not None, wait, 180, what="the Table 1 run")
    note = dash.status.note.value
    # in the paper's radians and the teeter plot's degrees (the note was in rad beside a plot in deg)
    assert "measured in flight 0.031 rad (1.78°); original AMRA 0.026 rad (1.49°)" in note
    beta = float(note.split("this model ")[1].split(" rad")[0])
    beta_deg = float(note.split("this model ")[1].split("(")[1].split("°")[0])
    assert 0.0 < beta < 0.2 and abs(beta_deg - math.degrees(beta)) < 0.06


def test_analyses_fill_the_mode_table_locus_and_fan(dash, wait):
    dash.refresh_analyses()
    pump_until(dash, lambda: dash.modes.points and len(dash.modes.frame) and dash.fan.pipe.data, wait, 180,
               what="modes, locus and fan plot")
    f = dash.modes.frame
    assert {"frequency [Hz]", "damping ratio [-]", "real part [1/s]"} <= set(f.columns)
    assert "aero lag" not in set(f["mode"]) and (f["stable"] == "yes").all()
    gjs = [p.gj_nm2 for p in dash.modes.points]
    assert max(gjs) == pytest.approx(3000.0) and min(gjs) == pytest.approx(50.0)
    assert not all(p.trimmed for p in dash.modes.points)  # the fold at low GJ (paper-boundary blade)
    assert "no trim (fold)" in dash.modes.locus_info.object
    assert list(dash.modes.frame.columns)[:2] == ["mode", "frequency [Hz]"]  # the table's header, as exported
    text = dash.modes_csv().getvalue()
    assert text.startswith("# AMRA ") and "# gj_nm2: 1500" in text and "\nmode,frequency [Hz]" in text
    # what the table is of: its trim and method (the page says them above the table; the file did not)
    assert "# trim_omega_rad_s: 33.89" in text and "# method: eigenvalues" in text and "# stable: True" in text
    assert dash.exports.buttons["modes"].filename == "amra-paper-boundary-rigid-gj1500-cg40-modes.csv"
    # the file's numbers at the export's 8 significant digits, not the table's rounding (a frequency
    # of 0.003 Hz was written as shown)
    import io

    import pandas as pd
    written = pd.read_csv(io.StringIO(text), comment="#")
    np.testing.assert_allclose(written["frequency [Hz]"], dash.modes.full_frame["frequency [Hz]"], rtol=1e-7)
    np.testing.assert_allclose(written["frequency [Hz]"], f["frequency [Hz]"], atol=5e-4)
    assert (written["real part [1/s]"] != written["real part [1/s]"].round(4)).any()
    fan = dash.fan.pipe.data
    assert len(fan["modes"]) >= 5
    teeter = dict(fan["modes"])["teeter"]  # the rigid tilt of a teetering rotor is exactly 1/rev
    np.testing.assert_allclose(teeter, fan["omega"] / (2 * np.pi), atol=1e-6)
    # before any run the fan's marker stands at the case's trim (it sat at 0 rad/s until a run)
    assert dash.last_history is None and dash.fan.omega.omega == pytest.approx(33.89, abs=0.01)


def test_map_cells_arrive_and_picking_one_loads_it(dash, wait):
    fig = dash.map.figure()
    from app.views.map import CLASS_COLOURS
    legends = [[item.label["value"] for item in lg.items] for lg in fig.right]
    assert legends[0] == list(CLASS_COLOURS)  # the same order whatever class a map meets first
    assert "elastic axis (EA)" in legends[1] and legends[1][:4] == ["strong flutter (this map)",
                                                                     "weak window (does not set GJ)",
                                                                     "rigid: fold (no autorotation below)",
                                                                     "rigid: strong flutter"]
    dash.refresh_analyses()
    assert 0.40 in dash.map.job.spec.cg_values  # the paper's CG is always a column
    assert dash.map.ea_source.data["x"] == [32.0]  # the EA drawn where it is
    pump_until(dash, lambda: dash.map.job.state == "done" and dash.map.cells, wait, 180, what="the map")
    dash.map.poll()
    assert dash.map.progress.value == 100 and "complete" in dash.map.status.value
    # the legend lists what the map draws: no fem-coupled lines on a rigid map, no "failed" without a
    # failed cell (such entries stood there without a swatch)
    shown = [item.label["value"] for lg in fig.right for item in lg.items if item.visible]
    assert "rigid: fold (no autorotation below)" in shown and "current case" in shown and "stable" in shown
    assert not [lb for lb in shown if lb.startswith(("fem-torsion", "fem-coupled"))], shown
    assert ("failed" in shown) == any(c.verdict == "failed" for c in dash.map.cells)
    assert "sensitivity band (estimates ±10 %)" not in shown
    cell = dash.map.cells[3]
    dash.load_cell(cell)  # values rounded to the grid's resolution
    assert dash.controls.cg_pct == pytest.approx(100 * cell.cg) and dash.controls.gj_nm2 == float(f"{cell.gj_nm2:.3g}")
    # the plot holds every cell once, coloured by its class
    from amra_core.boundary import cell_class
    data = dash.map.cells_source.data
    assert len(data["cg_pct"]) == len(dash.map.cells)
    assert list(data["colour"]) == [CLASS_COLOURS[cell_class(c)] for c in dash.map.cells]
    # a tap on the plot loads the nearest cell
    from types import SimpleNamespace
    other = dash.map.cells[-1]
    dash.map._tapped(SimpleNamespace(x=100 * other.cg + 0.1, y=other.gj_nm2 * 1.001))
    assert dash.controls.cg_pct == pytest.approx(100 * other.cg) and dash.controls.gj_nm2 == float(f"{other.gj_nm2:.3g}")
    lines = dash.map.csv().getvalue().splitlines()
    meta = [ln for ln in lines if ln.startswith("# ")]
    assert "# complete: yes" in meta and "# ea_pct_chord: 32" in meta
    # the whole map's case: which rotor and GJ grid (the file named neither)
    assert "# rotor: paper-boundary" in meta and "# gj_range_nm2: 30 to 3000" in meta and "# method: eigen" in meta
    assert lines[len(meta)].startswith("cg_pct_chord,gj_nm2,verdict")  # CG in % as on the page
    assert len(lines) == len(meta) + len(dash.map.cells) + 1
    assert lines[-1].split(",")[0] == f"{100 * max(c.cg for c in dash.map.cells):.8g}"
    # the lines the page draws, per column: fold, strong flutter and critical GJ (the file had cells only)
    cols = dash.map.job.columns()
    assert cols and sum(ln.startswith("# column cg_pct_chord ") for ln in meta) == len(cols)
    for col in cols:
        line = next(ln for ln in meta if ln.startswith(f"# column cg_pct_chord {100 * col['cg']:g}: "))
        if col.get("critical_gj") not in (None, math.inf):
            assert f"critical_gj_nm2 {col['critical_gj']:.8g}" in line, line
        if col.get("fold_gj") is not None:
            assert f"fold_gj_nm2 {col['fold_gj']:.8g}" in line, line
    dash.map.job.state = "running"  # a half-finished map says so
    n_cells = len(dash.map.cells)
    dash.map.cells = []  # the page's copy lags the job's: a file said "0 cells so far" above column lines
    text = dash.map.csv().getvalue().splitlines()
    assert f"# complete: NO: {n_cells} cells so far, the map was still filling" in text
    assert len(text) == len(meta) + n_cells + 1


def test_a_cell_loaded_after_a_preset_runs_from_its_own_trim(dash):
    """After Fig. 10 a stable cell at GJ 1720 ran as "GJ 1500 → 1720 N m²/rad at 2 s" (the preset's
    softening stayed on): not the case the map classified."""
    from types import SimpleNamespace
    dash.controls.preset = "fig10"
    assert dash.controls.soften_at_s == 2.0
    dash.load_cell(SimpleNamespace(cg=0.4625, gj_nm2=1715.3, verdict="stable"))
    assert dash.controls.soften_at_s == 0.0 and dash.controls.gj_nm2 == 1720.0
    assert dash.controls.scenario(None).changes == ()
    assert "from its own trim ('Soften at 2 s' set to 0)" in dash.messages[-1][1]
    dash.load_cell(SimpleNamespace(cg=0.40, gj_nm2=800.0, verdict="stable"))  # nothing to say without one
    assert "Soften at" not in dash.messages[-1][1]


def test_a_case_flown_at_an_airspeed_is_not_starred_on_a_map_of_another_flight(dash):
    """Table 1 A flies at 14 m/s with the rotor speed held: its star sat on the axial map (μ 0)."""
    dash.controls.preset = "table1a"
    dash.refresh_analyses()
    assert dash.map.marker_source.data["cg_pct"] == []
    dash.map.poll()
    status = dash.map.status.value
    assert "Not this case's flight:</b> this case is not on the map: it flies at 14 m/s and its rotor speed is held at 38 rad/s, while the map is at μ 0" in status
    dash.controls.preset = "fig10"  # a map's own flight: the star and no note
    dash.refresh_analyses()
    dash.map.poll()
    assert dash.map.marker_source.data["cg_pct"] == [40.0] and "Not this case's flight" not in dash.map.status.value


def test_bad_input_becomes_a_message_and_the_session_keeps_working(dash, wait):
    assert not dash.upload(b"this is [not toml", "broken.toml")
    assert dash.alert.visible and "broken.toml" in dash.alert.object and "not valid TOML" in dash.alert.object
    dash.controls.omega_hold_rad_s = 0.5  # in the widget's bounds, refused by the core
    assert not dash.start_run()
    assert "omega_hold_rad_s" in dash.alert.object
    dash.controls.omega_hold_rad_s = 0.0
    dash.controls.param.update(run_s=0.5, speed=20.0)
    assert dash.start_run()
    pump_until(dash, lambda: dash.last_history is not None, wait, what="a good run after the errors")


def test_a_run_says_it_uses_the_value_kept_when_a_box_still_shows_a_refused_one(dash):
    """A teacher typed GJ 50000 (refused: out of range), scrolled on and pressed Run: the run used
    the kept GJ with nothing saying so where she looked."""
    sidebar = dash.sidebar()
    box = next(o for o in sidebar.objects if isinstance(o, pn.Column) and o.objects
               and "amra-gj" in (o.objects[0].css_classes or []))
    box.objects[0].value = "50000"
    assert dash.controls.gj_nm2 == 1500.0 and "gj_nm2" in dash.refused
    dash.controls.param.update(run_s=0.5, speed=20.0)
    assert dash.start_run()
    level, text = dash.messages[-1]
    assert level == "warning" and text.startswith("this run uses the values kept, not the ones refused: ")
    assert "GJ [N m²/rad] = 50000 is out of range: allowed 10 to 10000" in text
    box.objects[0].value = "1500"  # a good value: nothing refused, the next run says nothing of it
    assert dash.refused == {}
    dash.controls.param.trigger("stop")
    assert dash.start_run() and not any("values kept" in t for _, t in dash.messages)


def test_uploaded_rotor_is_used(dash):
    data = (Path(__file__).resolve().parents[2] / "assets" / "rotors" / "mccutcheon.toml").read_bytes()
    assert dash.upload(data, "mine.toml")
    assert dash.controls.rotor == "uploaded file" and dash.controls.case(dash.uploaded).rotor.name == "mccutcheon"
    assert dash.map_spec().rotor.name == "mccutcheon"


def test_a_failed_upload_says_which_rotor_stays_in_use(dash):
    """After a good file, a broken one left the select on "uploaded file" with nothing saying that the
    earlier file was still the rotor."""
    good = (Path(__file__).resolve().parents[2] / "assets" / "rotors" / "mccutcheon.toml").read_bytes()
    assert dash.upload(good, "good.toml")
    assert not dash.upload(b"radius_m = [", "broken.toml")
    assert dash.messages[-1][0] == "error" and "'broken.toml'" in dash.messages[-1][1]
    assert dash.messages[-1][1].endswith("; the rotor stays the earlier file 'good.toml'")
    assert dash.controls.rotor == "uploaded file" and dash.uploaded.name == "mccutcheon"
    dash.controls.rotor = "paper-boundary"
    assert not dash.upload(b"\x00\x01", "binary.toml")
    assert dash.messages[-1][1].endswith("; the rotor stays paper-boundary")


def test_uploaded_file_without_a_file_keeps_the_rotor_and_says_why(dash):
    """Chosen in the select, or applied by a shared link's rotor=uploaded+file (Location.sync sets it
    after the link's own check refused it), 'uploaded file' without a file left every run failing."""
    dash.controls.rotor = "mccutcheon"
    dash.controls.rotor = "uploaded file"
    assert dash.controls.rotor == "mccutcheon"
    assert "no rotor file uploaded in this session: the rotor stays mccutcheon" in dash.messages[-1][1]
    assert dash.start_run()
    dash.session.stop()


def test_an_empty_file_is_named_as_empty(dash):
    """The browser sends an empty file as no value: only its name changes, and that is read too."""
    import panel as pn
    upload = next(o for o in dash.sidebar().select(pn.widgets.FileInput))
    upload.param.update(filename="empty.toml")
    assert dash.messages[-1] == ("error", "rotor file 'empty.toml' is empty; the rotor stays paper-boundary")
    assert dash.uploaded is None


def test_a_rejected_file_is_cleared_from_the_input_and_its_clearing_is_no_new_choice(dash, monkeypatch):
    """A rejected file stood in the input as if in use (the message said another rotor stayed)."""
    import panel as pn
    upload = next(o for o in dash.sidebar().select(pn.widgets.FileInput))
    cleared = []
    monkeypatch.setattr(upload, "clear", lambda: cleared.append(True))
    upload.param.update(value=b"radius_m = [", filename="broken.toml")
    assert cleared == [True]
    n = len(dash.messages)
    upload.param.update(value=None, filename=None)  # the browser's echo of the clearing
    assert len(dash.messages) == n and dash.uploaded is None
    good = (Path(__file__).resolve().parents[2] / "assets" / "rotors" / "mccutcheon.toml").read_bytes()
    upload.param.update(value=good, filename="good.toml")
    assert cleared == [True] and dash.uploaded is not None


def test_the_page_builds_with_lazy_tabs_and_the_test_hooks(dash):
    """No busy indicator (Panel's busy flag is per process), the views' tabs render lazily, and the
    page carries the hooks the browser tests use."""
    import holoviews as hv
    import panel as pn
    from bokeh.document import Document
    hv.extension("bokeh", logo=False)
    page = dash.__panel__()
    assert page.busy_indicator is None
    doc = page.server_doc(Document())
    assert doc.roots
    classes = {c for m in doc.models for c in (getattr(m, "css_classes", None) or [])}
    assert {"amra-run", "amra-stop", "amra-reset", "amra-gj", "amra-gj-slider", "amra-upload"} <= classes


def test_opening_a_holoviews_view_leaves_the_pages_look(dash):
    """Rendering the first HoloViews view (the Modes tab) set HoloViews' theme as the document's, and
    the live plots' titles turned black 12 pt mid-session."""
    import holoviews as hv
    import panel as pn
    from bokeh.document import Document
    from app.main import configure_holoviews
    configure_holoviews()
    doc = dash.__panel__().server_doc(Document())
    before = doc.theme._json
    pn.pane.HoloViews(hv.Curve([1, 2, 3])).get_root(doc)
    assert doc.theme._json == before == {"attrs": {}}


def test_no_view_takes_the_mouse_wheel_until_its_zoom_is_chosen(dash):
    """HoloViews activates wheel zoom by default: scrolling the page down over the fan plot zoomed
    it instead. Every view's plot leaves the wheel to the page (wheel zoom stays in the toolbar)."""
    import panel as pn
    from bokeh.document import Document
    from bokeh.models import Toolbar, WheelZoomTool
    from app.main import configure_holoviews
    configure_holoviews()
    views = [dash.fan, dash.modes, dash.disc, dash.ladder, dash.rotor_view]
    toolbars = []
    for view in views:
        root = pn.panel(view).get_root(Document())
        toolbars += [m for m in root.references() if isinstance(m, Toolbar)]
    toolbars += [f.toolbar for f in [*dash.live.figures(), dash.map.figure()]]
    assert len(toolbars) >= 8
    assert any(isinstance(t, WheelZoomTool) for tb in toolbars for t in tb.tools)
    assert all(not isinstance(tb.active_scroll, WheelZoomTool) for tb in toolbars), \
        [type(tb.active_scroll).__name__ for tb in toolbars]


def test_the_figures_every_page_builds_have_one_glyph_per_renderer(dash):
    """The live plots and the map are built for every page: each renderer carries its one glyph
    model, its unselected and muted looks derived in the browser (they use neither selection nor
    muting); the plotting helpers would add two glyph models per renderer (48 in the map alone)."""
    from bokeh.models import GlyphRenderer
    figures = [*dash.live.figures(), dash.map.figure()]
    renderers = [r for f in figures for r in f.renderers if isinstance(r, GlyphRenderer)]
    assert len(renderers) >= 30
    assert all(r.nonselection_glyph == "auto" and r.muted_glyph == "auto" for r in renderers)
    glyphs = [m for f in figures for m in f.references() if m.__class__.__module__.startswith("bokeh.models.glyphs")]
    assert len(glyphs) == len(renderers)


def test_the_gj_slider_and_input_are_two_views_of_one_parameter(dash):
    import math
    from app.inputs import gj_slider
    slider = gj_slider(dash.controls)
    dash.controls.gj_nm2 = 420.0
    assert slider.value == pytest.approx(math.log10(420.0)) and dash.controls.gj_nm2 == 420.0  # no echo
    with pn_edit(slider):
        slider.value_throttled = math.log10(2000.0)  # what a release in the browser sets
    assert dash.controls.gj_nm2 == pytest.approx(2000.0)


def pn_edit(widget):
    import param
    return param.edit_constant(widget)


def test_each_run_starts_with_a_clean_message_area(dash, wait):
    dash.notify("a message of the last run", "warning")
    assert dash.alert.visible
    dash.controls.param.update(run_s=0.5, speed=10.0)
    dash.start_run()
    assert dash.messages == [] and not dash.alert.visible
    pump_until(dash, lambda: dash.last_history is not None, wait, what="the run")


def test_map_columns_always_include_the_papers_cg():
    from app.app import map_columns
    for n in (2, 3, 7, 9, 16, 31):
        cgs = map_columns(n)
        assert 0.40 in cgs and cgs[0] == 0.20 and cgs[-1] == 0.50 and list(cgs) == sorted(set(cgs))


def test_the_map_time_estimate_follows_the_rate_of_computed_cells():
    from app.views.map import Eta
    eta, now = Eta(), [100.0]
    eta._clock = lambda: now[0]
    assert eta.update(0, 50, True) == ""  # the first look starts the clock
    now[0] += 10.0
    assert eta.update(2, 48, True) == ""  # too few cells for a rate
    assert eta.update(5, 45, True) == ", about 90 s left"  # 5 cells in 10 s: 45 cells in 90 s
    now[0] += 90.0
    assert eta.update(5, 45, True) == ", about 15 min left"  # 5 cells in 100 s: 900 s
    assert eta.update(50, 0, True) == "" and eta.update(5, 45, False) == ""


def test_map_boundaries_and_bands_from_the_columns():
    """Fold and strong-flutter lines per column, flutter intervals as bands, weak ones apart (issue 21)."""
    from app.views.map import boundary_lines, flutter_bands
    cols = [{"cg": 0.36, "fold_gj": 270.0, "flutter_gj": None, "intervals": [
                {"kind": "fold", "gj_lo_nm2": 30.0, "gj_hi_nm2": 270.0},
                {"kind": "flutter", "gj_lo_nm2": 270.0, "gj_hi_nm2": 281.0, "fold_approach": True,
                 "strength": "weak"}]},
            {"cg": 0.40, "fold_gj": 416.0, "flutter_gj": None, "intervals": [
                {"kind": "flutter", "gj_lo_nm2": 628.0, "gj_hi_nm2": 662.0, "strength": "weak",
                 "damping_ratio": -0.01, "peak_growth_rate_1_s": 0.97}]},
            {"cg": 0.44, "fold_gj": 550.0, "flutter_gj": 700.0, "intervals": [
                {"kind": "flutter", "gj_lo_nm2": 600.0, "gj_hi_nm2": 700.0, "strength": "strong",
                 "damping_ratio": -0.05, "peak_growth_rate_1_s": 4.0}]}]
    fold, flutter = boundary_lines(cols)
    assert fold == [(0.36, 270.0), (0.40, 416.0), (0.44, 550.0)] and flutter == [(0.44, 700.0)]
    bands = flutter_bands(cols, 4.0)
    assert [(b["strength"], b["bottom"], b["top"]) for b in bands] == [("weak", 628.0, 662.0), ("strong", 600.0, 700.0)]
    assert bands[0]["left"] == pytest.approx(40 - 1.4) and "damping ratio -0.010" in bands[0]["text"]


def test_an_uploaded_rotor_says_its_own_values_are_overridden(dash):
    data = (Path(__file__).resolve().parents[2] / "assets" / "rotors" / "mccutcheon.toml").read_bytes()
    assert dash.upload(data, "mine.toml")
    level, text = dash.messages[-1]
    assert level == "info" and "Its own GJ 1471 N m²/rad, EA 31.4 % and CG 33.0 % chord" in text
    assert "overridden by the controls' uniform GJ, EA and CG" in text


def test_a_hidden_tab_builds_its_figures_only_when_it_is_shown(dash):
    """Page build holds the controls; the plots come after the first paint, and a view's figures are
    built when its tab is first shown (issue 22: page build <= 0.3 s server time)."""
    import holoviews as hv
    from bokeh.document import Document
    hv.extension("bokeh", logo=False)
    page = dash.__panel__()
    doc = page.server_doc(Document())
    assert dash.rotor_view.drawing._figures is None  # (defer_load waits for a served page's load only)
    tabs = dash.views()
    tabs.get_root(doc)
    assert dash.rotor_view.drawing._figures is None  # the first tab (the map) is shown, not the rotor
    tabs.active = 2  # "Live rotor"
    side, tips = dash.rotor_view.drawing._figures
    assert side.title.text.startswith("Live rotor.") and tips.title.text.startswith("Tip sections")


def test_the_advanced_card_makes_its_inputs_when_first_opened(dash):
    """The collapsed card holds no models at page build; opened, its inputs show the controls' values
    and set them (issue 22: page build <= 0.3 s server time)."""
    card = next(o for o in dash.sidebar().objects if "amra-advanced" in (getattr(o, "css_classes", None) or []))
    assert card.collapsed and len(card) == 0
    dash.controls.airspeed_m_s = 12.0
    card.collapsed = False
    assert len(card) == 4
    airspeed = card[0][0]
    assert airspeed.value == "12"
    airspeed.value = "15"
    assert dash.controls.airspeed_m_s == 15.0
    columns = card[2][0]  # an Integer control gets an int
    columns.value = "12"
    assert dash.controls.map_columns == 12 and isinstance(dash.controls.map_columns, int)
    card.collapsed, card.collapsed = True, False  # closed and opened again: the same four inputs
    assert len(card) == 4


def test_a_status_line_update_sends_only_its_text(dash):
    """The run status, the verdict card and the map's status line change all through a run: each
    change sends its text alone. (An HTML pane in a template rewrites its stylesheets at its first
    update, and Bokeh then walks the whole document: docs/upstream/panel-template-pane-first-update-stylesheets.md.)"""
    import holoviews as hv
    from bokeh.document import Document
    from panel.io.state import set_curdoc
    from app.views.status import run_html
    hv.extension("bokeh", logo=False)
    doc = Document()
    with set_curdoc(doc):
        dash.__panel__().server_doc(doc)
        the_map = dash.map.__panel__()
        doc.add_root(the_map.get_root(doc))
    changed = []
    doc.on_change(lambda e: changed.append(getattr(e, "attr", type(e).__name__)))
    with set_curdoc(doc):
        dash.status.run.value = run_html("running, t = 1.00 s")
        dash.status.card.value = "<div class='amra-verdict' data-verdict='stable'>stable</div>"
        dash.map.status.value = "<b>Map</b>: computing"
    assert len(changed) >= 3 and set(changed) == {"text"}, changed  # (a widget shown twice sends twice)


def test_an_exported_map_reads_back_as_a_table_whatever_its_reasons_say():
    """A cell's reason has commas ("... (4.12 v_h), not autorotation"): unquoted, it split its row."""
    import io
    import pandas as pd
    from amra_core.stability import CellResult
    from app.views.map import map_csv
    cells = [CellResult(0.2, 41.0, "no-autorotation", False, "windmill-brake", None, None, 30.0,
                        "no normal autorotation; descent rate 23.1 m/s (4.12 v_h), not autorotation", "windmill-brake"),
             CellResult(0.4, 1500.0, "stable", True, "", -0.5, 12.0, 33.9, 'least damped: "torsion"', "normal")]
    df = pd.read_csv(io.StringIO(map_csv(cells).getvalue()), comment="#")
    assert len(df) == 2 and list(df["reason"]) == [cells[0].reason, cells[1].reason]
    assert list(df["cg_pct_chord"]) == [20.0, 40.0]


def test_an_edit_away_from_a_preset_shows_custom_in_the_selector_and_its_card(dash):
    """After GJ was typed over Fig. 10's, the selector still showed "Fig. 10" and its card its text
    (the URL said custom), and choosing Fig. 10 again did not bring its GJ back."""
    import panel as pn
    from app.controls import PRESETS
    sidebar = dash.sidebar()
    select = next(w for w in sidebar.select(pn.widgets.Select) if w.name == "Preset")
    card = sidebar.select(lambda o: getattr(o, "name", "") == "preset-explanation")[0]
    dash.controls.preset = "fig10"
    assert select.value == "fig10" and dash.controls.gj_nm2 == 100.0
    dash.controls.gj_nm2 = 300.0
    assert dash.controls.preset == "custom" and select.value == "custom"
    assert card.object == PRESETS["custom"].explanation
    select.value = "fig10"  # chosen again in the page
    assert dash.controls.gj_nm2 == 100.0 and card.object == PRESETS["fig10"].explanation
