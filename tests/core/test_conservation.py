"""Conservation checks of the rotor mechanics (docs/model-equations.md).

With the aerodynamics switched off (``compile_model(..., vacuum=True)``: no air loads, no apparent
mass, inflow and descent frozen) and no structural damping, the model is the Lagrangian system

    L = 1/2 x'^T M x' + 1/2 sum I_b(x) zeta_b'^2 + 1/2 Omega^2 J(x, zeta)
        + Omega (sum S_b(x) zeta_b' + g(x)^T x') - 1/2 x^T K0 x - 1/2 k_lag |zeta|^2,

with ``J = I_R + 2 f^T x - x^T K2 x + 2 f_lag sum zeta - k2_lag |zeta|^2``, ``g = g0 + H x`` and
the coned blade's lag coupling ``S_b = S - x^T S2_b x/2`` and inertia ``I_b = I_z - x^T I2_b x``. The azimuth is
cyclic and L does not depend on time, so with the rotor speed free

* the total mechanical energy ``E = T + V`` (L is quadratic in the velocities) and
* the angular momentum about the shaft ``h = dL/dOmega = Omega J + sum S_b zeta_b' + g^T x'``

are conserved exactly by the equations of motion and to RK4's accuracy by :func:`kernels.advance`.
The blades are started flapping, twisting, teetering and lagging, with a CG offset, a built-in
incidence and twist, so every term of L is exercised. Each test also shows that it fails when
one term of the kernel is removed or has its sign flipped (``_mutated``), and
:func:`test_polar_inertia_and_angular_momentum_match_exact_kinematics` checks J and g themselves
against the exact kinematics of the mass particles of a rigid blade.
"""
import dataclasses
import math

import numpy as np
import pytest

from amra_core import kernel_guard, kernels
from amra_core.flight import FlightCondition, SolverSettings
from amra_core.layout import with_coordinate_products
from amra_core.model import (P_IR, P_SLAG, Y_OMEGA, Y_ZETA0, Y_ZETAD0, angular_momentum, compile_model,
                             lag_inertias, mechanical_energy, polar_inertia, stable_time_step)
from amra_core.rotor import BladeStations, Rotor
from amra_core.rotor_io import load_preset
from amra_core.shapes import make_mesh
from amra_core.structure import K_FLAP_SPRING, K_TORSION_SPRING, assemble, cyclic_flap_equivalence

FIDELITIES = ("rigid", "fem-torsion", "fem-coupled")
OMEGA0 = 40.0  # rad/s
N_REV = 20


def flapping_rotor():
    """McCutcheon blade with EA 32 %, CG 40 % (e = 0.08 c aft), GJ 300, 2.5 deg incidence plus a
    -3 deg linear twist, no structural damping."""
    rot = load_preset("mccutcheon").with_overrides(x_cg=0.40, x_ea=0.32, gj_nm2=300.0)
    st = rot.stations
    twist = tuple(math.radians(-3.0) * (r - st.r_m[0]) / (st.r_m[-1] - st.r_m[0]) for r in st.r_m)
    return dataclasses.replace(rot, structural_damping_ratio=0.0,
                               stations=dataclasses.replace(st, twist_rad=twist))


def vacuum_model(fidelity, rotor=None):
    return compile_model(rotor or flapping_rotor(), FlightCondition(), SolverSettings(fidelity=fidelity),
                         vacuum=True)


def kicked_state(model):
    """Rotor at 40 rad/s with smooth initial deflections: teeter 0.03 rad, blade 0 flap slope
    0.05 rad and tip twist 0.05 rad, blade 1 tip twist -0.02 rad, lag 2 mrad, flap rate."""
    s = model.structure
    mesh = s.mesh
    nodes = np.asarray(mesh.nodes_m)
    r0, L = mesh.root_m, mesh.tip_m - mesh.root_m
    x = np.zeros(s.n); xd = np.zeros(s.n)
    x[0] = 0.03
    for b, (slope, tip_twist) in enumerate(((0.05, 0.05), (0.0, -0.02))):
        q0 = 1 + b * mesh.n_q
        if mesh.fidelity == "fem-coupled":  # nodal (w, w') of w = slope (r - r0)
            x[q0:q0 + mesh.n_flap:2] = slope * (nodes[1:] - r0)
            x[q0 + 1:q0 + mesh.n_flap:2] = slope
        else:
            x[q0] = slope
        t = q0 + mesh.n_flap + np.arange(mesh.n_torsion)
        x[t] = tip_twist if mesh.fidelity == "rigid" else tip_twist * (nodes[1:] - r0) / L
        xd[q0] = 0.5 if mesh.fidelity != "fem-coupled" else 0.5 * (nodes[1] - r0)
    y = np.zeros(model.n_y)
    y[Y_OMEGA] = OMEGA0
    y[Y_ZETA0] = 0.002
    model.set_physical(y, x, xd)
    return y


