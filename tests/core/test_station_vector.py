"""The right-hand side's station loops (both blades' stations as one vector, in passes the compiler
vectorises) against the scalar station path (station_kinematics + station_aero, one station at a
time, as station_loads and the steady Wagner states use it), and the polynomial sine and cosine
they run on against the C library."""
import math

import numpy as np
import pytest
from numba import njit

from amra_core import kernel_guard, kernels
from amra_core.flight import FlightCondition, SolverSettings
from amra_core.layout import L_THRUST, L_TORQUE, N_Y_FIXED, P_AERO, P_NS, P_NST, P_QUASI_STATIC, P_RHO, S_R, S_W
from amra_core.model import compile_model
from amra_core.sincos_kernel import sincos


@njit
def _sincos_many(x):
    out = np.empty((2, x.shape[0]))
    for i in range(x.shape[0]):
        out[0, i], out[1, i] = sincos(x[i])
    return out


def test_sincos_matches_the_c_library_to_the_last_bits():
    rng = np.random.default_rng(11)
    for lim in (1.0, 10.0, 1e5):
        x = np.concatenate([np.linspace(-lim, lim, 200_001), rng.uniform(-lim, lim, 200_000)])
        got = _sincos_many(x)
        assert np.max(np.abs(got[0] - np.sin(x))) <= 3e-16
        assert np.max(np.abs(got[1] - np.cos(x))) <= 3e-16
    # the quadrant boundaries and zero
    x = np.array([0.0, math.pi / 2, math.pi, -math.pi / 2, 3 * math.pi / 2, 2 * math.pi, 1e-300])
    got = _sincos_many(x)
    np.testing.assert_allclose(got[0], np.sin(x), rtol=0, atol=3e-16)
    np.testing.assert_allclose(got[1], np.cos(x), rtol=0, atol=3e-16)
    assert np.isnan(_sincos_many(np.array([math.nan, math.inf, -math.inf]))).all()


@njit
def _scalar_stations(y, m):
    """Thrust, torque [N, N m] and the Wagner state rates of every station, one station at a time."""
    p = m.p
    nst = int(p[P_NST]); ns = int(p[P_NS])
    a0 = N_Y_FIXED + 2 * ns
    theo = p[P_AERO] > 0.5 and p[P_QUASI_STATIC] < 0.5
    vx, vup = kernels.free_stream(y, m)
    hs, hc = kernels.inflow_gradients(y, m)
    rates = np.zeros(4 * nst)
    thrust = 0.0; torque = 0.0
    for b in range(2):
        sgn = 1.0 - 2.0 * b
        sp = sgn * math.sin(y[0]); cp = sgn * math.cos(y[0])
        for j in range(nst):
            ut, up, theta, thd, wp, w, th = kernels.station_kinematics(y, m, b, j, vx, vup, sp, cp, hs, hc)
            ia = a0 + 2 * (b * nst + j)
            fup, ffwd, mea, d1, d2 = kernels.station_aero(
                ut, up, theta, thd, m.st[j, 2], m.st[j, 3], m.st[j, 4], m.st[j, 6], y[ia], y[ia + 1], theo,
                p[P_RHO], p[1], m.af_alpha0, m.af_dalpha, m.af_cl, m.af_cd, m.af_cm)
            thrust += fup * m.st[j, S_W]
            torque += m.st[j, S_R] * ffwd * m.st[j, S_W]
            rates[2 * (b * nst + j)] = d1; rates[2 * (b * nst + j) + 1] = d2
    return thrust, torque, rates


@pytest.mark.parametrize("fidelity", ["rigid", "fem-coupled"])
@pytest.mark.parametrize("mu, inflow, n_stations", [(0.0, "uniform", 12), (0.3, "three-state", 7)])
def test_the_vectorised_stations_give_the_scalar_path_s_loads(mccutcheon, fidelity, mu, inflow, n_stations):
    """Random states (rotor speed, descent, deflections, lag, Wagner states): thrust, torque and
    every Wagner state rate agree to rounding (1e-12 relative); 7 stations per blade leave a
    remainder after the vector width."""
    model = compile_model(mccutcheon, FlightCondition(mu=mu),
                          SolverSettings(fidelity, inflow=inflow, n_stations=n_stations))
    a0 = N_Y_FIXED + 2 * model.n_s
    rng = np.random.default_rng(5)
    for _ in range(5):
        y = np.zeros(model.n_y)
        y[0] = rng.uniform(0, 2 * math.pi); y[1] = rng.uniform(25, 45); y[2] = rng.uniform(5, 12)
        y[3] = rng.uniform(2, 6); y[4:] += rng.normal(0, 0.02, model.n_y - 4)
        y[a0:a0 + 4 * model.n_st] = rng.normal(0, 2.0, 4 * model.n_st)
        dy = np.zeros(model.n_y); loads = np.zeros(8)
        kernel_guard.evaluate(y, model.arrays, dy, loads)
        thrust, torque, rates = _scalar_stations(y, model.arrays)
        assert loads[L_THRUST] == pytest.approx(thrust, rel=1e-12, abs=1e-9)
        assert loads[L_TORQUE] == pytest.approx(torque, rel=1e-12, abs=1e-9)
        np.testing.assert_allclose(dy[a0:a0 + 4 * model.n_st], rates, rtol=1e-12, atol=1e-9 * np.abs(rates).max())


def test_the_guard_refuses_station_vectors_that_are_not_the_station_table(mccutcheon):
    """sv and kin are copies of st and shw/shd/sht laid out per station: arrays mixed from two
    models, or edited on one side only, would pass every shape check but not this one."""
    a = compile_model(mccutcheon, FlightCondition(), SolverSettings("fem-coupled"))
    y = np.zeros(a.n_y); y[1] = 38.0
    for field in ("sv", "kin"):
        bad = a.arrays._replace(**{field: getattr(a.arrays, field) * 1.01})
        with pytest.raises(kernel_guard.KernelShapeError, match=field):
            kernel_guard.evaluate(y, bad, np.zeros(a.n_y), np.zeros(8))


def test_the_guard_rechecks_p_of_a_model_with_changed_controls(mccutcheon):
    """A model with changed controls holds the same arrays under a new ``p``: the guard does not
    check the arrays again, but still checks the counts in that ``p``, and a tuple that swaps in
    any other array is checked in full."""
    a = compile_model(mccutcheon, FlightCondition(), SolverSettings("fem-coupled"))
    y = np.zeros(a.n_y); y[1] = 38.0
    dy, loads = np.zeros(a.n_y), np.zeros(8)
    kernel_guard.evaluate(y, a.arrays, dy, loads)
    held = a.with_controls(airspeed_m_s=10.0, hold_omega=True)
    assert held.arrays.sv is a.arrays.sv and held.arrays.p is not a.arrays.p
    kernel_guard.evaluate(y, held.arrays, dy, loads)  # accepted
    for slot, value in ((P_NS, a.n_s + 1.0), (P_NST, a.n_st - 1.0)):
        p = held.arrays.p.copy(); p[slot] = value
        with pytest.raises(kernel_guard.KernelShapeError):
            kernel_guard.evaluate(y, held.arrays._replace(p=p), dy, loads)
    bad = held.arrays._replace(kin=held.arrays.kin * 1.01)
    with pytest.raises(kernel_guard.KernelShapeError, match="kin"):
        kernel_guard.evaluate(y, bad, dy, loads)
