"""The stable time step against the full linearised mechanics (issue 8).

:func:`amra_core.model.stable_time_step` takes the stiffest undamped structural mode (eigenvalues
of ``M^-1 K``) and the collective lag against the free rotor. The equations also carry
velocity-dependent terms: structural damping ``C``, lag damping, and the Coriolis (gyroscopic)
coupling of the structure and the lag with the rotor speed, ``2 Omega f`` / ``2 Omega f_lag`` (skew),
plus the inertial couplings ``g0`` (structure-rotor speed), ``gl0`` (structure-lag pivot), ``S``
(lag-rotor speed). Here the first-order system ``[[0, P], [-Mf^-1 K P, -Mf^-1 (C + G)]]`` of all of
them (linearised at x = 0, rotor speed free) is built from the compiled arrays, and each eigenvalue's
largest RK4-stable step along its ray is taken with the same margin as the undamped estimate
(1.5 / 2.83 of the imaginary-axis limit). Measured for both presets, all fidelities, GJ 1..1e6 and
rotor speeds 10..52 rad/s: the full system's step is never shorter than the undamped estimate and
at most 0.71 % longer (damping moves the eigenvalues into the left half-plane, where RK4's region
reaches further), so the estimate is kept; this test holds it to that. This is the rule of plain
RK4 (``integrator="rk4"``; the rigid level always); the FEM levels' default Lawson step has its
own rule and check (``test_lawson.py``).
"""
from __future__ import annotations

import itertools

import numpy as np
import pytest

from amra_core.flight import FlightCondition, SolverSettings
from amra_core.model import compile_model, stable_time_step
from amra_core.rotor_io import load_preset
from mechanics_helpers import linear_mechanics

IMAG_LIMIT = 2.0 * np.sqrt(2.0)  #: RK4's stability limit on the imaginary axis
CAP_S = 0.003


def rk4_amplification(z):
    return np.abs(1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24)


def ray_limit(lam: complex) -> float:
    """Largest s with |R(s lam)| <= 1 (RK4) along the ray through ``lam``."""
    d = lam / abs(lam)
    ss = np.linspace(1e-3, 3.0, 3001)
    bad = np.nonzero(rk4_amplification(ss * d) > 1 + 1e-12)[0]
    if len(bad) == 0:
        return np.inf
    lo, hi = ss[max(bad[0] - 1, 0)], ss[bad[0]]
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if rk4_amplification(mid * d) > 1 + 1e-12 else (mid, hi)
    return lo / abs(lam)


def first_order_eigenvalues(model, om: float) -> np.ndarray:
    """Eigenvalues of the linearised mechanics at x = 0, zeta = 0, rotor speed ``om`` (free):
    positions (x, zeta0, zeta1), velocities (x', Omega, zeta0', zeta1')."""
    return np.linalg.eigvals(linear_mechanics(model, om)[0])


def undamped_step(model, om: float) -> float:
    """The structural part of stable_time_step (undamped M^-1 K and the collective lag)."""
    a, s = model.arrays, model.structure
    w2 = np.linalg.eigvals(a.minv @ (a.k0 + om**2 * a.k2)).real
    w = np.sqrt(max(w2.max(), 1.0))
    i_eff = max(s.I_lag - 2 * s.S_lag**2 / s.I_R, 1e-6 * s.I_lag)
    return 1.5 / max(w, np.sqrt((s.k_lag + om**2 * s.k2_lag) / i_eff))


CASES = list(itertools.product(["mccutcheon", "paper-boundary"], ["rigid", "fem-torsion", "fem-coupled"],
                               [1.0, 300.0, 1e6]))


@pytest.mark.parametrize("preset, fidelity, gj", CASES)
def test_velocity_terms_do_not_shorten_the_stable_step(preset, fidelity, gj):
    rotor = load_preset(preset).with_overrides(gj_nm2=gj)
    model = compile_model(rotor, FlightCondition(), SolverSettings(fidelity=fidelity, integrator="rk4"))
    assert np.abs(model.arrays.sf).max() > 0 and np.abs(model.arrays.c).max() > 0  # the terms are there
    for om in (10.0, 40.0, 52.0):
        lam = first_order_eigenvalues(model, om)
        lam_fast = lam[np.abs(lam) > 1.0]
        dt_full = 1.5 / IMAG_LIMIT * min(ray_limit(v) for v in lam_fast)
        dt_undamped = undamped_step(model, om)
        rel = min(dt_full, CAP_S) / min(dt_undamped, CAP_S) - 1.0
        print(f"{preset} {fidelity} GJ {gj:g} {om:g} rad/s: undamped {1e3 * dt_undamped:.4f} ms, "
              f"with C + G {1e3 * dt_full:.4f} ms ({100 * rel:+.2f} %)")
        assert -0.01 <= rel <= 0.01
        # and the step the solver takes keeps every mode of the full system inside RK4's region
        dt = stable_time_step(model, om)
        assert rk4_amplification(lam * dt).max() <= 1.0 + 1e-9


@pytest.mark.parametrize("preset, gj", list(itertools.product(["mccutcheon", "paper-boundary"], [1.0, 300.0, 1e6])))
def test_the_rigid_step_with_exact_wagner_decay_keeps_the_mechanics_stable(preset, gj):
    """The default integrator takes the Wagner states out of RK4's hands in axial flight
    (``test_lawson.py``), so the rigid step grows to the lag mode's limit, capped at 4 ms (3.69 ms
    for McCutcheon); the mechanics, still RK4's, stay inside its region there at every rotor speed."""
    from amra_core.model import STEP_CAP_S
    rotor = load_preset(preset).with_overrides(gj_nm2=gj)
    model = compile_model(rotor, FlightCondition(), SolverSettings(fidelity="rigid"))
    plain = compile_model(rotor, FlightCondition(), SolverSettings(fidelity="rigid", integrator="rk4"))
    for om in (10.0, 40.0, 52.0):
        dt = stable_time_step(model, om)
        assert stable_time_step(plain, om) <= dt <= STEP_CAP_S
        assert dt == pytest.approx(min(undamped_step(model, om), STEP_CAP_S), rel=1e-12)
        assert rk4_amplification(first_order_eigenvalues(model, om) * dt).max() <= 1.0 + 1e-9
