"""Controls -> solver Case; presets; bounds; server settings from the environment."""
from __future__ import annotations

import math

import pytest

from amra_core.flight import SettingsError
from amra_core.rotor_io import load_preset
from app.controls import UPLOADED, Controls
from app.controls import PRESETS
from app.server.settings import ServerSettings
from app.server.settings import SettingsError as EnvError


def test_defaults_give_the_paper_boundary_case():
    c = Controls()
    case = c.case()
    st = case.rotor.stations
    assert case.rotor.name == "paper-boundary"
    assert set(st.gj_nm2) == {1500.0} and set(st.x_ea) == {0.32} and set(st.x_cg) == {0.40}
    assert case.flight.is_axial
    assert case.settings.fidelity == "rigid" and case.settings.aero == "theodorsen"
    assert case.t_end_s == 10.0


def test_values_map_to_solver_units():
    c = Controls(gj_nm2=250.0, ea_pct=30.0, cg_pct=45.5, mu=0.12, fidelity="fem-coupled", aero="quasi-steady",
                 inflow="three-state", run_s=3.0)
    case = c.case()
    st = case.rotor.stations
    assert set(st.gj_nm2) == {250.0}
    assert st.x_ea[0] == pytest.approx(0.30) and st.x_cg[-1] == pytest.approx(0.455)
    assert case.flight.mu == pytest.approx(0.12) and not case.flight.is_axial
    assert (case.settings.fidelity, case.settings.aero, case.settings.inflow) == ("fem-coupled", "quasi-steady",
                                                                                  "three-state")
    assert c.live_values() == {"gj_nm2": 250.0, "x_ea": pytest.approx(0.30), "x_cg": pytest.approx(0.455)}


def test_airspeed_and_held_rotor_speed_table1():
    c = Controls(preset="table1b")
    f = c.flight()
    assert f.airspeed_m_s == 27.0 and f.omega_hold_rad_s == 41.0 and f.mu is None
    assert c.case().rotor.name == "mccutcheon"


@pytest.mark.parametrize("name, value", [("gj_nm2", 5.0), ("gj_nm2", 2e4), ("cg_pct", 90.0), ("mu", 0.6),
                                         ("fidelity", "beam"), ("run_s", 0.1)])
def test_out_of_range_values_are_refused_with_the_name(name, value):
    c = Controls()
    with pytest.raises(ValueError, match=name):
        setattr(c, name, value)
    assert getattr(c, name) == Controls.param[name].default


def test_core_validation_names_values_bounds_cannot_express():
    c = Controls(omega_hold_rad_s=0.5)  # 0 means free; (0, 1) rad/s is refused by the core
    with pytest.raises(SettingsError, match="omega_hold_rad_s"):
        c.case()


def test_run_length_capped_by_the_server():
    c = Controls(max_run_s=20.0)
    assert c.param.run_s.bounds == (0.5, 20.0)
    with pytest.raises(ValueError):
        c.run_s = 30.0
    assert Controls(max_run_s=5.0).run_s == 5.0
    assert Controls().param.run_s.bounds[1] == 120.0  # per instance: the class is untouched


def test_uploaded_rotor_needs_a_file():
    c = Controls(rotor=UPLOADED)
    with pytest.raises(ValueError, match="no rotor file"):
        c.case()
    r = load_preset("mccutcheon")
    assert c.case(uploaded=r).rotor.name == "mccutcheon"


@pytest.mark.parametrize("key", [k for k in PRESETS if k != "custom"])
def test_every_preset_gives_a_valid_case_and_explains_itself(key):
    c = Controls(preset=key)
    c.case()
    scenario = c.scenario()
    p = PRESETS[key]
    assert len(p.explanation) > 40
    if key.startswith("fig"):  # the paper's story: what the paper reports, what this model gives, and why
        assert "**The paper:**" in p.explanation and "**This model:**" in p.explanation
        (change,) = scenario.changes
        assert change.t_s == 2.0 and change.gj_nm2 == c.gj_nm2
        assert scenario.case.rotor.stations.gj_nm2[0] == 1500.0
    else:
        assert scenario.changes == ()
    for name, v in p.as_dict().items():
        assert getattr(c, name) == v


def test_paper_presets_match_the_system_tests():
    # tests/core/test_system.py PAPER_CASES: (fidelity, GJ, flight)
    want = {"fig10": ("rigid", 100.0, 0.0), "fig11": ("fem-coupled", 400.0, 0.0), "fig12": ("rigid", 300.0, 0.1),
            "fig13": ("fem-coupled", 600.0, 0.1)}
    for key, (fid, gj, mu) in want.items():
        c = Controls(preset=key)
        assert (c.fidelity, c.gj_nm2, c.mu, c.ea_pct, c.cg_pct, c.rotor) == (fid, gj, mu, 32.0, 40.0, "paper-boundary")


def test_the_preset_selector_shows_each_preset_by_its_label():
    """The select lists "Fig. 10: rigid, axial, GJ 100", not "fig10"; the value stays the key (links, tests)."""
    import panel as pn
    c = Controls()
    w = pn.widgets.Select.from_param(c.param.preset)
    assert w.labels == [p.label for p in PRESETS.values()]
    w.value = "fig10"
    assert c.preset == "fig10" and c.gj_nm2 == 100.0


@pytest.mark.parametrize("key", ["table1a", "table1b"])
def test_a_table1_preset_runs_long_enough_for_a_verdict(key):
    """Its card says the verdict tells whether the kick dies out: the run gives one (5 s was undetermined)."""
    from amra_core.simulation import Simulation
    sim = Simulation(Controls(preset=key).scenario().case).run()
    v = sim.verdict()
    assert v.verdict == "stable" and v.outcome == "decays", v.explanation


def test_moving_a_control_leaves_the_preset():
    c = Controls(preset="fig10")
    c.gj_nm2 = 120.0
    assert c.preset == "custom" and c.gj_nm2 == 120.0


def test_server_settings_from_env(tmp_path):
    s = ServerSettings.from_env({"AMRA_STORE": str(tmp_path / "s.sqlite"), "AMRA_MAP_WORKERS": "2",
                                 "AMRA_DASK_SCHEDULER": "tcp://h:8786", "AMRA_MAX_RUN_S": "30"})
    assert (s.store_path, s.map_workers, s.dask_scheduler, s.max_run_s) == (tmp_path / "s.sqlite", 2, "tcp://h:8786", 30.0)
    d = ServerSettings.from_env({})
    assert d.store_path.name == "cells.sqlite" and ".cache" in str(d.store_path) and d.map_workers == 1
    assert d.dask_scheduler is None and d.max_run_s == 120.0
    for env, name in (({"AMRA_MAP_WORKERS": "0"}, "AMRA_MAP_WORKERS"), ({"AMRA_MAP_WORKERS": "x"}, "AMRA_MAP_WORKERS"),
                      ({"AMRA_MAX_RUN_S": "1e9"}, "AMRA_MAX_RUN_S"), ({"AMRA_MAX_RUN_S": "nan"}, "AMRA_MAX_RUN_S")):
        with pytest.raises(EnvError, match=name):
            ServerSettings.from_env(env)
    assert math.isfinite(d.max_run_s)