def march(model, y0, dt_s, n_rev=N_REV, arrays=None):
    """States every 10 steps over ``n_rev`` revolutions of the initial rotor speed."""
    t_end = n_rev * 2.0 * math.pi / OMEGA0
    n = int(round(t_end / dt_s))
    y = y0.copy()
    rows = n // 10 + 2
    hist = np.zeros((rows, kernels.N_HIST)); states = np.zeros((rows, model.n_y))
    done, k, status = kernel_guard.advance(y, 0.0, t_end / n, n, 10, arrays or model.arrays, hist, states, 1.0)
    assert status == 0 and done == n
    return np.vstack([states[:k], y])


def _mutated(model, **changes):
    """The model's arrays with some terms changed (to show that a test detects a missing term)."""
    a = model.arrays
    return with_coordinate_products(a._replace(**{k: v(a) for k, v in changes.items()}))


def energy_drift(model, states):
    e = np.array([mechanical_energy(model, s) for s in states])
    return np.abs(e - e[0]).max()


def structural_energy(model, y):
    """Energy above that of the undeflected rotor spinning at the same angular momentum [J]: the
    scale of what the flap, twist and lag motion exchange."""
    h = angular_momentum(model, y)
    return mechanical_energy(model, y) - 0.5 * h**2 / model.arrays.p[P_IR]


@pytest.fixture(scope="module", params=FIDELITIES)
def case(request):
    model = vacuum_model(request.param)
    y0 = kicked_state(model)
    dt = stable_time_step(model, OMEGA0)
    return model, y0, dt


def test_energy_conserved_to_rk4_order(case):
    """Free rotor in vacuo, 20 revolutions: max |E(t) - E(0)| at dt/4 and dt/8 (dt the solver's
    stable step), relative to the exchanged structural energy. RK4's energy error falls at
    order >= 4 (5 for the linear oscillator part, whose RK4 amplification error is (w dt)^6/144
    per step); anything below order 3.5 or a drift above 2e-6 of the structural energy fails."""
    model, y0, dt = case
    drifts = [energy_drift(model, march(model, y0, dt / k)) for k in (8, 16)]
    e_s = structural_energy(model, y0)
    order = math.log2(drifts[0] / drifts[1])
    print(f"\n{model.settings.fidelity}: E_struct {e_s:.2f} J, drift over {N_REV} rev "
          f"{drifts[0]:.3e} J (dt/8), {drifts[1]:.3e} J (dt/16) = {drifts[1] / N_REV:.2e} J/rev, "
          f"order {order:.2f}")
    assert e_s > 1.0
    assert drifts[1] <= 2e-6 * e_s, drifts
    assert order >= 3.5


def test_angular_momentum_conserved_and_rotor_speed_follows_coning(case):
    """Zero aerodynamic torque: h = Omega J + S sum zeta' + g^T x' stays constant while the
    rotor speed swings by ~1 % as the blades flap, twist and lag (the Coriolis terms). The
    constant-inertia momentum I_R Omega + S sum zeta' of the old rotor-speed equation varies by
    orders of magnitude more than the tolerance, so a model without them cannot pass."""
    model, y0, dt = case
    states = march(model, y0, dt / 8)
    h = np.array([angular_momentum(model, s) for s in states])
    drift = np.abs(h / h[0] - 1.0).max()
    om = states[:, Y_OMEGA]
    p = model.arrays.p
    h_rigid = p[P_IR] * om + p[P_SLAG] * (states[:, Y_ZETAD0] + states[:, Y_ZETAD0 + 1])
    rigid_var = np.abs(h_rigid / h[0] - 1.0).max()
    print(f"\n{model.settings.fidelity}: max |dh/h| {drift:.2e}; Omega {om.min():.4f}..{om.max():.4f} "
          f"rad/s; constant-inertia momentum varies by {rigid_var:.2e}")
    assert drift <= 1e-7
    assert (om.max() - om.min()) / OMEGA0 >= 1e-3
    assert rigid_var >= 1e4 * 1e-7


