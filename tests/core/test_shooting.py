"""Newton shooting onto the periodic orbit of forward flight (amra_core.shooting): the slow columns
of the one-revolution transition matrix carry the same least-damped Floquet multipliers as the
full monodromy matrix, and the projection reaches the orbit in a few revolutions where marching
leaves the slow lag transient."""
from __future__ import annotations

import numpy as np
import pytest

from amra_core import shooting
from amra_core.flight import FlightCondition, SolverSettings
from amra_core.model import compile_model, stable_time_step
from amra_core.stability import monodromy
from amra_core.trim import trim


@pytest.fixture(scope="module")
def held_orbit(request):
    from amra_core.rotor_io import load_preset
    model = compile_model(load_preset("mccutcheon"), FlightCondition(mu=0.1), SolverSettings("fem-coupled"))
    res = trim(model)
    assert res.ok
    m = res.model.with_controls(hold_omega=True, hold_vd=True)
    y = res.state.copy()
    idx = shooting.slow_states(m)
    y[idx] += 1e-2 * np.random.default_rng(7).standard_normal(len(idx)) * np.maximum(1.0, np.abs(y[idx]))
    return m, y, stable_time_step(m, y[1])


def test_the_slow_block_has_the_least_damped_floquet_multipliers(held_orbit):
    m, y, dt = held_orbit
    s = shooting.PeriodicShooting()
    s.build(m, y, dt)
    slow = np.sort(np.abs(np.linalg.eigvals(s.phi_s[s.idx])))[::-1]
    phi, _ = monodromy(m, y, dt)
    full = np.sort(np.abs(np.linalg.eigvals(phi)))[::-1]
    full = full[full < 1.0 - 1e-6]  # held rotor speed and descent rate: multipliers of exactly 1
    # the lag modes (about 0.9 per revolution): the slow subspace loses nothing the Wagner states held
    assert slow[:4] == pytest.approx(full[:4], abs=2e-3)
    assert slow[0] > 0.85


def test_shooting_reaches_the_orbit_where_marching_does_not(held_orbit):
    m, y, dt = held_orbit
    s = shooting.PeriodicShooting()
    s.build(m, y, dt)
    yy, gaps = y.copy(), []
    for _ in range(5):
        yy, gap = s.project(m, yy, dt)
        gaps.append(gap)
    # measured: 0.98, 0.35, 3.3e-3, 9.9e-5, 2.6e-6 (the first step is the nonlinear one)
    assert gaps[-1] < 1e-5 * gaps[0] and all(b < a for a, b in zip(gaps, gaps[1:]))
    marched = y.copy()
    for _ in range(8):
        before = marched.copy()
        marched = shooting.one_rev(m, marched, dt)
    assert np.max(np.abs(marched[s.idx] - before[s.idx])) > 1e-2 * gaps[0]  # the lag modes still ring
    # the orbit shot for repeats itself
    again = shooting.one_rev(m, yy, dt)
    assert np.max(np.abs(again[s.idx] - yy[s.idx])) < 1e-6
