"""Branch labels (issue 21 §4): "windmill-brake" only for a separate root or collapsed inflow; the
normal branch continued beyond 2 v_h with its rotor speed risen is "overspeed".

The measured case: rigid, EA 0.32, CG 0.24, GJ 150 was labelled windmill-brake with Omega 54.7
rad/s and V_d = 2.02 v_h, although the branch rises continuously (52.7 -> 61.5 rad/s as GJ falls)
with inflow 4-7 m/s."""
from __future__ import annotations

import pytest

from amra_core.column import walk_column
from amra_core.equilibrium import INFLOW_COLLAPSED_RATIO, _hover_induced, windmill_brake_state
from amra_core.flight import FlightCondition, SolverSettings
from amra_core.model import compile_model
from amra_core.rotor_io import load_preset
from amra_core.stability import assess_cell
from amra_core.trim import trim


def _rotor(cg, gj=None):
    r = load_preset("paper-boundary").with_overrides(x_ea=0.32, x_cg=cg)
    return r if gj is None else r.with_overrides(gj_nm2=gj)


def test_rigid_cg024_gj150_is_the_normal_branch_overspeeding():
    m = compile_model(_rotor(0.24, 150.0), FlightCondition(), SolverSettings(fidelity="rigid"))
    tr = trim(m)
    vh = _hover_induced(m)
    assert tr.ok and tr.continued
    assert tr.descent_ratio > 2.0  # beyond the turbulent-wake region ...
    assert tr.omega_rad_s > tr.omega_branch_start_rad_s  # ... reached with the rotor speed rising ...
    assert tr.inflow_m_s > INFLOW_COLLAPSED_RATIO * vh  # ... and the inflow not collapsed
    assert tr.branch == "overspeed"
    assert tr.omega_rad_s == pytest.approx(54.7, abs=0.5)
    assert tr.to_dict()["branch"] == "overspeed"
    cell = assess_cell(_rotor(0.24, 150.0), FlightCondition(), SolverSettings(fidelity="rigid"))
    assert cell.branch != "windmill-brake" and cell.verdict in ("overspeed", "flutter", "divergence")


def test_cg024_column_has_no_windmill_brake_but_an_overspeed_stretch():
    w = walk_column(_rotor(0.24), FlightCondition(), SolverSettings(fidelity="rigid"), 0.24, 30.0, 3000.0)
    kinds = [iv["kind"] for iv in w.intervals]
    assert "windmill-brake" not in kinds and "overspeed" in kinds, w.intervals
    over = [p for p in w.points if p.branch == "overspeed"]
    omegas = [p.trim.omega_rad_s for p in sorted(over, key=lambda p: -p.gj_nm2)]
    assert omegas == sorted(omegas)  # the rotor speeds up as GJ falls: one continuous branch


def test_a_separate_root_deep_in_the_descent_is_windmill_brake():
    """Below the fold at CG 0.40 (GJ 300) the cold-started root descends at 5-7 v_h with an inflow
    of about 0.2 v_h: the windmill-brake state."""
    m = compile_model(_rotor(0.40, 300.0), FlightCondition(), SolverSettings(fidelity="rigid"))
    wb = windmill_brake_state(m)
    assert wb is not None and not wb.continued
    assert wb.descent_ratio > 4.0 and wb.inflow_m_s < INFLOW_COLLAPSED_RATIO * _hover_induced(m)
    assert wb.branch == "windmill-brake"
    assert not trim(m).ok  # no normal branch there: the fold is above