@pytest.mark.parametrize("term, change", [
    ("static pitch load with the wrong sign", dict(sf=lambda a: -a.sf)),
    ("static pitch load missing", dict(sf=lambda a: 0.0 * a.sf)),
    ("gyroscopic H missing", dict(gyh=lambda a: 0.0 * a.gyh, ugyh=lambda a: 0.0 * a.ugyh,
                                  glh=lambda a: 0.0 * a.glh, uglh=lambda a: 0.0 * a.uglh)),
    ("gyroscopic H with the wrong sign", dict(gyh=lambda a: -a.gyh, ugyh=lambda a: -a.ugyh,
                                              glh=lambda a: -a.glh, uglh=lambda a: -a.uglh)),
    ("lag-pivot coupling of H missing", dict(glh=lambda a: 0.0 * a.glh, uglh=lambda a: 0.0 * a.uglh)),
    ("lag-pivot coupling gl0 missing", dict(gl0=lambda a: 0.0 * a.gl0, ugl0=lambda a: 0.0 * a.ugl0)),
    ("lag-pivot coupling gl0 with the wrong sign", dict(gl0=lambda a: -a.gl0, ugl0=lambda a: -a.ugl0)),
    ("gyroscopic g0 missing", dict(gy0=lambda a: 0.0 * a.gy0, ugy0=lambda a: 0.0 * a.ugy0)),
    ("flap-lag coupling S2 missing", dict(ls2=lambda a: 0.0 * a.ls2)),
    ("flap-lag coupling S2 with the wrong sign", dict(ls2=lambda a: -a.ls2)),
    ("coned lag inertia I2 missing", dict(li2=lambda a: 0.0 * a.li2)),
])
@pytest.mark.parametrize("fidelity", ["rigid", "fem-coupled"])
def test_conservation_detects_a_missing_or_wrong_signed_term(fidelity, term, change):
    """The same march with one term of the kernel's equations changed: energy or angular
    momentum (computed with the correct model) drifts by at least 100 times as much as with the
    correct kernel at the same step."""
    model = vacuum_model(fidelity)
    y0 = kicked_state(model)
    dt = stable_time_step(model, OMEGA0) / 16

    def drifts(arrays):
        states = march(model, y0, dt, n_rev=5, arrays=arrays)
        h = np.array([angular_momentum(model, s) for s in states])
        return energy_drift(model, states) / structural_energy(model, y0), np.abs(h / h[0] - 1.0).max()

    e_ok, h_ok = drifts(model.arrays)
    e_rel, h_rel = drifts(_mutated(model, **change))
    assert e_ok <= 1e-6 and h_ok <= 1e-8
    assert e_rel >= 100 * max(e_ok, 1e-8) or h_rel >= 100 * max(h_ok, 1e-10), (term, e_rel, h_rel, e_ok, h_ok)


# ---------------------------------------------------------------------------------------------
# the Lagrangian's polar inertia and angular momentum against exact particle kinematics
# ---------------------------------------------------------------------------------------------
def _ry(a):
    c, s = np.cos(a), np.sin(a)  # x -> (c, 0, s): flap up
    return np.array([[c, 0 * c, -s], [0 * c, 1 + 0 * c, 0 * c], [s, 0 * c, c]])


def _rz(a):
    c, s = np.cos(a), np.sin(a)  # x -> (c, s, 0): lead, in the direction of rotation
    return np.array([[c, -s, 0 * c], [s, c, 0 * c], [0 * c, 0 * c, 1 + 0 * c]])


def _particles(rotor, mesh):
    """Two particles per quadrature point, chordwise at e +- sqrt(I/m - e^2) aft of the EA, so
    mass, first and second chordwise moments equal the section's m, m e and I_ea."""
    from amra_core.structure import quadrature
    st = rotor.stations
    r, w = quadrature(rotor, mesh)
    m = st.at("mass_kg_m", r) * w
    e = (st.at("x_cg", r) - st.at("x_ea", r)) * st.at("chord_m", r)
    d = np.sqrt(st.at("torsional_inertia_kg_m", r) / st.at("mass_kg_m", r) - e**2)
    th0 = rotor.incidence_rad + st.at("twist_rad", r)
    return (np.concatenate([r, r]), np.concatenate([e + d, e - d]), np.concatenate([m, m]) / 2,
            np.concatenate([th0, th0]))


