"""Verdicts on runs without a trim and on the windmill-brake side, on synthetic histories whose
answer is known by construction (amra_core.verdict.judge)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from amra_core.kernels import HISTORY_COLUMNS
from amra_core.verdict import VERDICTS, judge

C = {c: i for i, c in enumerate(HISTORY_COLUMNS)}
V_H = 5.6  # hover induced velocity [m/s] of the McCutcheon preset
OM0 = 40.0


def history(omega, descent, t_end=10.0, dt=0.0025, teeter_amp=0.01, teeter_rate=-0.5, teeter_hz=20.0):
    """Rows with rotor speed omega(t), descent rate descent(t) and a teeter oscillation of
    ``teeter_hz`` whose amplitude grows at ``teeter_rate`` [1/s]."""
    t = np.arange(0.0, t_end, dt)
    om = omega(t)
    h = np.zeros((len(t), len(HISTORY_COLUMNS)))
    h[:, C["t_s"]] = t
    h[:, C["omega_rad_s"]] = om
    h[:, C["azimuth_rad"]] = np.concatenate([[0.0], np.cumsum(0.5 * (om[1:] + om[:-1]) * dt)])
    h[:, C["descent_rate_m_s"]] = descent(t)
    h[:, C["teeter_rad"]] = teeter_amp * np.exp(teeter_rate * t) * np.sin(2 * math.pi * teeter_hz * t)
    return h


def run_judge(h, trimmed, axial=True):
    return judge(h, HISTORY_COLUMNS, OM0, axial, "finished", trimmed, h[0].copy(), 0.01, hover_induced_m_s=V_H)


def test_axial_run_that_falls_into_the_windmill_brake_state_lost_autorotation():
    """Paper Fig. 10 (paper-boundary, GJ 100): descent 10.5 -> 36 m/s = 6.4 v_h while the rotor
    speed falls and recovers; the old verdict needed the rotor speed still falling."""
    h = history(lambda t: OM0 * (1 - 0.15 * (1 - np.exp(-t))), lambda t: 10.5 + 25.5 * (1 - np.exp(-t / 2)))
    v = run_judge(h, trimmed=False)
    assert v.verdict == "no-autorotation" and "windmill-brake" in v.explanation, v


def test_axial_run_that_starts_and_stays_in_the_windmill_brake_state():
    h = history(lambda t: OM0 + 0 * t, lambda t: 25.6 + 0 * t)
    v = run_judge(h, trimmed=True)
    assert v.verdict == "windmill-brake" and "windmill-brake" in v.explanation
    assert "windmill-brake" in VERDICTS and v.unstable  # an equilibrium, but not normal autorotation


def test_forward_glide_at_a_few_v_h_is_not_a_windmill_brake():
    h = history(lambda t: OM0 + 0 * t, lambda t: 15.0 + 0 * t)
    assert run_judge(h, trimmed=True, axial=False).verdict == "stable"


def test_untrimmed_run_that_settles_is_judged_on_the_settled_motion():
    """Rotor speed 10 % below the start after 2 s and steady, the kick decaying: stable there."""
    h = history(lambda t: OM0 * (0.9 + 0.1 * np.exp(-2 * t)), lambda t: 7.0 + 0 * t)
    v = run_judge(h, trimmed=False)
    assert v.verdict == "stable", v
    assert "settled 10 % below" in v.explanation
    # the same with a limit cycle 30x the kick: flutter
    h = history(lambda t: OM0 * (0.9 + 0.1 * np.exp(-2 * t)), lambda t: 7.0 + 0 * t, teeter_amp=0.3,
                teeter_rate=0.0)
    assert run_judge(h, trimmed=False).verdict == "flutter"


def test_untrimmed_run_still_falling_is_no_autorotation():
    h = history(lambda t: OM0 * (1 - 0.03 * t), lambda t: 10.0 + 0 * t)
    v = run_judge(h, trimmed=False)
    assert v.verdict == "no-autorotation" and "still falling" in v.explanation


def test_untrimmed_run_still_moving_is_undetermined():
    """Rotor speed down 20 % in 3 s, then rising 1 %/s to the end: not settled, not falling."""
    h = history(lambda t: OM0 * np.where(t < 3, 1 - 0.2 * t / 3, 0.8 + 0.01 * (t - 3)), lambda t: 10.0 + 0 * t)
    v = run_judge(h, trimmed=False)
    assert v.verdict == "undetermined" and "run longer" in v.explanation, v


def test_a_descent_rate_that_fell_is_not_said_to_have_risen():
    """Paper-boundary, fem-torsion, GJ 10: the run starts on the windmill-brake side (no branch to
    follow) and its descent rate falls a little; the explanation read 'the descent rate rose from 38.8
    to 38.3 m/s'."""
    import re

    from amra_core.flight import FlightCondition, SolverSettings
    from amra_core.rotor_io import load_preset
    from amra_core.simulation import Case, Simulation
    sim = Simulation(Case(load_preset("paper-boundary").with_overrides(gj_nm2=10.0), FlightCondition(),
                          SolverSettings("fem-torsion"), t_end_s=2.0))
    sim.run()
    v = sim.verdict()
    m = re.search(r"the descent rate (\w+) from ([\d.]+) to ([\d.]+) m/s", v.explanation)
    assert v.verdict == "no-autorotation" and m is not None, v.explanation
    word, a, b = m.group(1), float(m.group(2)), float(m.group(3))
    assert b < a and word == "went"


@pytest.mark.parametrize("fidelity", ["rigid", "fem-torsion"])
def test_a_run_that_starts_and_stays_on_the_windmill_brake_side_is_no_overspeed(fidelity):
    """Paper-boundary, GJ 10, 3 s: no branch to follow, the run starts from the windmill-brake
    equilibrium (16 rad/s, 38 m/s) and stays on that side while its rotor speed rises to 26 rad/s and
    falls again. Rigid said 'overspeed: rotor speed ran away upwards' (1.5 x its slow start), the FEM
    levels 'no-autorotation': every level now says the latter, as the map's windmill-brake cells do."""
    from amra_core.flight import FlightCondition, SolverSettings
    from amra_core.rotor_io import load_preset
    from amra_core.simulation import Case, Simulation
    sim = Simulation(Case(load_preset("paper-boundary").with_overrides(gj_nm2=10.0), FlightCondition(),
                          SolverSettings(fidelity), t_end_s=3.0))
    sim.run()
    v = sim.verdict()
    if fidelity == "rigid":  # what made it read as an overspeed: 1.5 x its slow start
        assert sim.history[-1, 2] > 1.5 * sim.history[0, 2]
    assert v.verdict == "no-autorotation" and "the windmill-brake state" in v.explanation, (v.verdict, v.explanation)
