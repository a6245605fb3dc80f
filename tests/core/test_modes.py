"""Tests of amra_core.modes: natural modes, labels, the JSON report and the tracked fan plot."""
import json
import math

import numpy as np
import pytest
import scipy.linalg as sl

from amra_core.modes import (KINDS, fan_plot, modes_report, natural_modes, participation,
                             solve_modes, track_modes)
from amra_core.rotor import BladeStations, Rotor
from amra_core.rotor_io import load_preset

FIDELITIES = ("rigid", "fem-torsion", "fem-coupled")
REQUIRED = ("teeter", "flap 1 (collective)", "flap 1 (cyclic)", "torsion 1 (collective)",
            "torsion 1 (cyclic)", "lag 1 (collective)", "lag 1 (cyclic)")


def uniform_rotor(gj=150.0, x_ea=0.3, x_cg=0.3):
    """Uniform test rotor (x_cg = x_ea: flap and torsion decoupled, so their modes cross)."""
    two = lambda v: (v, v)  # noqa: E731
    st = BladeStations(r_m=(0.5, 4.0), chord_m=two(0.2), twist_rad=two(0.0), mass_kg_m=two(3.0),
                       torsional_inertia_kg_m=two(0.01), gj_nm2=two(gj), ei_flap_nm2=two(1200.0),
                       ei_lag_nm2=two(9.0e4), x_ea=two(x_ea), x_cg=two(x_cg), x_ac=two(0.25))
    return Rotor(name="uniform-test", radius_m=4.0, root_cutout_m=0.5, n_blades=2, incidence_rad=0.0,
                 vehicle_mass_kg=300.0, hub_teeter_inertia_kg_m2=0.5, hub_polar_inertia_kg_m2=0.5,
                 stations=st)


# ---------------------------------------------------------------------------------------------
# natural modes and labels
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("fidelity", FIDELITIES)
@pytest.mark.parametrize("omega", [0.0, 40.0])
def test_mccutcheon_labels(mccutcheon, fidelity, omega):
    modes = natural_modes(mccutcheon, fidelity, 10, omega)
    labels = [m["label"] for m in modes]
    for req in REQUIRED:
        assert req in labels, (req, labels)
    if fidelity != "rigid":  # FEM torsion
        assert "torsion 2 (collective)" in labels and "torsion 2 (cyclic)" in labels
    if fidelity == "fem-coupled":  # FEM bending
        assert "flap 2 (collective)" in labels and "flap 2 (cyclic)" in labels
    else:  # one root flap spring per blade
        assert not any(lab.startswith("flap 2") for lab in labels)
    assert len(set(labels)) == len(labels), labels
    assert labels.count("teeter") == 1
    for lab in labels:
        assert lab == "teeter" or any(lab.startswith(k + " ") for k in ("flap", "torsion", "lag")), lab
    f = [m["frequency_hz"] for m in modes]
    assert f == sorted(f)
    # numbering within kind and symmetry follows frequency order
    for kind in ("flap", "torsion", "lag"):
        for sym in ("collective", "cyclic"):
            nums = [int(lab.split()[1]) for lab in labels
                    if lab.startswith(kind + " ") and lab.endswith(f"({sym})")]
            assert nums == list(range(1, len(nums) + 1)), (kind, sym, nums)
    if omega == 0.0:
        assert all(m["per_rev"] is None for m in modes)
        assert modes[0]["label"] == "teeter" and modes[0]["frequency_hz"] == 0.0
    else:
        for m in modes:
            assert m["per_rev"] == pytest.approx(2 * math.pi * m["frequency_hz"] / omega, rel=1e-12)


@pytest.mark.parametrize("fidelity", FIDELITIES)
def test_teeter_is_one_per_rev_at_40(mccutcheon, fidelity):
    modes = natural_modes(mccutcheon, fidelity, 10, 40.0)
    teeter = next(m for m in modes if m["label"] == "teeter")
    assert teeter["per_rev"] == pytest.approx(1.0, abs=1e-6)
    assert teeter["frequency_hz"] == pytest.approx(40.0 / (2 * math.pi), rel=1e-6)


