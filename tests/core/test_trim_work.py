"""The forward trim's work (issue 24 §3): the advance ratio held inside the Newton iteration, a
cycling iteration stopped early, and no stiff start stiffer than the blade needs. Each is checked
for its answer (the trim is the same equilibrium) and for its work in revolutions marched, which
is deterministic (never wall time)."""
from __future__ import annotations

import math

import pytest

from amra_core import equilibrium, trim as trim_module
from amra_core.flight import FlightCondition, SolverSettings
from amra_core.model import compile_model
from amra_core.trim import trim


@pytest.fixture
def revolutions(monkeypatch):
    """Count the revolutions the forward trim marches."""
    count = [0]
    march = equilibrium._march_revs

    def counted(model, y, n_revs, dt):
        count[0] += n_revs
        return march(model, y, n_revs, dt)
    monkeypatch.setattr(equilibrium, "_march_revs", counted)
    return count


def test_the_advance_ratio_is_exact_and_the_trim_an_equilibrium(mccutcheon, revolutions):
    """mu is held inside every evaluation (V = mu Omega R / cos tilt), so the trim has exactly the
    requested advance ratio (the fixed point on the airspeed stopped at |d mu| < 1e-4 after two to
    three whole trims), and its residuals are below the acceptance level."""
    model = compile_model(mccutcheon, FlightCondition(mu=0.3), SolverSettings("rigid"))
    res = trim(model)
    assert res.status == "trimmed"
    assert res.mu == pytest.approx(0.3, abs=1e-12)
    assert res.disk_tilt_rad < 0.0  # forward-tilted shaft, as every McCutcheon trim above mu 0.2
    # the same trim from a fresh start at its solution stays there: an equilibrium of the residuals
    again = equilibrium.trim_forward(res.model, None, None, res, mu=0.3)
    assert again.status == "trimmed"
    assert again.omega_rad_s == pytest.approx(res.omega_rad_s, rel=2e-3)
    assert again.descent_rate_m_s == pytest.approx(res.descent_rate_m_s, abs=0.05)
    assert again.disk_tilt_rad == pytest.approx(res.disk_tilt_rad, abs=math.radians(0.1))
    print(f"revolutions marched: {revolutions[0]}")


def test_a_branch_that_ends_costs_few_revolutions(mccutcheon, revolutions):
    """At mu 0.5 the McCutcheon trim branch, followed down in GJ from the stiff blade, folds at a
    mean GJ of about 2,350 N m^2/rad (2,327 before this change: the continuation resolves a fold to
    2 % in GJ), above the blade's 1,478. Each failed step near the fold used to run 30 cycling
    Newton iterations (100+ revolutions): 8,732 revolutions in all before, 3,428 after (2026-12-03)."""
    model = compile_model(mccutcheon, FlightCondition(mu=0.5), SolverSettings("rigid"))
    res = trim(model)
    assert res.status == "no-autorotation"
    assert res.branch_end["runaway"] == "collapse"
    assert res.branch_end["gj_mean_nm2"] == pytest.approx(2327.0, rel=0.04)
    print(f"revolutions marched: {revolutions[0]}")
    assert revolutions[0] < 4500


def test_a_stiff_blade_starts_at_its_own_gj_with_the_same_answer(mccutcheon, monkeypatch):
    """GJ 1e6 is far stiffer than any map's blade: the trim starts there, not at 30 x 1e6 (whose
    torsion mode forced a 50 us step), and finds the same trim as a start at 30x."""
    model = compile_model(mccutcheon.with_overrides(gj_nm2=1e6), FlightCondition(mu=0.1), SolverSettings("rigid"))
    compiled = []
    scale = trim_module._with_gj_scale
    monkeypatch.setattr(trim_module, "_with_gj_scale", lambda m, f: compiled.append(f) or scale(m, f))
    res = trim(model)
    assert res.status == "trimmed" and not compiled  # started at the blade's own GJ
    monkeypatch.setattr(trim_module, "STIFF_START_GJ_NM2", math.inf)
    ref = trim(model)
    assert compiled and compiled[0] == pytest.approx(30.0)
    assert ref.status == "trimmed"
    assert res.omega_rad_s == pytest.approx(ref.omega_rad_s, rel=2e-3)
    assert res.descent_rate_m_s == pytest.approx(ref.descent_rate_m_s, abs=0.05)
    assert res.disk_tilt_rad == pytest.approx(ref.disk_tilt_rad, abs=math.radians(0.1))


def test_a_map_blade_keeps_the_30x_stiff_start(mccutcheon, monkeypatch):
    """Up to GJ 3000 (the top of the boundary map's range) the start is 30x stiffer, as before."""
    compiled = []
    scale = trim_module._with_gj_scale
    monkeypatch.setattr(trim_module, "_with_gj_scale", lambda m, f: compiled.append(f) or scale(m, f))
    res = trim(compile_model(mccutcheon.with_overrides(gj_nm2=3000.0), FlightCondition(), SolverSettings("rigid")))
    assert res.status == "trimmed"
    assert compiled[0] == pytest.approx(30.0)
