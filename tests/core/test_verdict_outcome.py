"""A run's verdict carries its outcome and the rotor-speed headline, and a short run is never
"stable" (issue 21 §1, §7): synthetic histories whose answer is known by construction."""
from __future__ import annotations

import math

import numpy as np

from amra_core.kernels import HISTORY_COLUMNS
from amra_core.verdict import OUTCOMES, STABLE_MIN_FIT_S, judge

C = {c: i for i, c in enumerate(HISTORY_COLUMNS)}
V_H = 5.6
OM0 = 40.0


def history(teeter, omega=lambda t: OM0 + 0 * t, t_end=20.0, dt=0.0025, hz=12.0):
    """Rows with rotor speed omega(t), descent 10 m/s and a teeter oscillation of ``hz`` whose
    amplitude is teeter(t) [rad]."""
    t = np.arange(0.0, t_end, dt)
    om = omega(t)
    h = np.zeros((len(t), len(HISTORY_COLUMNS)))
    h[:, C["t_s"]] = t
    h[:, C["omega_rad_s"]] = om
    h[:, C["azimuth_rad"]] = np.concatenate([[0.0], np.cumsum(0.5 * (om[1:] + om[:-1]) * dt)])
    h[:, C["descent_rate_m_s"]] = 10.0
    h[:, C["teeter_rad"]] = teeter(t) * np.sin(2 * math.pi * hz * t)
    return h


def run_judge(h, trimmed=True, branch="normal"):
    return judge(h, HISTORY_COLUMNS, OM0, True, "finished", trimmed, h[0].copy(), 0.01, hover_induced_m_s=V_H,
                 branch=branch)


def test_decaying_run_is_stable_and_decays():
    v = run_judge(history(lambda t: 0.01 * np.exp(-0.3 * t)))
    assert v.verdict == "stable" and v.outcome == "decays"
    assert v.rotor_speed.startswith("rotor speed kept") and "40.0 rad/s" in v.rotor_speed


def test_a_growth_below_the_threshold_is_neutral_not_a_decay():
    """A map's flutter cell (fem-torsion CG 26 %, GJ 186) ran "stable, the perturbation decays" with a
    growth rate of +0.0013 1/s."""
    v = run_judge(history(lambda t: 0.01 * np.exp(-3.0 * t) + 1e-5 * np.exp(0.005 * t)))  # kick gone, a slow rest
    assert v.verdict == "stable" and v.outcome == "neutral" and 0.0 < v.growth_rate_per_s < 0.02, v
    assert v.explanation.startswith("no measurable growth") and "decays" not in v.explanation


def test_saturating_oscillation_is_a_bounded_flutter_with_its_amplitudes():
    """Grows at +2 1/s from 1e-4 rad, levels off at 0.005 rad (below the 0.01 rad kick scale):
    the old fit over the last two thirds saw a flat envelope and said "stable"."""
    v = run_judge(history(lambda t: np.minimum(1e-4 * np.exp(2.0 * t), 0.005)))
    assert v.verdict == "flutter" and v.outcome == "bounded-oscillation", v
    lc = v.limit_cycle
    assert math.isclose(lc["teeter_deg"], math.degrees(0.005), rel_tol=0.02), lc
    assert lc["omega_rad_s"] == 0.0 and v.frequency_hz == pytest_approx(12.0, 0.05)


def pytest_approx(x, rel):
    import pytest
    return pytest.approx(x, rel=rel)


def test_a_drift_is_not_read_as_a_frequency():
    """A decaying run whose largest deviation is a slow drift (under two cycles in the record) has no
    resolved frequency: it read 1/T (0.1 Hz over 10 s), the spectrum's lowest bin."""
    h = history(lambda t: 0.0 * t, t_end=10.0)
    h[:, C["tip_twist_0_rad"]] = 0.005 * np.exp(-0.5 * h[:, C["t_s"]])  # a slow return to the trim
    trim_row = h[0].copy()
    trim_row[C["tip_twist_0_rad"]] = 0.0
    v = judge(h, HISTORY_COLUMNS, OM0, True, "finished", True, trim_row, 0.01, hover_induced_m_s=V_H, branch="normal")
    assert v.verdict == "stable" and v.frequency_hz is None, v


def test_an_oscillation_of_two_cycles_in_the_record_is_resolved():
    """The rule is per record: 0.25 Hz over 8 s is 2 cycles, resolved (below the flutter floor)."""
    v = run_judge(history(lambda t: 0.01 * np.exp(-0.3 * t), t_end=8.0, hz=0.25))
    assert v.frequency_hz == pytest_approx(0.25, 1e-6), v


def test_growing_oscillation_is_a_runaway():
    v = run_judge(history(lambda t: 1e-4 * np.exp(0.3 * t)))
    assert v.verdict == "flutter" and v.outcome == "runaway" and v.growth_rate_per_s > 0.2


