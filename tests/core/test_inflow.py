"""Inflow models: the turbulent-wake mass-flow parameter and the Peters-HaQuang three-state model
(kernels.mass_flow, kernels.inflow_harmonics) against their closed-form steady solutions."""
import math

import numpy as np
import pytest

from amra_core import kernels
from amra_core.flight import FlightCondition, SolverSettings
from amra_core.model import Y_V0, compile_model
from amra_core.rotor_io import load_preset
from amra_core.trim import trim

RHO, R = 1.225, 3.81
AREA = math.pi * R * R
THRUST = 3530.0
VH = math.sqrt(THRUST / (2 * RHO * AREA))


def steady_inflow_ratio(x):
    """Steady v0/v_h of the uniform equation T = 2 rho A V_m v0 at climb ratio x = V_c/v_h."""
    from scipy.optimize import brentq

    def resid(v):
        return 2 * RHO * AREA * kernels.mass_flow(THRUST, 0.0, x * VH, v * VH, RHO, AREA) * v * VH - THRUST
    vs = np.linspace(1e-3, 4.0, 4000)
    res = np.array([resid(v) for v in vs])
    roots = [brentq(resid, vs[i], vs[i + 1]) for i in np.nonzero(np.diff(np.sign(res)))[0]]
    return roots


@pytest.mark.parametrize("x", [-1.9, -1.5, -1.0, -0.5])
def test_turbulent_wake_curve_is_the_steady_inflow(x):
    k = kernels.EMP_K
    emp = k[0] + x * (k[1] + x * (k[2] + x * (k[3] + x * k[4])))
    roots = steady_inflow_ratio(x)
    assert len(roots) == 1 and roots[0] == pytest.approx(emp, rel=1e-9)


@pytest.mark.parametrize("x", [-2.02, -2.05, -2.08])
def test_one_root_where_the_curve_blends_into_the_windmill_state(x):
    """-2.1 < x < -2: the curve blends into the windmill-brake root written as a mass flow that
    does not depend on v0, so there is exactly one steady inflow between the two."""
    k = kernels.EMP_K
    emp_end = k[0] - 2 * k[1] + 4 * k[2] - 8 * k[3] + 16 * k[4]
    wb = -x / 2 - math.sqrt(x * x / 4 - 1)
    roots = steady_inflow_ratio(x)
    assert len(roots) == 1
    assert min(wb, emp_end) <= roots[0] <= max(wb, emp_end)


@pytest.mark.parametrize("x", [-2.5, -3.0, 0.5, 1.0])
def test_momentum_theory_outside_the_curve(x):
    """Climb: the momentum root v/v_h = -x/2 + sqrt(x^2/4 + 1) is the only one. Windmill brake
    state (x < -2.1): the smallest root is the physical one, -x/2 - sqrt(x^2/4 - 1); the larger
    momentum roots are rejected by the trim (see trim.trim_axial)."""
    roots = steady_inflow_ratio(x)
    if x >= 0:
        assert len(roots) == 1
        assert roots[0] == pytest.approx(-x / 2 + math.sqrt(x * x / 4 + 1), rel=1e-9)
    else:
        assert roots[0] == pytest.approx(-x / 2 - math.sqrt(x * x / 4 - 1), rel=1e-9)


def _harmonic_rates(v0, vs, vc, mom_s, mom_c, vx, vup, vm):
    y = np.zeros(12); dy = np.zeros(12)
    y[Y_V0] = v0; y[-2] = vs; y[-1] = vc
    kernels.inflow_harmonics(y, dy, 2 * RHO * AREA * vm * v0, mom_s, mom_c, vx, vup, vm, RHO, R)
    return dy[Y_V0], dy[-2], dy[-1]


@pytest.mark.parametrize("vx, vup", [(0.0, 10.0), (14.0, 4.0), (27.0, 1.0), (40.0, 0.0)])
def test_three_state_steady_solution_is_pitt_peters(vx, vup):
    """Thrust alone: the steady state is v0 = T / (2 rho A V_m) (momentum) with the longitudinal
    gradient v_c = (15 pi / 32) tan(chi / 2) v0 of Pitt-Peters and no lateral inflow."""
    v0, vm = 6.0, 9.0
    chi = math.atan2(abs(vx), abs(vup - v0))
    vc = 15 * math.pi / 32 * math.tan(chi / 2) * v0
    rates = _harmonic_rates(v0, 0.0, vc, 0.0, 0.0, vx, vup, vm)
    scale = THRUST * 3 / (8 * RHO * R**3)  # size of one term of dv0/dt
    assert np.allclose(rates, 0.0, atol=1e-9 * scale)


def test_three_state_lateral_gain_and_time_constant():
    """Axial flow: a lateral moment M_s holds v_s = L22 M_s / (rho pi R^3 V_m) with L22 = 2, and a
    free v_s decays at (45 pi / 32) V_m / R."""
    vm, ms = 9.0, 400.0
    vs = 2.0 * ms / (RHO * math.pi * R**3 * vm)
    assert _harmonic_rates(6.0, vs, 0.0, ms, 0.0, 0.0, 10.0, vm)[1] == pytest.approx(0.0, abs=1e-12)
    rate = _harmonic_rates(6.0, 1.0, 0.0, 0.0, 0.0, 0.0, 10.0, vm)[1]
    assert rate == pytest.approx(-45 * math.pi / 32 * vm / R, rel=1e-12)


def test_three_state_trims_match_uniform_in_axial_flight():
    rotor = load_preset("mccutcheon")
    a = trim(compile_model(rotor, FlightCondition(), SolverSettings(inflow="uniform")))
    b = trim(compile_model(rotor, FlightCondition(), SolverSettings(inflow="three-state")))
    assert b.omega_rad_s == pytest.approx(a.omega_rad_s, rel=1e-9)
    assert b.descent_rate_m_s == pytest.approx(a.descent_rate_m_s, rel=1e-9)


def test_three_state_forward_trim_has_fore_aft_gradient():
    """mu = 0.1: more inflow at the rear of the disc (v_c > 0), of the Pitt-Peters size."""
    m = compile_model(load_preset("mccutcheon"), FlightCondition(mu=0.1), SolverSettings(inflow="three-state"))
    t = trim(m)
    assert t.ok
    vs, vc = t.state[m.inflow_harmonics_slice()]
    print(f"\nthree-state mu=0.1: v0 {t.inflow_m_s:.3f} m/s, v_s {vs:.3f}, v_c {vc:.3f} m/s, "
          f"teeter {t.teeter_amplitude_rad:.4f} rad")
    assert 0.0 < vc < 15 * math.pi / 32 * t.inflow_m_s  # tan(chi/2) < 1
