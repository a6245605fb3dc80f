"""Analytic checks of the structural model (model-notes §6 "Structure", physics-reference §4.1-4.3).

Single-blade checks use :func:`amra_core.structure.blade_matrices` with the teeter row/column
(index 0) dropped: a cantilever clamped at the root cut-out. Tolerances are the ones written in
model-notes §6 (0.5 % for the non-rotating beam and torsion checks, 1 % for the rotating table,
+-10 % for the measured McCutcheon torsion frequency); "exact" identities are checked to
round-off or to a stated, justified level.
"""
import dataclasses
import math

import numpy as np
import pytest
import scipy.linalg as sl
from scipy.integrate import quad

from amra_core.modes import natural_modes
from amra_core.rotor import BladeStations, PointMass, Rotor
from amra_core.rotor_io import load_preset
from amra_core.shapes import make_mesh
from amra_core.structure import assemble, blade_matrices
from amra_core.validation.structure import BETA_L, ROTATING_TABLE  # physics-reference §4.1-4.2


# uniform test blade (SI): chosen round numbers, not a real blade
M_KG_M, I_KG_M, GJ, EI, EI_LAG = 3.0, 0.01, 1500.0, 1200.0, 9.0e4


def uniform_rotor(root_m=0.5, radius_m=4.0, x_ea=0.3, x_cg=0.3, gj=GJ, ei=EI, m=M_KG_M, i=I_KG_M,
                  point_mass=None, hub=0.0):
    """A uniform custom rotor; x_cg = x_ea (default) decouples flap and torsion."""
    two = lambda v: (v, v)  # noqa: E731
    st = BladeStations(r_m=(root_m, radius_m), chord_m=two(0.2), twist_rad=two(0.0),
                       mass_kg_m=two(m), torsional_inertia_kg_m=two(i), gj_nm2=two(gj),
                       ei_flap_nm2=two(ei), ei_lag_nm2=two(EI_LAG), x_ea=two(x_ea), x_cg=two(x_cg),
                       x_ac=two(0.25))
    return Rotor(name="uniform-test", radius_m=radius_m, root_cutout_m=root_m, n_blades=2,
                 incidence_rad=0.0, vehicle_mass_kg=300.0, hub_teeter_inertia_kg_m2=hub,
                 hub_polar_inertia_kg_m2=hub, stations=st, point_mass=point_mass)


def cantilever(rotor, fidelity, n_elements, trapeze=True):
    """(mesh, M, K0, K2) of one blade clamped at the root cut-out (teeter dropped)."""
    mesh = make_mesh(fidelity, rotor.root_cutout_m, rotor.radius_m, n_elements)
    M, K0, K2 = blade_matrices(rotor, mesh, trapeze=trapeze)
    return mesh, M[1:, 1:], K0[1:, 1:], K2[1:, 1:]


def flap_idx(mesh):
    return np.arange(mesh.n_flap)


def torsion_idx(mesh):
    return np.arange(mesh.n_flap, mesh.n_q)


def block_omegas(M, K, idx, n=3):
    """Lowest ``n`` circular frequencies [rad/s] of the sub-system on coordinates ``idx``."""
    ix = np.ix_(idx, idx)
    lam = sl.eigh(K[ix], M[ix], eigvals_only=True)
    return np.sqrt(lam[:n])


def torsion_exact(rotor, n=3):
    L = rotor.blade_length_m
    return np.array([(2 * k - 1) * math.pi / (2 * L) * math.sqrt(GJ / I_KG_M) for k in range(1, n + 1)])


def bending_exact(rotor):
    L = rotor.blade_length_m
    return BETA_L**2 * math.sqrt(EI / (M_KG_M * L**4))


def observed_order(n_elements, errors):
    """Least-squares slope of log|error| against log(h), h = L/n."""
    h = 1.0 / np.asarray(n_elements, dtype=float)
    return float(np.polyfit(np.log(h), np.log(np.abs(errors)), 1)[0])


# ---------------------------------------------------------------------------------------------
# uniform fixed-free torsion
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("fidelity", ["fem-torsion", "fem-coupled"])
def test_uniform_torsion_frequencies_20_elements(fidelity):
    rotor = uniform_rotor()
    mesh, M, K0, _ = cantilever(rotor, fidelity, 20)
    t = torsion_idx(mesh)
    # no inertial/elastic coupling into the torsion block when x_cg = x_ea
    assert np.abs(M[np.ix_(flap_idx(mesh), t)]).max() == 0.0
    w = block_omegas(M, K0, t)
    err = w / torsion_exact(rotor) - 1.0
    print(f"\n{fidelity}: torsion relative errors at 20 elements {err}")
    assert np.all(np.abs(err) <= 0.005), err