def _positions(rotor, mesh, x, zeta):
    """Exact positions (3, n) of both blades' particles (each in its own rotating frame) of a
    rotor with rigid flap about r0 (rigid, fem-torsion), teeter at the axis, lag about r0."""
    r, eta, m, th0 = _particles(rotor, mesh)
    r0, nq = mesh.root_m, mesh.n_q
    out = []
    for b, sgn in ((0, 1.0), (1, -1.0)):
        q = x[1 + b * nq: 1 + (b + 1) * nq]
        _, _, _, pt, _ = mesh.shapes(r)
        theta = th0 + pt.astype(x.dtype) @ q
        chord = np.array([0 * theta, -np.cos(theta), -np.sin(theta)])
        local = np.array([r - r0, 0 * r, 0 * r]) + eta * chord
        p = _rz(zeta[b]) @ (_ry(q[0]) @ local)
        p = _ry(sgn * x[0]) @ (p + np.array([[r0], [0.0], [0.0]]))
        out.append(p)
    return np.concatenate(out, axis=1), np.concatenate([m, m])


def _exact_j_and_g(rotor, mesh, x, xd, zeta, zetad):
    """Polar inertia sum m (X^2 + Y^2) and in-plane angular momentum sum m (X Y' - Y X') of the
    particles; velocities by complex-step differentiation along (x', zeta')."""
    h = 1e-30
    p, m = _positions(rotor, mesh, x.astype(complex), zeta.astype(complex))
    pc, _ = _positions(rotor, mesh, x + 1j * h * xd, zeta + 1j * h * zetad)
    v = pc.imag / h
    p = p.real
    return float(np.sum(m * (p[0]**2 + p[1]**2))), float(np.sum(m * (p[0] * v[1] - p[1] * v[0])))


def _pitching_cg_momentum(rotor, mesh, x, xd):
    """``sum_b int m e r theta_e theta_e'``: the in-plane momentum of the pitching CG that the
    model leaves out on purpose (structure.blade_pitch_and_gyro, docs/model-equations.md)."""
    from amra_core.structure import quadrature
    st = rotor.stations
    r, w = quadrature(rotor, mesh)
    me = st.at("mass_kg_m", r) * (st.at("x_cg", r) - st.at("x_ea", r)) * st.at("chord_m", r)
    _, _, _, pt, _ = mesh.shapes(r)
    nq = mesh.n_q
    total = 0.0
    for b in range(2):
        q, qd = x[1 + b * nq:1 + (b + 1) * nq], xd[1 + b * nq:1 + (b + 1) * nq]
        total += float(np.sum(w * me * r * (pt @ q) * (pt @ qd)))
    return total


@pytest.mark.parametrize("fidelity", ["rigid", "fem-torsion"])
def test_polar_inertia_and_angular_momentum_match_exact_kinematics(fidelity):
    """J(x) - J(0) and G = g(x)^T x' + S sum zeta' of the model against the exact kinematics of
    the blade particles, with every deflection and the built-in pitch scaled by eps: the model
    keeps everything to second order, so the error falls as eps^3 (ratio 8 per halving) while
    the terms themselves fall as eps^2. A missing or wrong-signed term of f, K2, g0, H, k2_lag or
    S_lag leaves an eps^2 error and fails. (No trapeze: rigid particles carry no axial strain. The
    one second-order term the model leaves out on purpose, the pitching CG's in-plane momentum
    int m e r theta_e theta_e', is added to the model's side: :func:`_pitching_cg_momentum`.)"""
    base = flapping_rotor()
    mesh = make_mesh(fidelity, base.root_cutout_m, base.radius_m, 6)
    rng = np.random.default_rng(3)
    n = 1 + 2 * mesh.n_q
    xb, xdb, zb, zdb = rng.normal(size=n), rng.normal(size=n), rng.normal(size=2), rng.normal(size=2)
    errs = []
    for eps in (0.02, 0.01, 0.005):
        st = base.stations
        rot = dataclasses.replace(base, incidence_rad=eps * 2.0, hub_teeter_inertia_kg_m2=0.0,
                                  stations=dataclasses.replace(
                                      st, twist_rad=tuple(-eps * (r - st.r_m[0]) for r in st.r_m)))
        s = assemble(rot, mesh, trapeze=False)
        x, xd, z, zd = eps * xb, eps * xdb, eps * zb, eps * zdb
        j0, _ = _exact_j_and_g(rot, mesh, 0 * x, 0 * x, 0 * z, 0 * z)
        j, g = _exact_j_and_g(rot, mesh, x, xd, z, zd)
        # the equivalent rigid blade's hub is a bar along the blades with the effective teeter
        # inertia (derived, not the estimate 0): a tilt beta turns its polar inertia I into I cos^2 beta
        i_hub = cyclic_flap_equivalence(rot).teeter_inertia_kg_m2
        j += i_hub * (math.cos(x[0]) ** 2 - 1.0)
        dj_model = 2 * s.f @ x - x @ s.K2 @ x + 2 * s.f_lag * z.sum() - s.k2_lag * (z @ z)
        g_model = (s.g0 + s.H @ x) @ xd + s.S_lag * zd.sum() + _pitching_cg_momentum(rot, mesh, x, xd)
        errs.append((abs(j - j0 - dj_model), abs(g - g_model), abs(dj_model), abs(g_model)))
    for (ej1, eg1, dj, g), (ej2, eg2, _, _) in zip(errs[:-1], errs[1:]):
        assert ej1 / ej2 >= 6.0 and eg1 / eg2 >= 6.0, errs
        assert ej1 <= 0.05 * dj and eg1 <= 0.05 * g, errs