def test_rotor_speed_collapse_is_the_headline_with_its_time():
    om = lambda t: OM0 * np.exp(-0.2 * t)  # noqa: E731 - below 50 % at ln 2 / 0.2 = 3.47 s
    v = run_judge(history(lambda t: 0.01 * np.exp(0.2 * t), omega=om), trimmed=False)
    assert v.outcome == "rotor-speed-collapse" and abs(v.collapse_time_s - math.log(2) / 0.2) < 0.01
    assert v.rotor_speed.startswith("rotor speed LOST") and "3.4" in v.rotor_speed
    # no equilibrium: the verdict names the cause (an oscillation on the way is told in the explanation)
    assert v.verdict == "no-autorotation"


def test_short_run_that_seems_to_decay_is_undetermined():
    """The measured case: a 0.5 s run fitted -4.4 1/s and said "stable (final)"."""
    for t_end in (0.5, 2.0, 0.9 * 1.5 * STABLE_MIN_FIT_S):
        v = run_judge(history(lambda t: 0.01 * np.exp(-0.5 * t), t_end=t_end))
        assert v.verdict == "undetermined" and "run too short" in v.explanation, (t_end, v)
        assert v.outcome == "undetermined"
    v = run_judge(history(lambda t: 0.01 * np.exp(-0.5 * t), t_end=1.6 * STABLE_MIN_FIT_S))
    assert v.verdict == "stable"


def test_overspeed_start_is_named_and_decays():
    v = run_judge(history(lambda t: 0.01 * np.exp(-0.3 * t)), branch="overspeed")
    assert v.verdict == "overspeed" and v.outcome == "decays" and "overspeeding" in v.rotor_speed


def test_every_outcome_is_from_the_vocabulary():
    for h in (history(lambda t: 0.01 * np.exp(-0.3 * t)), history(lambda t: 1e-4 * np.exp(0.3 * t)),
              history(lambda t: 0.01 + 0 * t, t_end=0.5)):
        assert run_judge(h).outcome in OUTCOMES


def test_a_failure_after_the_collapse_keeps_the_collapse_as_the_answer():
    """The rotor speed falls below half its trim at 2 s; the integration breaks down at 15 s (the rows
    from there are non-finite). The collapse answered the question first: the verdict is the
    collapse's, and it names the failure; a failure before any collapse knows nothing."""
    omega = lambda t: OM0 * np.maximum(1.0 - 0.3 * t, 0.3)  # noqa: E731 - below OM0/2 from t = 1.67 s
    h = history(lambda t: 0.01 + 0 * t, omega=omega)
    h[h[:, C["t_s"]] >= 15.0, 1:] = np.nan
    v = judge(h, HISTORY_COLUMNS, OM0, True, "numerical-failure", False, h[0].copy(), 0.01,
              hover_induced_m_s=V_H, branch="normal")
    assert v.verdict == "no-autorotation" and v.outcome == "rotor-speed-collapse", v
    assert v.collapse_time_s == __import__("pytest").approx(5.0 / 3.0, abs=0.01)
    assert "left its stability region at t = 15.00 s" in v.explanation
    steady = history(lambda t: 0.01 + 0 * t)
    steady[steady[:, C["t_s"]] >= 15.0, 1:] = np.nan
    v = judge(steady, HISTORY_COLUMNS, OM0, True, "numerical-failure", True, steady[0].copy(), 0.01,
              hover_induced_m_s=V_H, branch="normal")
    assert v.verdict == "numerical-failure" and v.outcome == "undetermined"


def test_a_failure_after_seconds_of_growth_is_the_instability_running_away():
    """An oscillation growing at +1 1/s for 8 s, then non-finite rows (the state left the model's
    range): a flutter that ran away, at its fitted growth; a history that decayed and then blew up
    within one step (a time step outside its stability region) stays a numerical failure."""
    h = history(lambda t: 1e-4 * np.exp(1.0 * t))
    h[h[:, C["t_s"]] >= 8.0, 1:] = np.nan
    v = judge(h, HISTORY_COLUMNS, OM0, True, "numerical-failure", True, h[0].copy(), 0.01,
              hover_induced_m_s=V_H, branch="normal")
    assert v.verdict == "flutter" and v.outcome == "runaway", v
    assert v.growth_rate_per_s == __import__("pytest").approx(1.0, rel=0.1)
    assert "left the model's range" in v.explanation and "t = 8.00 s" in v.explanation
    # its headline does not say the rotor speed was kept (a 10 s run that failed at 1.25 s read
    # "rotor speed kept: 66.9 rad/s at t = 1.2 s")
    assert v.rotor_speed.startswith("rotor speed not known to be kept: 40.0 rad/s at t = 8.00 s"), v.rotor_speed
    assert v.rotor_speed.endswith("when the run failed numerically")
    d = history(lambda t: 0.01 * np.exp(-0.3 * t))
    t = d[:, C["t_s"]]
    blow = (t >= 7.98) & (t < 8.0)  # the last 20 ms explode by e^100 (finite), then non-finite
    d[blow, C["teeter_rad"]] *= np.exp(np.linspace(0.0, 100.0, blow.sum()))
    d[t >= 8.0, 1:] = np.nan
    v = judge(d, HISTORY_COLUMNS, OM0, True, "numerical-failure", True, d[0].copy(), 0.01,
              hover_induced_m_s=V_H, branch="normal")
    assert v.verdict == "numerical-failure", v