def _torsion_errors(n_list, mode):
    rotor = uniform_rotor()
    exact = torsion_exact(rotor)[mode]
    errs = []
    for n in n_list:
        mesh, M, K0, _ = cantilever(rotor, "fem-torsion", n)
        errs.append(block_omegas(M, K0, torsion_idx(mesh))[mode] / exact - 1.0)
    return np.array(errs)


@pytest.mark.parametrize("mode, n_list", [(0, (4, 8, 16)), (1, (8, 16, 32)), (2, (8, 16, 32))])
def test_torsion_convergence_order(mode, n_list):
    """The torsion mass is the average of the consistent and lumped linear-element masses: its
    dispersion relation 2(1 - cos kh)/(10/12 + 2/12 cos kh) = (kh)^2 (1 - (kh)^4/240 + ...) gives
    a frequency error -(kh)^4/480, order 4 (modes 2 and 3 are fitted on finer meshes, where kh is
    in the asymptotic range). Expected order window [3.5, 4.5]; never widened."""
    errs = _torsion_errors(n_list, mode)
    order = observed_order(n_list, errs)
    print(f"\ntorsion mode {mode + 1}: errors {errs} over {n_list} elements, order {order:.3f}")
    assert 3.5 <= order <= 4.5, (
        f"torsion mode {mode + 1}: observed convergence order {order:.3f} (errors {errs} at "
        f"{n_list} elements) is not the 4 of the averaged consistent/lumped mass")


def test_st_venant_tip_twist_uniform():
    rotor = uniform_rotor()
    torque = 50.0  # N m at the tip
    for fidelity in ("fem-torsion", "fem-coupled"):
        mesh, _, K0, _ = cantilever(rotor, fidelity, 20)
        *_, pt, _ = mesh.shapes([rotor.radius_m])
        f = torque * pt[0]  # virtual work of a tip torque: T * delta theta(tip)
        x = np.linalg.solve(K0, f)
        twist = float(pt[0] @ x)
        exact = torque * rotor.blade_length_m / GJ
        assert abs(twist / exact - 1.0) <= 0.005, (fidelity, twist, exact)


def test_st_venant_tip_twist_mccutcheon_tapered_gj():
    """Non-uniform GJ (linear between stations): tip twist T * int dr / GJ(r)."""
    rotor = load_preset("mccutcheon")
    st = rotor.stations
    torque = 50.0
    exact = torque * sum(quad(lambda r: 1.0 / st.at("gj_nm2", r), a, b)[0]
                         for a, b in zip(st.r_m[:-1], st.r_m[1:]))
    for fidelity in ("fem-torsion", "fem-coupled"):
        mesh, _, K0, _ = cantilever(rotor, fidelity, 10)
        *_, pt, _ = mesh.shapes([rotor.radius_m])
        twist = float(pt[0] @ np.linalg.solve(K0, torque * pt[0]))
        assert abs(twist / exact - 1.0) <= 0.005, (fidelity, twist, exact)


# ---------------------------------------------------------------------------------------------
# uniform cantilever bending (Hermite cubics)
# ---------------------------------------------------------------------------------------------
def test_uniform_cantilever_bending_20_elements():
    rotor = uniform_rotor()
    mesh, M, K0, _ = cantilever(rotor, "fem-coupled", 20)
    f, t = flap_idx(mesh), torsion_idx(mesh)
    # x_cg = x_ea: flap and torsion are decoupled, so the flap block holds the bending modes
    assert np.abs(M[np.ix_(f, t)]).max() == 0.0 and np.abs(K0[np.ix_(f, t)]).max() == 0.0
    w = block_omegas(M, K0, f)
    err = w / bending_exact(rotor) - 1.0
    print(f"\nbending relative errors at 20 elements {err}")
    assert np.all(np.abs(err) <= 0.005), err
    # the same three frequencies are modes of the whole coupled cantilever
    lam_all = sl.eigh(K0, M, eigvals_only=True)
    for wk in w:
        assert np.min(np.abs(np.sqrt(lam_all) / wk - 1.0)) < 1e-9