# ---------------------------------------------------------------------------------------------
# static twist under rotation: hand calculation for a rigid blade
# ---------------------------------------------------------------------------------------------
def uniform_blade(x_cg, incidence_deg=4.0, twist_deg=-6.0):
    two = lambda v: (v, v)  # noqa: E731
    r0, R = 0.5, 4.0
    st = BladeStations(r_m=(r0, R), chord_m=two(0.2), twist_rad=(0.0, math.radians(twist_deg)),
                       mass_kg_m=two(3.0), torsional_inertia_kg_m=two(0.01), gj_nm2=two(200.0),
                       ei_flap_nm2=two(1200.0), ei_lag_nm2=two(9.0e4), x_ea=two(0.3), x_cg=two(x_cg),
                       x_ac=two(0.25))
    return Rotor(name="uniform-static", radius_m=R, root_cutout_m=r0, n_blades=2,
                 incidence_rad=math.radians(incidence_deg), vehicle_mass_kg=300.0,
                 hub_teeter_inertia_kg_m2=0.0, hub_polar_inertia_kg_m2=0.0, stations=st)


@pytest.mark.parametrize("x_cg", [0.3, 0.38, 0.22])
def test_static_twist_rigid_blade_hand_calculation(x_cg):
    """Uniform rigid blade on root springs (r0 = 0.5 m, R = 4 m, L = 3.5 m, m = 3 kg/m,
    I = 0.01 kg m, EI = 1200, GJ = 200), pitch theta0(r) = theta_i + theta_t (r - r0)/L, CG
    e = (x_cg - x_ea) c aft of the EA, in vacuo at Omega = 40 rad/s. Per blade, flap angle b
    about r0 and uniform twist t; the potential of the Lagrangian's rigid-blade J gives

        [k_b + W^2 K_ww,  -W^2 S_e ] [b]         [ F_w ]      K_ww = int_r0^R T/W^2 dr
        [-W^2 S_e,   k_t + W^2 I L ] [t] = W^2   [ F_t ],     = m/2 (R^2 L - (R^3 - r0^3)/3),

    S_e = int m e r dr = m e (R^2 - r0^2)/2, F_w = int m e r theta0 dr, F_t = -int I theta0 dr
    = -I L (theta_i + theta_t/2), k_b = 1.8751^4/3 EI/L, k_t = (pi/2)^2 GJ/L. By Cramer's rule
    t = W^2 (A F_t + B F_w)/(A C - B^2) with A = k_b + W^2 K_ww, B = W^2 S_e, C = k_t + W^2 I L;
    for e = 0 this is the propeller moment alone, t = -W^2 I L theta0_mean / (k_t + W^2 I L).
    The teeter row balances by symmetry (t, b equal on both blades, teeter 0). The CG offset also
    leads each blade by the static lag angle W^2 r0 m e L / (k_lag + W^2 k2_lag) (the
    centrifugal force on a CG behind the lag pivot line). The kernel's accelerations (flap,
    twist, lag and rotor speed) must vanish there, and not at zero deflection."""
    rot = uniform_blade(x_cg)
    W, r0, R = OMEGA0, rot.root_cutout_m, rot.radius_m
    L = R - r0
    m, I, c = 3.0, 0.01, 0.2
    e = (x_cg - 0.3) * c
    ti, tt = rot.incidence_rad, math.radians(-6.0)
    K_ww = m / 2 * (R**2 * L - (R**3 - r0**3) / 3)
    S_e = m * e * (R**2 - r0**2) / 2
    # int r theta0 dr with theta0 = ti + tt (r - r0)/L
    int_r_th = ti * (R**2 - r0**2) / 2 + tt / L * ((R**3 - r0**3) / 3 - r0 * (R**2 - r0**2) / 2)
    F_w = m * e * int_r_th
    F_t = -I * L * (ti + tt / 2)
    A = K_FLAP_SPRING * 1200.0 / L + W**2 * K_ww
    B = W**2 * S_e
    C = K_TORSION_SPRING * 200.0 / L + W**2 * I * L
    det = A * C - B * B
    twist = W**2 * (A * F_t + B * F_w) / det
    flap = W**2 * (C * F_w + B * F_t) / det
    print(f"\nx_cg {x_cg}: static twist {math.degrees(twist):+.4f} deg, flap {math.degrees(flap):+.4f} deg")

    model = compile_model(rot, FlightCondition(), SolverSettings(fidelity="rigid"), vacuum=True)
    y = np.zeros(model.n_y); y[Y_OMEGA] = W
    dy, loads = np.zeros(model.n_y), np.zeros(8)
    kernel_guard.evaluate(y, model.arrays, dy, loads)
    scale = np.abs(dy[model.xd_slice()]).max()
    assert scale > 1.0  # the static loads act at zero deflection
    x = np.zeros(model.structure.n)
    x[[1, 3]] = flap
    x[[2, 4]] = twist
    model.set_physical(y, x, 0 * x)
    s = model.structure
    lag = W**2 * r0 * m * e * L / (s.k_lag + W**2 * s.k2_lag)  # f_lag = r0 int m e dr
    y[Y_ZETA0:Y_ZETA0 + 2] = lag
    kernel_guard.evaluate(y, model.arrays, dy, loads)
    assert np.abs(dy[model.xd_slice()]).max() <= 1e-10 * scale
    assert abs(dy[Y_OMEGA]) <= 1e-12 * W
    assert np.abs(dy[Y_ZETAD0:Y_ZETAD0 + 2]).max() <= 1e-10 * W**2 * abs(r0 * m * e * L) / s.I_lag + 1e-14
    if x_cg == 0.3:
        assert twist == pytest.approx(-W**2 * I * L * (ti + tt / 2) / (C), rel=1e-12)


