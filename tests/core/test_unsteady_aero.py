"""Unsteady aerodynamics of the time-domain model: Theodorsen via R.T. Jones' two-state Wagner lag
(``amra_core.kernels.wagner``, constants ``amra_core.model.WAGNER_A/B``).

The jitted kernel itself is exercised: its frequency response is measured by marching its state
equations under harmonic forcing and compared with the exact Theodorsen function
``C(k) = H1(k) / (H1(k) + i H0(k))`` (Hankel functions of the second kind, physics-reference §4.4).
model-notes §6 asks for agreement "within 2 %"; R.T. Jones' approximation is itself only that good
(its magnitude error peaks at -2.07 % near k = 1), so the point k = 1 is an expected failure of
the 2 % criterion (documented below), while the kernel reproduces R.T. Jones to round-off.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import hankel2

from amra_core import kernels
from amra_core.airfoil import compile_airfoil, load_airfoil
from amra_core.flight import FlightCondition, SolverSettings
from amra_core.model import WAGNER_A, WAGNER_B, Y_OMEGA, Y_V0, Y_VD, compile_model
from amra_core.rotor_io import load_preset
from amra_core.trim import trim

MAG_TOL = 0.02  #: model-notes §6: "within 2 %"
PHASE_TOL_DEG = 2.0  #: "a few degrees" (R.T. Jones: at most 1.3 deg off over k = 0.05..2)
K_GRID = (0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0, 1.5, 2.0)


def theodorsen_exact(k):
    k = np.asarray(k, dtype=float)
    h1, h0 = hankel2(1, k), hankel2(0, k)
    return h1 / (h1 + 1j * h0)


def kernel_state_space(v: float, c: float):
    """(A, B, C, D) of the kernel, read off by calling it with unit inputs: it is linear in
    (wn, x1, x2), so its outputs at the unit vectors are the columns of the matrices."""
    out_u, d1_u, d2_u = kernels.wagner(1.0, v, c, 0.0, 0.0)
    out_1, d1_1, d2_1 = kernels.wagner(0.0, v, c, 1.0, 0.0)
    out_2, d1_2, d2_2 = kernels.wagner(0.0, v, c, 0.0, 1.0)
    A = np.array([[d1_1, d1_2], [d2_1, d2_2]])
    B = np.array([d1_u, d2_u])
    C = np.array([out_1, out_2])
    return A, B, C, out_u


def kernel_response(k, v=1.0, c=2.0):
    """Transfer function of the kernel at reduced frequency k = omega c / (2 v)."""
    A, B, C, D = kernel_state_space(v, c)
    w = 2.0 * v * np.atleast_1d(k) / c
    return np.array([D + C @ np.linalg.solve(1j * wi * np.eye(2) - A, B) for wi in w])


def march_harmonic(k: float, v: float = 1.0, c: float = 2.0) -> complex:
    """Drive the kernel with wn = sin(omega t), march its two states with RK4 until the transient
    has died out, and fit the steady output to a sin + b cos: returns the complex gain a + i b."""
    w = 2.0 * v * k / c
    period = 2 * math.pi / w
    dt = min(0.05, period / 400.0) * (c / (2.0 * v))
    rate_min = 2.0 * v / c * WAGNER_B[0]
    t_settle = 12.0 / rate_min  # slowest lag state: e^-12 of its transient left
    n_settle = int(math.ceil(t_settle / dt))
    n_fit = int(round(2 * period / dt))
    x1 = x2 = 0.0
    t = 0.0
    out = np.empty(n_fit)
    tt = np.empty(n_fit)

    def f(t, x1, x2):
        _, d1, d2 = kernels.wagner(math.sin(w * t), v, c, x1, x2)
        return d1, d2

    for n in range(n_settle + n_fit):
        if n >= n_settle:
            tt[n - n_settle] = t
            out[n - n_settle] = kernels.wagner(math.sin(w * t), v, c, x1, x2)[0]
        a1, a2 = f(t, x1, x2)
        b1, b2 = f(t + dt / 2, x1 + dt / 2 * a1, x2 + dt / 2 * a2)
        c1, c2 = f(t + dt / 2, x1 + dt / 2 * b1, x2 + dt / 2 * b2)
        e1, e2 = f(t + dt, x1 + dt * c1, x2 + dt * c2)
        x1 += dt / 6 * (a1 + 2 * b1 + 2 * c1 + e1)
        x2 += dt / 6 * (a2 + 2 * b2 + 2 * c2 + e2)
        t += dt
    M = np.column_stack([np.sin(w * tt), np.cos(w * tt)])
    a, b = np.linalg.lstsq(M, out, rcond=None)[0]
    return complex(a, b)  # sin(wt) -> Re{(a + i b) e^{i wt}} / i  ==  a sin + b cos


# ---------------------------------------------------------------------------------------------
# the kernel's state equations
# ---------------------------------------------------------------------------------------------
def test_kernel_constants_are_rt_jones():
    assert WAGNER_A == (0.165, 0.335)
    assert WAGNER_B == (0.0455, 0.3)
    A, B, C, D = kernel_state_space(1.0, 2.0)  # 2 v / c = 1: time is semichords travelled
    np.testing.assert_allclose(np.sort(np.linalg.eigvals(A).real), [-0.3, -0.0455], rtol=1e-14)
    assert D == pytest.approx(1.0 - 0.165 - 0.335, abs=1e-15)  # C(inf) = 1/2: the instant response


def test_kernel_is_linear_and_scales_with_semichords():
    rng = np.random.default_rng(3)
    for _ in range(20):
        wn, x1, x2, a = rng.normal(size=4)
        v, c = rng.uniform(20, 200), rng.uniform(0.1, 0.5)
        r = np.array(kernels.wagner(wn, v, c, x1, x2))
        r2 = np.array(kernels.wagner(a * wn, v, c, a * x1, a * x2))
        np.testing.assert_allclose(r2, a * r, rtol=1e-12, atol=1e-12)
    # the same reduced frequency gives the same response at any speed and chord
    np.testing.assert_allclose(kernel_response(K_GRID, v=150.0, c=0.197), kernel_response(K_GRID), rtol=1e-12)


def test_kernel_transfer_function_is_rt_jones():
    k = np.array(K_GRID)
    rtj = 1 - 0.165 * k / (k - 0.0455j) - 0.335 * k / (k - 0.3j)
    np.testing.assert_allclose(kernel_response(k, v=80.0, c=0.2), rtj, rtol=1e-12)


def test_kernel_limits_and_peak_lag():
    """C(0) = 1 and C(inf) = 1/2; the largest phase lag lies near k = 0.2 with Im C ~ -0.189
    (physics-reference §4.4)."""
    assert kernel_response(1e-9)[0] == pytest.approx(1.0, abs=1e-7)
    assert kernel_response(1e6)[0] == pytest.approx(0.5, abs=1e-6)
    k = np.linspace(0.02, 2.0, 2000)
    h = kernel_response(k)
    k_min_im = k[np.argmin(h.imag)]
    exact = theodorsen_exact(k)
    print(f"min Im C: kernel {h.imag.min():.4f} at k = {k_min_im:.3f}; exact {exact.imag.min():.4f} "
          f"at k = {k[np.argmin(exact.imag)]:.3f}")
    assert 0.1 <= k_min_im <= 0.3
    assert h.imag.min() == pytest.approx(exact.imag.min(), abs=0.01)


_K_PARAMS = [
    pytest.param(k, marks=pytest.mark.xfail(strict=True, reason=(
        "R.T. Jones' approximation itself: |C| 0.5373 vs exact 0.5486 at k = 1 (-2.07 %, model-notes "
        "§6 asks 2 %); the kernel equals R.T. Jones to 1e-12 (test_kernel_transfer_function_is_rt_jones), "
        "phase error there -0.16 deg")))
    if k == 1.0 else k for k in K_GRID]


@pytest.mark.parametrize("k", _K_PARAMS)
def test_marched_frequency_response_vs_exact_theodorsen(k):
    gain = march_harmonic(k)
    # the marched response is the kernel's own transfer function (RK4 converged)
    assert gain == pytest.approx(complex(kernel_response(k)[0]), abs=2e-5)
    exact = complex(theodorsen_exact(k))
    mag_err = abs(gain) / abs(exact) - 1.0
    ph_err = math.degrees(np.angle(gain) - np.angle(exact))
    print(f"k = {k}: marched C = {gain:.4f}, exact {exact:.4f}; |C| error {100 * mag_err:+.2f} %, "
          f"phase error {ph_err:+.2f} deg")
    assert abs(ph_err) <= PHASE_TOL_DEG
    assert abs(mag_err) <= MAG_TOL


def test_rotor_band_within_two_percent():
    """Where rotor blades live (1/rev k ~ 0.03 to torsion k ~ 0.2, physics-reference §4.4) the
    complex error |C_model - C| / |C| stays below 2 %."""
    k = np.linspace(0.02, 0.25, 47)
    err = np.abs(kernel_response(k) - theodorsen_exact(k)) / np.abs(theodorsen_exact(k))
    print(f"max complex error over k = 0.02..0.25: {100 * err.max():.2f} % at k = {k[np.argmax(err)]:.3f}")
    assert err.max() < 0.02


# ---------------------------------------------------------------------------------------------
# the section loads use the lagged normal velocity
# ---------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def airfoil():
    return compile_airfoil(load_airfoil("naca0012_critzos"))


def _station(af, ut, up, theta, thd, x1, x2, theo, c=0.197, xea=0.3):
    return kernels.station_aero(ut, up, theta, thd, c, xea, 0.25, 2 * xea - 1, x1, x2, theo, 1.225, 340.3,
                                af.alpha0_rad, af.dalpha_rad, af.cl, af.cd, af.cm)


def _steady_states(ut, up, theta, thd, c=0.197, xea=0.3):
    """Steady Wagner states A_k * w_n for the section (w_n as documented in station_aero)."""
    v = math.hypot(ut, up)
    up34 = up + thd * (0.75 - xea) * c
    wn = v * (math.sin(theta) * ut + math.cos(theta) * up34) / math.hypot(ut, up34)
    return WAGNER_A[0] * wn, WAGNER_A[1] * wn


@pytest.mark.parametrize("ut, up, theta_deg, thd", [
    (100.0, 2.0, 2.5, 0.0), (60.0, -3.0, 4.0, 1.5), (20.0, 4.0, 8.0, -2.0), (140.0, 0.5, 1.0, 5.0),
    (-30.0, 3.0, 2.5, 0.0),  # reverse flow
])
def test_steady_wagner_states_give_quasi_steady_loads(airfoil, ut, up, theta_deg, thd):
    """At the steady state x_k = A_k w_n the lag is complete (C = 1): Theodorsen loads equal the
    quasi-steady ones and the states do not move."""
    th = math.radians(theta_deg)
    x1, x2 = _steady_states(ut, up, th, thd)
    qs = _station(airfoil, ut, up, th, thd, 0.0, 0.0, False)
    un = _station(airfoil, ut, up, th, thd, x1, x2, True)
    np.testing.assert_allclose(un[:3], qs[:3], rtol=1e-9, atol=1e-9)
    assert abs(un[3]) < 1e-9 and abs(un[4]) < 1e-9


def test_indicial_lift_follows_wagner(airfoil):
    """A step to 1 deg at t = 0 (lag states zero): the section lift, marched with the states'
    own derivatives from station_aero, builds up as Wagner's phi(s) = 1 - 0.165 e^-0.0455s -
    0.335 e^-0.3s, s = 2 V t / c. (The table's lift slope varies 0.5 % between 0.5 and 1 deg.)"""
    V, c, th = 100.0, 0.197, math.radians(1.0)
    lift_qs = _station(airfoil, V, 0.0, th, 0.0, 0.0, 0.0, False)[0]
    ds = 0.02
    dt = ds * c / (2 * V)
    x1 = x2 = 0.0
    s_check = {0.0: None, 1.0: None, 5.0: None, 20.0: None, 60.0: None, 200.0: None}
    n_end = int(round(200.0 / ds))
    for n in range(n_end + 1):
        s = n * ds
        for sc in s_check:
            if abs(s - sc) < ds / 2:
                s_check[sc] = _station(airfoil, V, 0.0, th, 0.0, x1, x2, True)[0] / lift_qs
        _, _, _, d1, d2 = _station(airfoil, V, 0.0, th, 0.0, x1, x2, True)
        # the states' equations are linear with constant input here: advance them exactly (RK4 not needed)
        wn = V * math.sin(th)
        r1, r2 = 2 * V / c * WAGNER_B[0], 2 * V / c * WAGNER_B[1]
        assert d1 == pytest.approx(r1 * (WAGNER_A[0] * wn - x1), rel=1e-9, abs=1e-9)  # v has a +1e-9 guard
        assert d2 == pytest.approx(r2 * (WAGNER_A[1] * wn - x2), rel=1e-9, abs=1e-9)
        x1 = WAGNER_A[0] * wn + (x1 - WAGNER_A[0] * wn) * math.exp(-r1 * dt)
        x2 = WAGNER_A[1] * wn + (x2 - WAGNER_A[1] * wn) * math.exp(-r2 * dt)
    for s, ratio in s_check.items():
        phi = 1 - 0.165 * math.exp(-0.0455 * s) - 0.335 * math.exp(-0.3 * s)
        print(f"s = {s:5.1f}: lift / steady lift {ratio:.4f}, Wagner phi {phi:.4f}")
        assert ratio == pytest.approx(phi, rel=0.01)


# ---------------------------------------------------------------------------------------------
# trims: Theodorsen and quasi-steady agree in steady flight
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("fidelity", ["rigid", "fem-coupled"])
def test_axial_trim_theodorsen_equals_quasi_steady(mccutcheon, fidelity):
    res = {}
    for aero in ("quasi-steady", "theodorsen"):
        res[aero] = trim(compile_model(mccutcheon, FlightCondition(), SolverSettings(fidelity=fidelity, aero=aero)))
        assert res[aero].ok, res[aero].reason
    qs, th = res["quasi-steady"], res["theodorsen"]
    print(f"{fidelity}: omega qs {qs.omega_rad_s:.6f} theo {th.omega_rad_s:.6f} rad/s; descent qs "
          f"{qs.descent_rate_m_s:.6f} theo {th.descent_rate_m_s:.6f} m/s")
    assert th.omega_rad_s == pytest.approx(qs.omega_rad_s, rel=1e-6)
    assert th.descent_rate_m_s == pytest.approx(qs.descent_rate_m_s, rel=1e-6)
    assert th.tip_twist_rad == pytest.approx(qs.tip_twist_rad, rel=1e-6, abs=1e-9)

    # the Theodorsen trim is an equilibrium of the full unsteady model (Wagner states included)
    m = th.model.with_controls(quasi_static=False)
    assert m.arrays.p[kernels.P_AERO] == 1.0
    dy = np.zeros(m.n_y)
    loads = np.zeros(8)
    kernels.evaluate(th.state.copy(), m.arrays, dy, loads)
    wag = dy[m.aero_slice()]
    print(f"  |dy|: omega {abs(dy[Y_OMEGA]):.2e}, descent {abs(dy[Y_VD]):.2e}, inflow {abs(dy[Y_V0]):.2e}, "
          f"wagner max {np.abs(wag).max():.2e}, structure max {np.abs(dy[m.xd_slice()]).max():.2e}")
    assert abs(dy[Y_OMEGA]) < 1e-8  # rad/s^2
    assert abs(dy[Y_VD]) < 1e-7 and abs(dy[Y_V0]) < 1e-7  # m/s^2
    assert np.abs(wag).max() < 1e-8  # m/s^2: C = 1 at steady state
    assert np.abs(dy[m.xd_slice()]).max() < 1e-5
    # the Wagner states sit at A_k w_n: total share of the steady normal velocity = 0.5
    st = th.state[m.aero_slice()].reshape(2, -1, 2)
    np.testing.assert_allclose(st[..., 1] / st[..., 0], WAGNER_A[1] / WAGNER_A[0], rtol=1e-12)


def test_forward_trim_theodorsen_close_to_quasi_steady(mccutcheon):
    """mu = 0.1: the 1/rev forcing sits at k ~ 0.03, where C(k) is close to 1, so the periodic trims
    differ only slightly."""
    res = {aero: trim(compile_model(mccutcheon, FlightCondition(mu=0.1), SolverSettings(aero=aero)))
           for aero in ("quasi-steady", "theodorsen")}
    qs, th = res["quasi-steady"], res["theodorsen"]
    assert qs.ok and th.ok
    print(f"mu 0.1 rigid: omega qs {qs.omega_rad_s:.4f} theo {th.omega_rad_s:.4f}; descent qs "
          f"{qs.descent_rate_m_s:.4f} theo {th.descent_rate_m_s:.4f}; teeter qs {qs.teeter_amplitude_rad:.5f} "
          f"theo {th.teeter_amplitude_rad:.5f}")
    assert th.omega_rad_s == pytest.approx(qs.omega_rad_s, rel=0.01)
    assert th.descent_rate_m_s == pytest.approx(qs.descent_rate_m_s, rel=0.01)
    assert th.teeter_amplitude_rad == pytest.approx(qs.teeter_amplitude_rad, rel=0.05)
