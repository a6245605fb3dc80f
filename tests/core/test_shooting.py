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


def _turned_reduction(original, turn_rad: float):
    """``model._reduction`` with the retained modes in another basis: two modes change sign and the
    closest pair in frequency (the two blades' copies of a mode, split by the teeter hub) turns by
    ``turn_rad`` in its plane, as an eigensolver returns them at a neighbouring GJ. The physics is
    unchanged (with plain RK4: the Lawson step integrates the diagonal of the modal stiffness
    exactly, so a turned pair would change its numerics)."""
    def reduction(s, settings, omega_ref_rad_s):
        phi, _, minv, _, _ = original(s, settings, omega_ref_rad_s)
        w2 = np.diag(phi.T @ (s.K0 + omega_ref_rad_s**2 * s.K2) @ phi)
        i = int(np.argmin(np.diff(w2) / w2[1:]))
        pair = (i, i + 1)
        r = np.eye(len(w2))
        r[0, 0] = r[len(w2) - 1, len(w2) - 1] = -1.0
        c, sn = np.cos(turn_rad), np.sin(turn_rad)
        i, j = pair
        r[np.ix_([i, j], [i, j])] = r[np.ix_([i, j], [i, j])] @ np.array([[c, -sn], [sn, c]])
        phi = phi @ r
        return phi, phi.T @ s.M, minv, phi.T @ s.K0 @ phi, phi.T @ s.K2 @ phi
    return reduction


def test_a_matrix_reused_in_another_modal_basis_is_rewritten_in_it(monkeypatch):
    """The modal basis of the FEM levels comes from an eigensolver: at a neighbouring GJ a mode may
    change sign and the blades' equal-frequency pairs turn. A shooting matrix formed in one basis and
    used in another must be the matrix of that basis (the same dynamics, written in the new
    coordinates), or the projection is thrown off (the fem-torsion trim at mu 0.5 then ended its
    branch anywhere from GJ 2041 to 2989 N m^2/rad for GJ values within 1 % of 1478)."""
    from amra_core import model as model_module
    from amra_core.model import transfer_state
    from amra_core.rotor_io import load_preset
    rotor, flight = load_preset("mccutcheon"), FlightCondition(mu=0.3)
    a = compile_model(rotor, flight, SolverSettings("fem-torsion", integrator="rk4")).with_controls(
        alpha_s_rad=-0.05, airspeed_m_s=30.0, hold_omega=True, hold_vd=True)
    monkeypatch.setattr(model_module, "_reduction", _turned_reduction(model_module._reduction, 0.6))
    b = compile_model(rotor, flight, SolverSettings("fem-torsion", integrator="rk4")).with_controls(
        alpha_s_rad=-0.05, airspeed_m_s=30.0, hold_omega=True, hold_vd=True)
    t = b.phi_pinv @ a.phi
    assert np.min(np.diag(t)) < -0.99 and np.max(np.abs(t - np.diag(np.diag(t)))) > 0.5  # flipped and turned
    y_a = np.zeros(a.n_y)
    y_a[1], y_a[2] = 40.0, 8.0  # rotor speed [rad/s], descent rate [m/s]
    dt = stable_time_step(a, 40.0)
    for _ in range(3):  # onto the neighbourhood of the orbit
        y_a = shooting.one_rev(a, y_a, dt)
    y_b = transfer_state(y_a, a, b)

    formed_in_a = shooting.PeriodicShooting()
    formed_in_a.build(a, y_a, dt)
    unconverted = formed_in_a.copy()
    unconverted.basis = b.phi  # what was done before: the matrix used as it was
    formed_in_b = shooting.PeriodicShooting()
    formed_in_b.build(b, y_b, dt)

    projected_b, _ = formed_in_b.project(b, y_b, dt)
    projected_a, _ = formed_in_a.project(b, y_b, dt)
    projected_unconverted, _ = unconverted.project(b, y_b, dt)
    def off(m):
        return np.linalg.norm(m.phi_s - formed_in_b.phi_s) / np.linalg.norm(formed_in_b.phi_s)
    step = np.linalg.norm(projected_b - y_b)
    # measured: 3.9e-4 (the finite differences of two bases differ at that level) against 0.75,
    # and the projections 1.3e-6 of the step apart against 1.26
    assert off(formed_in_a) < 2e-3 and off(unconverted) > 0.3
    assert np.linalg.norm(projected_a - projected_b) < 1e-4 * step
    assert np.linalg.norm(projected_unconverted - projected_b) > 0.3 * step