def test_a_rotor_speed_within_half_a_percent_reads_plus_zero_not_minus_zero():
    """A run that lost 0.3 % of its rotor speed says "+0 % of the start": a rounded change has no sign."""
    v = run_judge(history(lambda t: 0.01 * np.exp(-0.3 * t), omega=lambda t: OM0 * (1.0 - 0.003 * t / 20.0)))
    assert "(+0 % of the start" in v.rotor_speed and "-0 %" not in v.rotor_speed, v.rotor_speed


def test_a_numerical_failure_says_how_large_the_motion_was_and_no_unusable_advice():
    """A failure too soon to judge names the motion before it (tip twist, teeter) and points to the
    Python API's step for telling a time-step failure from the motion itself: the dashboard and the
    CLI have no step setting, and "try a smaller dt_s" could not be followed there."""
    d = history(lambda t: 0.01 * np.exp(-0.3 * t))
    t = d[:, C["t_s"]]
    d[:, C["tip_twist_0_rad"]] = np.radians(35.0) * (t >= 0.1)
    d[t >= 0.2, 1:] = np.nan
    v = judge(d, HISTORY_COLUMNS, OM0, True, "numerical-failure", True, d[0].copy(), 0.01,
              hover_induced_m_s=V_H, branch="normal")
    assert v.verdict == "numerical-failure", v
    assert "at t = 0.20 s" in v.explanation and "tip twist reached 35 deg" in v.explanation, v.explanation
    assert "SolverSettings.dt_s" in v.explanation and "try a smaller dt_s" not in v.explanation


def test_a_slow_growth_under_a_decaying_oscillation_is_not_called_stable():
    """Rigid, CG 0.35, GJ 241 (a map's unstable inflow/rotor-speed mode, +0.05 1/s): over 10 s the
    decaying teeter dominated the deviation's norm (-0.13 1/s) and the run was called stable; 30 s
    later it was a limit cycle. Built here: a 12 Hz teeter decaying at -0.3 1/s over a 0.23 Hz rotor
    speed swing growing at +0.06 1/s. The rotor speed's own fit finds the growth."""
    grow = 0.06
    h = history(lambda t: 0.01 * np.exp(-0.3 * t),
                omega=lambda t: OM0 * (1 + 2e-4 * np.exp(grow * t) * np.sin(2 * math.pi * 0.23 * t)), t_end=10.0)
    v = run_judge(h)
    assert v.verdict == "undetermined" and "rotor speed deviation grows" in v.explanation, v
    # the reported growth is the rotor speed's own fit (per revolution peaks of a 0.23 Hz swing over
    # two cycles: its sign and order, not its digits)
    assert 0.02 < v.growth_rate_per_s < 0.2
    # without the slow growth the same run is stable
    assert run_judge(history(lambda t: 0.01 * np.exp(-0.3 * t), t_end=10.0)).verdict == "stable"


def test_an_untrimmed_run_whose_descent_still_climbs_is_undetermined_not_settled():
    """Forward flight, no trim: the rotor speed levels 27 % below the branch end while the descent
    rate climbs at 3 m/s per s (a glide steepening; in axial flight this is the windmill-brake
    check's). It was called "settled" with an outcome "runaway" and a headline "rotor speed kept"."""
    h = history(lambda t: 0.01 * np.exp(-0.3 * t), omega=lambda t: OM0 * (0.73 + 0.27 * np.exp(-t / 0.8)), t_end=6.0)
    h[:, C["descent_rate_m_s"]] = 5.0 + 3.0 * h[:, C["t_s"]]
    v = judge(h, HISTORY_COLUMNS, OM0, False, "finished", False, h[0].copy(), 0.01, hover_induced_m_s=V_H)
    assert v.verdict == "undetermined" and v.outcome == "undetermined", v
    assert "the descent rate was still rising (5.0 to 23.0 m/s, +3.00 m/s per s)" in v.explanation, v.explanation
    assert v.rotor_speed.startswith("rotor speed moved: 29.2 rad/s") and "not yet steady" in v.rotor_speed, v.rotor_speed