@pytest.mark.parametrize("fidelity", FIDELITIES)
def test_rotor_speed_inertia_with_free_lag_independent_of_coning(fidelity):
    """With both blades free to lag, the rotor-speed inertia is ``D = J - sum S_b^2/I_b`` (the
    Schur complement the kernel divides by). For the exact rigid-flap kinematics D does not
    depend on the flap angle at all (the blade's horizontal arm shrinks by the same cos beta in
    J, S and I_z), and D is small here (~2 kg m^2 against J ~ 100), so a model that lowers J by
    coning without the matching S2, I2 makes D negative at ~9 deg of coning and the explicit step
    blows up (that happened). Collective coning of 0.16 rad (uniform slope): the change of D must
    stay below 2 % of the change of J."""
    model = vacuum_model(fidelity, load_preset("paper-boundary").with_overrides(gj_nm2=400.0))
    s = model.structure
    mesh = s.mesh
    x = np.zeros(s.n)
    nodes = np.asarray(mesh.nodes_m)
    for b in range(2):
        q0 = 1 + b * mesh.n_q
        if mesh.fidelity == "fem-coupled":
            x[q0:q0 + mesh.n_flap:2] = 0.16 * (nodes[1:] - mesh.root_m)
            x[q0 + 1:q0 + mesh.n_flap:2] = 0.16
        else:
            x[q0] = 0.16
    y = np.zeros(model.n_y); y[Y_OMEGA] = OMEGA0
    d = []
    for scale in (0.0, 1.0):
        model.set_physical(y, scale * x, 0 * x)
        S, I = lag_inertias(model, y)
        d.append((polar_inertia(model, y), polar_inertia(model, y) - np.sum(S**2 / I)))
    (j0, d0), (j1, d1) = d
    print(f"\n{fidelity}: J {j0:.3f} -> {j1:.3f}, D {d0:.4f} -> {d1:.4f} kg m^2")
    assert d0 > 0.5 and d1 > 0.5
    assert abs(d1 - d0) <= 0.02 * abs(j1 - j0)