@pytest.mark.parametrize("mode", [0, 1, 2])
def test_bending_convergence_order(mode):
    """Hermite cubic beam elements with consistent mass: eigenvalue error O(h^(2(k-m))) with
    k = 4 (cubic) and m = 2 (second derivatives in the energy), i.e. order 4."""
    rotor = uniform_rotor()
    n_list = (4, 8, 16)
    exact = bending_exact(rotor)[mode]
    errs = []
    for n in n_list:
        mesh, M, K0, _ = cantilever(rotor, "fem-coupled", n)
        errs.append(float(block_omegas(M, K0, flap_idx(mesh))[mode] / exact - 1.0))
    order = observed_order(n_list, errs)
    print(f"\nbending mode {mode + 1}: errors {errs}, order {order:.3f}")
    assert 3.5 <= order <= 4.5, (mode, order, errs)


# ---------------------------------------------------------------------------------------------
# rotating uniform cantilever, no hub offset
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("eta", sorted(ROTATING_TABLE))
def test_rotating_cantilever_table(eta):
    rotor = uniform_rotor(root_m=0.0, radius_m=4.0)
    L = rotor.blade_length_m
    tscale = math.sqrt(M_KG_M * L**4 / EI)  # [s]
    omega = eta / tscale
    mesh, M, K0, K2 = cantilever(rotor, "fem-coupled", 20)
    w = block_omegas(M, K0 + omega**2 * K2, flap_idx(mesh)) * tscale
    ref = np.array(ROTATING_TABLE[eta])
    err = w / ref - 1.0
    print(f"\neta = {eta}: {w} vs {ref}")
    assert np.all(np.abs(err) <= 0.01), err


# ---------------------------------------------------------------------------------------------
# teeter: exactly 1/rev
# ---------------------------------------------------------------------------------------------
def _teeter_rotors():
    pm = PointMass(r_m=3.2, mass_kg=0.8, x_chord=0.45)
    return [load_preset("mccutcheon"), load_preset("paper-boundary"), uniform_rotor(hub=2.0),
            uniform_rotor(x_cg=0.4, point_mass=pm, hub=1.0)]


@pytest.mark.parametrize("fidelity", ["rigid", "fem-torsion", "fem-coupled"])
def test_rigid_teeter_is_one_per_rev(fidelity):
    """Teeter-only system (rigid blades, no flap spring involved): M[0,0] beta'' + Omega^2
    K2[0,0] beta = 0, so nu^2 = K2[0,0]/M[0,0] = int m r^2 / int m r^2 = 1.

    The full system: x = [1, 0, ..., 0] (the whole rotor tilting rigidly) is an exact
    eigenvector for ANY blade flexibility, because K0 has a zero teeter column (no spring is
    strained) and, by integration by parts of int T w' dr with T(R) = 0 and w(r0) = 0, the
    centrifugal column K2[:, 0] equals the inertial column M[:, 0]. So the full system's teeter
    mode is 1/rev too, and mass-orthogonality makes it the only mode with teeter participation.

    Tolerance 1e-6 on nu: the discrete identity holds to the accuracy of the tabulated tension
    (`tension_per_omega2`: trapezoid on 4001 points with linear interpolation, relative error
    ~1e-8 in nu^2); 1e-6 leaves two orders of margin while still catching any O(h^2) or missing
    hub-bar term (which would be ~1e-2)."""
    for rotor in _teeter_rotors():
        mesh = make_mesh(fidelity, rotor.root_cutout_m, rotor.radius_m, 10)
        s = assemble(rotor, mesh)
        assert s.K0[0, 0] == 0.0 and np.abs(s.K0[:, 0]).max() == 0.0
        assert math.sqrt(s.K2[0, 0] / s.M[0, 0]) == pytest.approx(1.0, abs=1e-6)
        scale = np.abs(s.M).max()
        assert np.abs(s.K2[:, 0] - s.M[:, 0]).max() <= 1e-6 * scale
        for omega in (5.0, 20.0, 40.0, 80.0):
            modes = natural_modes(rotor, fidelity, 10, omega)
            teeter = [m for m in modes if m["label"].startswith("teeter")]
            assert len(teeter) == 1, [m["label"] for m in modes]
            assert teeter[0]["per_rev"] == pytest.approx(1.0, abs=1e-6), (rotor.name, omega)
            assert teeter[0]["shape"]["energy"]["teeter"] == pytest.approx(1.0, abs=1e-6)


