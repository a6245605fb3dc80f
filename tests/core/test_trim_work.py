"""The forward trim's work (issue 24 §3): the advance ratio held inside the Newton iteration, a
cycling iteration stopped early, and no stiff start stiffer than the blade needs. Each is checked
for its answer (the trim is the same equilibrium) and for its work in revolutions marched, which
is deterministic (never wall time)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from amra_core import equilibrium, shooting, trim as trim_module
from amra_core.flight import FlightCondition, SolverSettings
from amra_core.model import compile_model
from amra_core.trim import trim


@pytest.fixture
def revolutions(monkeypatch):
    """Count the revolutions the forward trim marches (shooting's included)."""
    count = [0]
    march, one_rev = equilibrium._march_revs, shooting.one_rev

    def counted(model, y, n_revs, dt):
        count[0] += n_revs
        return march(model, y, n_revs, dt)

    def counted_one(model, y, dt):
        count[0] += 1
        return one_rev(model, y, dt)
    monkeypatch.setattr(equilibrium, "_march_revs", counted)
    monkeypatch.setattr(shooting, "one_rev", counted_one)
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


def test_the_mu_0_5_branch_goes_on_through_its_bend(mccutcheon, revolutions):
    """At mu 0.5 the McCutcheon branch, followed down in GJ, bends near GJ 2,350 N m^2/rad (the
    descent rate turns from falling to rising, the rotor speed from falling to rising and back).
    Started from the last trim, the undamped Newton iteration failed there and the branch was
    reported as folding at 2,327-2,373; with the controls predicted along the branch, a damped
    Newton step and periodic orbits shot for, it goes on. Reference: the same model followed in
    0.5 % steps (scripts-free: continue_to with on_branch, 2026-12-04) passes smoothly and trims
    GJ 1,477.7 at 40.2252 rad/s, descent 7.937 m/s, and GJ 1,600.7 at 41.300 rad/s."""
    model = compile_model(mccutcheon.with_overrides(gj_nm2=1478.0), FlightCondition(mu=0.5), SolverSettings("rigid"))
    res = trim(model)
    assert res.status == "trimmed"
    assert res.omega_rad_s == pytest.approx(40.228, rel=2e-3)
    assert res.descent_rate_m_s == pytest.approx(7.937, abs=0.05)
    print(f"revolutions marched: {revolutions[0]}")
    assert revolutions[0] < 3000  # 3,428 revolutions to a false fold before (2026-12-03)


def test_a_branch_that_ends_ends_where_the_small_step_branch_does(mccutcheon, revolutions):
    """At mu 0.1 the rigid McCutcheon branch does fold: followed in 0.5 % steps it trims GJ 296.9
    (twist at its maximum, descent rate rising fast) and not 295.4; the map's column walk of the
    same rotor at uniform EA 0.314 and CG 0.33 (its means) brackets the fold at 295-298. The trim
    from GJ 200 ends there too (it ended at 579 before 2026-12-04: the undamped Newton iteration
    failed on a smooth part of the branch, and the run contradicted the map in between)."""
    model = compile_model(mccutcheon.with_overrides(gj_nm2=200.0), FlightCondition(mu=0.1), SolverSettings("rigid"))
    res = trim(model)
    assert res.status == "no-autorotation"
    assert res.branch_end["runaway"] == "collapse"
    assert 283.0 <= res.branch_end["gj_mean_nm2"] <= 301.0
    print(f"revolutions marched: {revolutions[0]}")
    assert revolutions[0] < 2500


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


@pytest.mark.parametrize("fidelity", ["rigid", "fem-coupled"])
@pytest.mark.parametrize("free_omega", [True, False])
def test_the_fallback_residual_kernel_is_the_right_hand_side(mccutcheon, fidelity, free_omega):
    """scipy's hybr (the axial trim's fallback) calls a jitted residual: the rates of the full
    right-hand side at the state with the unknowns set, in the Newton's order, bit for bit."""
    import numpy as np
    from amra_core import kernel_guard, trim_kernels
    m = compile_model(mccutcheon, FlightCondition(), SolverSettings(fidelity)).with_controls(quasi_static=True)
    iu, ir = equilibrium._axial_indices(m, free_omega)
    rng = np.random.default_rng(7)
    y0 = np.zeros(m.n_y); y0[1] = 38.0; y0[2] = -10.0; y0[3] = 8.0
    work, dy_k, out = np.empty(m.n_y), np.empty(m.n_y), np.empty(len(iu))
    for _ in range(5):
        z = y0[iu] + 0.01 * rng.standard_normal(len(iu))
        trim_kernels.residual_at(z, y0, m.arrays, iu, ir, work, dy_k, np.zeros(8), out)
        y = y0.copy(); y[iu] = z
        dy = np.zeros(m.n_y)
        kernel_guard.evaluate(y, m.arrays, dy, np.zeros(8))
        np.testing.assert_array_equal(out, dy[ir])



def test_a_forward_branch_end_on_an_unstable_orbit_is_not_called_a_fold(mccutcheon):
    """The branch of the test above ends at GJ 299, where its trim is already unstable (largest
    Floquet multiplier 2.24 per revolution, a complex pair: flutter). The trim no longer calls that a
    fold of the torque balance, because the branch goes on below it. Settled shooting
    (``PeriodicShooting.settle``) from the last trim trims GJ 290 at 27.79 rad/s, also unstable
    (multiplier 1.76); the plain Newton iteration of the continuation does not converge there."""
    model = compile_model(mccutcheon.with_overrides(gj_nm2=200.0), FlightCondition(mu=0.1), SolverSettings("rigid"))
    res = trim(model)
    assert res.status == "no-autorotation"
    assert res.branch_end["last_trim_max_multiplier"] > 1.5 and res.branch_end["last_trim_unstable"] is True
    assert "not shown to be a fold" in res.reason and "torque balance loses" not in res.reason
    below = compile_model(mccutcheon.with_overrides(gj_nm2=290.0), FlightCondition(mu=0.1), SolverSettings("rigid"))
    on = equilibrium._solve_forward_at(below, None, res.start, settle=True)
    assert on.status == "trimmed"
    assert on.omega_rad_s == pytest.approx(res.branch_end["omega_rad_s"], rel=0.01)
    assert trim_module._largest_multiplier(on) > 1.0
    from amra_core.simulation import Case, Simulation
    assert "already unstable" in Simulation(Case(model.rotor, model.flight, model.settings, 1.0), res).start_note

def test_the_advance_ratio_continuation_stays_on_its_branch(mccutcheon):
    """Followed up in advance ratio at its mean GJ (1478.3), the rigid McCutcheon branch reaches mu 0.5 where the
    continuation in GJ does (the test above: 40.228 rad/s, descent 7.937 m/s). The last step, from
    mu 0.475, used to land on another orbit, 35.76 rad/s and 8.24 m/s (a jump of 12 % in rotor
    speed, inside the 25 % that was the only check), and the trim reported it. Each step must now
    continue the branch (``on_branch``: within 5 % of the secant prediction)."""
    gj = float(np.mean(mccutcheon.stations.gj_nm2))  # 1478.3
    model = compile_model(mccutcheon.with_overrides(gj_nm2=gj), FlightCondition(mu=0.5), SolverSettings("rigid"))
    res = equilibrium.trim_forward_continued(model)
    assert res.status == "trimmed"
    assert res.omega_rad_s == pytest.approx(40.228, rel=2e-3)
    assert res.descent_rate_m_s == pytest.approx(7.937, abs=0.05)


@pytest.mark.slow
def test_an_unstable_orbit_does_not_make_the_answer_depend_on_the_last_bit(mccutcheon):
    """At mu 0.5 the fem-torsion McCutcheon orbit is unstable, and one chord Newton step of the
    shooting left a gap that the averaging revolution amplified: the continuation in advance ratio
    at its mean GJ trimmed, and at that GJ times (1 - 1e-12) ended at mu 0.447 as "no-autorotation". A failed
    step is now tried again with every trial shot onto its orbit (``PeriodicShooting.settle``):
    the three give one answer (35.82 rad/s; 5e-4 rad/s apart, 2026-12-07)."""
    answers, gj = [], float(np.mean(mccutcheon.stations.gj_nm2))
    for factor in (1.0, 1.0 + 1e-12, 1.0 - 1e-12):
        model = compile_model(mccutcheon.with_overrides(gj_nm2=gj * factor), FlightCondition(mu=0.5),
                              SolverSettings("fem-torsion"))
        res = equilibrium.trim_forward_continued(model)
        assert res.status == "trimmed", res.reason
        answers.append(res.omega_rad_s)
    assert max(answers) - min(answers) < 5e-3


def test_an_iteration_that_leaves_its_best_behind_stops(mccutcheon, revolutions):
    """Fem-coupled McCutcheon at mu 0.5: the continuation in GJ ends at its last trim, GJ 3,715
    N m^2/rad, where the branch folds (not shown unstable). Near there the continuation's Newton
    iterations drifted away from their best iterate (residuals from 1e-3 up to 3e-2) for all their
    30 iterations; an iteration whose last 8 residuals are all above twice its best now stops, and
    the continuation halves its step as it did after the 30. The same end with fewer revolutions:
    2,322 against 2,786 (2026-12-07)."""
    model = compile_model(mccutcheon, FlightCondition(mu=0.5), SolverSettings("fem-coupled"))
    res = trim(model)
    assert res.status == "no-autorotation"
    assert res.branch_end["gj_mean_nm2"] == pytest.approx(3715.4, rel=0.02)  # the continuation's bracket
    assert res.branch_end["last_trim_unstable"] is False
    print(f"revolutions marched: {revolutions[0]}")
    assert revolutions[0] < 2500