def test_full_eigenproblem_matches_symmetry_blocks(mccutcheon):
    """The collective/cyclic block solve gives exactly the eigenvalues of the full system."""
    sol = solve_modes(mccutcheon, "fem-coupled", 10, 40.0)
    lam_full = sl.eigh(sol.K, sol.M, eigvals_only=True)
    np.testing.assert_allclose(sol.eigenvalues, lam_full, rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(sol.vectors.T @ sol.M @ sol.vectors, np.eye(len(lam_full)), atol=1e-9)
    resid = sol.K @ sol.vectors - sol.M @ sol.vectors * sol.eigenvalues
    assert np.abs(resid).max() <= 1e-8 * np.abs(sol.K).max()


def test_lag_block(mccutcheon):
    """Lag: I_lag zeta'' + (k_lag + Omega^2 k2_lag) zeta = 0 per blade, degenerate pair."""
    omega = 40.0
    sol = solve_modes(mccutcheon, "fem-coupled", 10, omega)
    s = sol.structure
    f_lag = math.sqrt((s.k_lag + omega**2 * s.k2_lag) / s.I_lag) / (2 * math.pi)
    lag = [m for m in natural_modes(mccutcheon, "fem-coupled", 10, omega) if m["label"].startswith("lag")]
    assert sorted(m["label"] for m in lag) == ["lag 1 (collective)", "lag 1 (cyclic)"]
    for m in lag:
        assert m["frequency_hz"] == pytest.approx(f_lag, rel=1e-10)
        z = m["shape"]["lag_rad"]
        same = m["label"].endswith("(collective)")
        assert z[0] == pytest.approx(z[1] if same else -z[1], abs=1e-12)


def test_participation_and_shape(mccutcheon):
    sol = solve_modes(mccutcheon, "fem-coupled", 10, 40.0)
    part = participation(sol)
    total = sum(part[k] for k in KINDS)
    np.testing.assert_allclose(total, 1.0, atol=1e-12)
    for m in natural_modes(mccutcheon, "fem-coupled", 10, 40.0):
        sh = m["shape"]
        R = mccutcheon.radius_m
        amp = max(np.abs(sh["flap_m"]).max() / R, np.abs(sh["twist_rad"]).max(),
                  np.abs(sh["lag_rad"]).max(), abs(sh["teeter_rad"]))
        assert amp == pytest.approx(1.0, rel=1e-12)
        assert sh["flap_m"].shape == (2, len(sh["r_m"])) == sh["twist_rad"].shape
        kind = m["label"].split()[0]
        assert max(sh["energy"], key=sh["energy"].get) == kind
        # symmetry: collective modes have equal blade twists, cyclic opposite
        t0, t1 = sh["twist_rad"]
        if sh["symmetry"] == "collective":
            np.testing.assert_allclose(t0, t1, atol=1e-12)
        else:
            np.testing.assert_allclose(t0, -t1, atol=1e-12)


def test_bad_inputs(mccutcheon):
    with pytest.raises(ValueError, match="omega_rad_s"):
        natural_modes(mccutcheon, "fem-coupled", 10, -1.0)
    with pytest.raises(ValueError, match="fidelity"):
        natural_modes(mccutcheon, "beam", 10, 0.0)
    with pytest.raises(ValueError, match="elements"):
        natural_modes(mccutcheon, "fem-coupled", 0, 0.0)


# ---------------------------------------------------------------------------------------------
# report
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("fidelity", FIDELITIES)
def test_modes_report_json(fidelity):
    rep = modes_report("mccutcheon", fidelity, 10, 40.0)
    text = json.dumps(rep)
    back = json.loads(text)
    assert back == rep
    assert rep["rotor"] == "mccutcheon" and rep["fidelity"] == fidelity
    assert rep["elements"] == 10 and rep["omega_rad_s"] == 40.0
    assert 1 <= len(rep["modes"]) <= 12
    assert rep["modes"][0] == {"label": "teeter", "frequency_hz": round(40 / (2 * math.pi), 3),
                               "per_rev": 1.0}
    full = natural_modes("mccutcheon", fidelity, 10, 40.0)
    for r, m in zip(rep["modes"], full):
        assert set(r) == {"label", "frequency_hz", "per_rev"}
        assert r["label"] == m["label"]
        assert r["frequency_hz"] == pytest.approx(m["frequency_hz"], abs=5e-4)
    rep0 = modes_report(load_preset("mccutcheon"), fidelity, 10, 0.0)
    assert all(m["per_rev"] is None for m in rep0["modes"])
    json.dumps(rep0)


# ---------------------------------------------------------------------------------------------
# tracking
# ---------------------------------------------------------------------------------------------
def _two_dof(omegas, coupling):
    """M = I, K = [[1 + 4 W^2, c], [c, 4 + W^2]]: branches cross (c = 0) or veer at W = 1."""
    vecs, lams = [], []
    for w in omegas:
        K = np.array([[1 + 4 * w**2, coupling], [coupling, 4 + w**2]])
        lam, V = np.linalg.eigh(K)
        vecs.append(V)
        lams.append(lam)
    return vecs, np.array(lams)


def test_track_modes_synthetic_crossing():
    omegas = np.linspace(0.0, 2.0, 200)  # does not hit the crossing W = 1 exactly
    vecs, lams = _two_dof(omegas, 0.0)
    idx = track_modes(vecs, np.eye(2))
    lam0 = lams[np.arange(len(omegas)), idx[:, 0]]
    lam1 = lams[np.arange(len(omegas)), idx[:, 1]]
    np.testing.assert_allclose(lam0, 1 + 4 * omegas**2, rtol=1e-12)  # keeps identity through the crossing
    np.testing.assert_allclose(lam1, 4 + omegas**2, rtol=1e-12)
    assert idx[0, 0] == 0 and idx[-1, 0] == 1  # sorted order did swap


def test_track_modes_synthetic_veering():
    omegas = np.linspace(0.0, 2.0, 200)
    vecs, lams = _two_dof(omegas, 0.2)
    idx = track_modes(vecs, np.eye(2))
    # a veering pair does not cross: each tracked branch stays continuous and on its side
    assert np.all(idx[:, 0] == 0) and np.all(idx[:, 1] == 1)


def test_fan_plot_crossing_keeps_identity():
    """Uniform rotor with x_cg = x_ea: flap and torsion are uncoupled, so flap modes (Southwell
    coefficient ~6-20) cross the slowly rising torsion modes (nu^2 = nu0^2 + 1 + tension-torsion)
    as Omega rises. The tracked torsion curve must be the single blade's rotating torsion
    frequency throughout, although its rank among the sorted frequencies changes."""
    rotor = uniform_rotor()
    omegas = np.linspace(0.0, 60.0, 61)
    fp = fan_plot(rotor, omegas, "fem-coupled", 10, n_modes=10)
    assert np.array_equal(fp["omega_rad_s"], omegas)
    by_label = {m["label"]: m for m in fp["modes"]}
    labels0 = [m["label"] for m in natural_modes(rotor, "fem-coupled", 10, 0.0)[:10]]
    assert [m["label"] for m in fp["modes"]] == labels0
    crossed = False
    # exact torsion curve: the single blade's rotating torsion block (propeller moment and
    # tension-torsion; with x_cg = x_ea it is uncoupled from flap, teeter and the other blade)
    from amra_core.shapes import make_mesh
    from amra_core.structure import blade_matrices
    mesh = make_mesh("fem-coupled", 0.5, 4.0, 10)
    Mb, K0b, K2b = blade_matrices(rotor, mesh)
    t = 1 + np.arange(mesh.n_flap, mesh.n_q)
    exact = np.array([math.sqrt(sl.eigh((K0b + w**2 * K2b)[np.ix_(t, t)], Mb[np.ix_(t, t)],
                                        eigvals_only=True)[0]) / (2 * math.pi) for w in omegas])
    for lab in ("torsion 1 (collective)", "torsion 1 (cyclic)"):
        f = by_label[lab]["frequency_hz"]
        np.testing.assert_allclose(f, exact, rtol=1e-9)
        assert np.all(by_label[lab]["southwell"] >= 1.0)  # propeller moment 1 + tension-torsion
        ranks = []
        for k, w in enumerate(omegas):
            all_f = np.sort([m["frequency_hz"] for m in natural_modes(rotor, "fem-coupled", 10, w)])
            ranks.append(int(np.searchsorted(all_f, f[k] * (1 - 1e-12))))
        crossed |= len(set(ranks)) > 1
    assert crossed, "the test case must contain a crossing"
    # flap 2 (collective) crosses torsion 1 upwards and stays a flap mode (Southwell ~7.5)
    f2 = by_label["flap 2 (collective)"]
    assert f2["frequency_hz"][0] < by_label["torsion 1 (collective)"]["frequency_hz"][0]
    assert f2["frequency_hz"][-1] > by_label["torsion 1 (collective)"]["frequency_hz"][-1]
    assert np.all(f2["southwell"] > 6.0)
    _assert_continuous(fp)


def _assert_continuous(fp):
    """No tracked curve jumps: along a branch d(omega^2)/d(Omega^2) = kappa (Hellmann-Feynman,
    kappa = phi^T K2 phi), so between neighbouring speeds |Delta omega^2| <= kappa_max |Delta
    Omega^2| with kappa_max the larger Southwell coefficient at the two ends. The factor 1.5
    allows kappa to vary inside a step (as it does near a veering); a jump onto another branch
    would differ by the branch gap (several Hz here) and break the bound."""
    om = fp["omega_rad_s"]
    d_om2 = np.diff(om**2)
    for m in fp["modes"]:
        w2 = (2 * math.pi * m["frequency_hz"]) ** 2
        kap = np.maximum(np.abs(m["southwell"][1:]), np.abs(m["southwell"][:-1]))
        bound = 1.5 * kap * d_om2 + 1e-9 * np.maximum(w2[1:], 1.0)
        assert np.all(np.abs(np.diff(w2)) <= bound), (m["label"], np.abs(np.diff(w2)) / (kap * d_om2))
        assert np.all(m["assurance"] > 0.8), (m["label"], m["assurance"].min())


def test_fan_plot_mccutcheon_veering(mccutcheon):
    """McCutcheon (CG aft of EA: flap and torsion coupled, the flap 3 / torsion 1 pair veers near
    40-50 rad/s). Every tracked curve is continuous, the teeter curve is Omega/2 pi."""
    omegas = np.linspace(0.0, 50.0, 26)
    fp = fan_plot(mccutcheon, omegas, "fem-coupled", 10, n_modes=12)
    labels = [m["label"] for m in fp["modes"]]
    assert labels == [m["label"] for m in natural_modes(mccutcheon, "fem-coupled", 10, 0.0)[:12]]
    teeter = fp["modes"][labels.index("teeter")]
    np.testing.assert_allclose(teeter["frequency_hz"], omegas / (2 * math.pi), rtol=1e-6, atol=1e-9)
    _assert_continuous(fp)
    # the rigid level too
    fpr = fan_plot(mccutcheon, omegas, "rigid", 10, n_modes=8)
    assert len(fpr["modes"]) == 7  # teeter, 2 flap, 2 lag, 2 torsion
    _assert_continuous(fpr)