# ---------------------------------------------------------------------------------------------
# propeller moment: nu^2 = nu0^2 + 1
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("fidelity", ["rigid", "fem-torsion", "fem-coupled"])
def test_propeller_moment(fidelity):
    """CG on the EA (thin section, no coupling), tension-torsion left out: every torsion
    eigenvalue rises by exactly Omega^2, because the propeller-moment stiffness is the torsional
    inertia matrix itself."""
    rotor = uniform_rotor()
    mesh, M, K0, K2 = cantilever(rotor, fidelity, 10, trapeze=False)
    t = torsion_idx(mesh)
    n = min(3, len(t))
    w0 = block_omegas(M, K0, t, n)
    for omega in (10.0, 40.0, 100.0):
        w = block_omegas(M, K0 + omega**2 * K2, t, n)
        nu2, nu02 = (w / omega) ** 2, (w0 / omega) ** 2
        np.testing.assert_allclose(nu2, nu02 + 1.0, rtol=1e-10)


def test_propeller_moment_in_assembled_rotor():
    """Rigid level (uniform twist, so no tension-torsion): nu^2 = nu0^2 + 1 exactly in the
    assembled rotor. fem-coupled: the assembled rotor's torsion modes are the single blade's
    rotating torsion modes (propeller moment and tension-torsion), CG on the EA."""
    rotor = uniform_rotor()
    omega = 40.0
    f0 = {m["label"]: m["frequency_hz"] for m in natural_modes(rotor, "rigid", 10, 0.0)}
    for m in natural_modes(rotor, "rigid", 10, omega):
        if m["label"].startswith("torsion"):
            nu0 = 2 * math.pi * f0[m["label"]] / omega
            assert m["per_rev"] ** 2 == pytest.approx(nu0**2 + 1.0, rel=1e-9), m["label"]
    mesh, M, K0, K2 = cantilever(rotor, "fem-coupled", 10)
    blade = block_omegas(M, K0 + omega**2 * K2, torsion_idx(mesh), 4) / omega
    for m in natural_modes(rotor, "fem-coupled", 10, omega):
        if m["label"].startswith("torsion") and m["per_rev"] < blade[-1]:
            assert np.min(np.abs(blade / m["per_rev"] - 1.0)) <= 1e-9, m["label"]


# ---------------------------------------------------------------------------------------------
# static twist under rotation (propeller moment of the built-in pitch, tension-torsion)
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("trapeze", [False, True])
def test_static_twist_under_rotation_vs_ode(trapeze):
    """Uniform blade, CG on the EA (no flap coupling), GJ 100, built-in pitch theta0 = 4 deg, at
    Omega = 40 rad/s: the static elastic twist solves
    ``d/dr[(GJ + Omega^2 k_A^2 T(r)) theta'] - Omega^2 I theta = Omega^2 I theta0``,
    ``theta(r0) = 0``, ``theta'(R) = 0``, with ``T/Omega^2 = m (R^2 - r^2)/2`` and
    ``k_A^2 = I/m`` (tension-torsion) or 0. Without it the solution is
    ``theta0 (cosh k(R - r)/cosh kL - 1)``, ``k^2 = Omega^2 I/GJ``. FEM torsion (20 and 40
    elements, ``(K0 + Omega^2 K2) x = Omega^2 f`` of the assembled rotor) against scipy's
    solve_bvp: within 0.2 % at the tip, error falling with refinement. The two answers differ by
    far more than that (the tension-torsion term is tested, not just tolerated)."""
    from scipy.integrate import solve_bvp
    gj, om, th0 = 100.0, 40.0, math.radians(4.0)
    rotor = dataclasses.replace(uniform_rotor(gj=gj), incidence_rad=th0)
    r0, R, m, i = rotor.root_cutout_m, rotor.radius_m, M_KG_M, I_KG_M

    def ode(r, y):
        stiff = gj + (om**2 * (i / m) * m * (R**2 - r**2) / 2 if trapeze else 0.0)
        # y = [theta, stiff theta']
        return np.vstack([y[1] / stiff, om**2 * i * (y[0] + th0)])

    rr = np.linspace(r0, R, 200)
    sol = solve_bvp(ode, lambda a, b: np.array([a[0], b[1]]), rr, np.zeros((2, rr.size)), tol=1e-10)
    assert sol.success
    exact_tip = float(sol.sol(R)[0])
    if not trapeze:
        k = math.sqrt(om**2 * i / gj)
        L = R - r0
        assert exact_tip == pytest.approx(th0 * (1 / math.cosh(k * L) - 1), rel=1e-8)
    errs = []
    for n in (20, 40):
        mesh = make_mesh("fem-torsion", r0, R, n)
        s = assemble(rotor, mesh, trapeze=trapeze)
        x = np.linalg.solve(s.K0 + om**2 * s.K2, om**2 * s.f)
        tip = x[mesh.n_q]  # blade 0, last torsion node
        errs.append(abs(tip / exact_tip - 1.0))
    print(f"\ntrapeze={trapeze}: static tip twist {math.degrees(exact_tip):+.4f} deg; FEM errors {errs}")
    assert errs[1] <= 0.002 and errs[1] < errs[0]
    mesh = make_mesh("fem-torsion", r0, R, 40)
    s = assemble(rotor, mesh, trapeze=not trapeze)
    tip_other = np.linalg.solve(s.K0 + om**2 * s.K2, om**2 * s.f)[mesh.n_q]
    assert abs(tip_other / exact_tip - 1.0) >= 0.05


