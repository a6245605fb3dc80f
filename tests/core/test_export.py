"""Exports that stand alone (amra_core.export): names that say the case, header lines with the
parameters and version, numbers to 8 significant digits, nan/inf for non-finite values."""
from __future__ import annotations

import io

import numpy as np
import pytest

from amra_core import __version__
from amra_core.export import file_name, table_csv


def test_file_names_say_the_case():
    assert file_name("history", case="fig10", fidelity="rigid", gj_nm2=100.0, cg_pct=40.0) == \
        "amra-fig10-rigid-gj100-cg40-history.csv"
    assert file_name("map", fidelity="fem-coupled", mu=0.1) == "amra-map-fem-coupled-mu0.1.csv"
    assert file_name("modes", case="My rotor/../x", gj_nm2=487.58387005217355) == "amra-myrotor..x-gj487.6-modes.csv"


def test_table_csv_round_trips_with_its_header():
    rows = np.array([[0.0, 37.387451975177356, 1e-12], [0.0025, float("nan"), -3.0]])
    text = table_csv(("t_s", "omega_rad_s", "teeter_rad"), rows, {"fidelity": "rigid", "gj_nm2": 100.0})
    lines = text.splitlines()
    assert lines[:3] == [f"# AMRA {__version__}", "# fidelity: rigid", "# gj_nm2: 100"]
    assert lines[3] == "t_s,omega_rad_s,teeter_rad"
    assert lines[4] == "0,37.387452,1e-12" and lines[5] == "0.0025,nan,-3"
    back = np.genfromtxt(io.StringIO(text), delimiter=",", comments="#", skip_header=4)
    np.testing.assert_allclose(back[0], [0.0, 37.387452, 1e-12])
    assert np.isnan(back[1, 1])


def test_a_case_flown_at_an_advance_ratio_does_not_claim_0_m_s():
    """With mu given the airspeed follows the trim; the header said airspeed_m_s: 0."""
    from amra_core.export import case_meta
    from amra_core.flight import FlightCondition, SolverSettings
    from amra_core.rotor_io import load_preset
    from amra_core.simulation import Case
    rotor = load_preset("mccutcheon")
    at_mu = case_meta(Case(rotor, FlightCondition(mu=0.1), SolverSettings("rigid")))
    assert at_mu["mu"] == 0.1 and at_mu["airspeed_m_s"] == "set by mu at the trim's rotor speed"
    at_speed = case_meta(Case(rotor, FlightCondition(airspeed_m_s=14.0), SolverSettings("rigid")))
    assert at_speed["mu"] == 0.0 and at_speed["airspeed_m_s"] == 14.0


def test_a_run_at_an_advance_ratio_writes_the_airspeed_its_trim_set():
    """A forward-flight history's header said only "set by mu at the trim's rotor speed": no number."""
    import math
    from amra_core.export import run_meta
    from amra_core.flight import FlightCondition, SolverSettings
    from amra_core.layout import P_ALPHA_S
    from amra_core.model import Y_OMEGA
    from amra_core.rotor_io import load_preset
    from amra_core.simulation import Case, Simulation
    rotor = load_preset("mccutcheon")
    sim = Simulation(Case(rotor, FlightCondition(mu=0.1), SolverSettings("rigid"), t_end_s=0.1))
    meta = run_meta(sim)
    # mu is the advance ratio in the disc plane: V cos(alpha_s) = mu Omega R at the trim
    v_disc = meta["airspeed_m_s"] * math.cos(sim.model.arrays.p[P_ALPHA_S])
    assert v_disc == pytest.approx(0.1 * sim.y[Y_OMEGA] * rotor.radius_m, rel=1e-9)
    assert meta["airspeed_from"] == "mu at the trim's rotor speed"


def test_a_run_changed_live_writes_the_case_it_started_with_and_then_its_changes():
    """The dashboard names a history file after the case at Run (``...-gj500-...``); after a live
    change to GJ 300 its header said ``gj_nm2 (span mean): 300`` above rows that began at 500."""
    from amra_core.export import run_meta
    from amra_core.flight import FlightCondition, SolverSettings
    from amra_core.rotor_io import load_preset
    from amra_core.simulation import Case, Simulation
    rotor = load_preset("paper-boundary").with_overrides(gj_nm2=500.0)
    sim = Simulation(Case(rotor, FlightCondition(), SolverSettings("rigid"), t_end_s=0.2))
    sim.advance(span_s=0.05)
    sim.set_parameters(gj_nm2=300.0)
    sim.advance(span_s=0.05)
    meta = run_meta(sim)
    assert meta["gj_nm2 (span mean)"] == pytest.approx(500.0)
    assert meta["case_key"] == sim.start_case.key() != sim.case.key()
    assert meta["change 1"].startswith("the change to GJ 300 N m^2/rad at t = 0.05")