# ---------------------------------------------------------------------------------------------
# equivalent root springs of the rigid level (model-notes §2)
# ---------------------------------------------------------------------------------------------
def test_rigid_level_root_springs_match_first_cantilever_modes():
    rotor = uniform_rotor()
    L = rotor.blade_length_m
    mesh, M, K0, _ = cantilever(rotor, "rigid", 10)
    w_flap = block_omegas(M, K0, flap_idx(mesh), 1)[0]
    w_tors = block_omegas(M, K0, torsion_idx(mesh), 1)[0]
    # rigid level by construction equals the analytic first modes (to round-off)
    assert w_flap == pytest.approx(bending_exact(rotor)[0], rel=1e-8)
    assert w_tors == pytest.approx(torsion_exact(rotor)[0], rel=1e-12)
    # and the first FEM modes (20 elements) within the 0.5 % of model-notes §6
    mesh20, M20, K020, _ = cantilever(rotor, "fem-coupled", 20)
    assert w_flap == pytest.approx(block_omegas(M20, K020, flap_idx(mesh20), 1)[0], rel=0.005)
    assert w_tors == pytest.approx(block_omegas(M20, K020, torsion_idx(mesh20), 1)[0], rel=0.005)
    # fem-torsion keeps the root flap spring: same flap frequency as the rigid level
    mesh_t, Mt, K0t, _ = cantilever(rotor, "fem-torsion", 20)
    assert block_omegas(Mt, K0t, flap_idx(mesh_t), 1)[0] == pytest.approx(w_flap, rel=1e-12)
    # lag spring: the same equivalence with EI_lag
    # (the lag inertia also carries the sections' chordwise inertia I L, 0.1 % here)
    s = assemble(rotor, mesh)
    w_lag = math.sqrt(s.k_lag / (s.I_lag - I_KG_M * L))
    assert w_lag == pytest.approx(BETA_L[0] ** 2 * math.sqrt(EI_LAG / (M_KG_M * L**4)), rel=1e-8)


def test_lag_offset_hinge_frequency():
    """Rigid lag about a hinge at r0 (physics-reference §4.3): nu^2 = (3/2) e/(1-e) + nonrotating
    for a mass line; the sections' chordwise inertia adds I L to the lag inertia m L^3/3."""
    rotor = uniform_rotor(root_m=0.2, radius_m=4.0)
    s = assemble(rotor, make_mesh("rigid", 0.2, 4.0, 10))
    e, L = 0.2 / 4.0, 3.8
    assert s.k2_lag / (s.I_lag - I_KG_M * L) == pytest.approx(1.5 * e / (1 - e), rel=1e-10)
    assert s.I_lag == pytest.approx(M_KG_M * L**3 / 3 + I_KG_M * L, rel=1e-12)


# ---------------------------------------------------------------------------------------------
# McCutcheon: first torsion vs the measured 34.8 Hz
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("fidelity", ["rigid", "fem-torsion", "fem-coupled"])
def test_mccutcheon_first_torsion_vs_measured(fidelity):
    measured = 34.8
    modes = natural_modes("mccutcheon", fidelity, 10, 0.0)
    first = min((m for m in modes if m["label"].startswith("torsion 1")),
                key=lambda m: m["frequency_hz"])
    f = first["frequency_hz"]
    msg = (f"McCutcheon first torsion ({fidelity}, 10 elements, Omega = 0): {f:.2f} Hz "
           f"[{first['label']}] vs measured {measured} Hz ({100 * (f / measured - 1):+.1f} %)")
    print("\n" + msg)
    assert abs(f / measured - 1.0) <= 0.10, msg
