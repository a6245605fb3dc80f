"""Tests of amra_core.airfoil: table loading, PCHIP resampling, jitted lookup, Mach correction."""
import math

import numpy as np
import pytest

from amra_core.airfoil import (AIRFOIL_FILES, SYMMETRISE_DEG, AirfoilTable, airfoil_coefficients,
                               coefficients, compile_airfoil, load_airfoil, symmetrised)

NAMES = sorted(AIRFOIL_FILES)


@pytest.fixture(scope="module", params=NAMES)
def table_and_arrays(request):
    table = load_airfoil(request.param)
    return table, compile_airfoil(table)


@pytest.fixture(scope="module")
def critzos():
    return compile_airfoil(load_airfoil("naca0012_critzos"))


def test_load_metadata():
    crit, shel = load_airfoil(), load_airfoil("naca0012_sheldahl360k")
    assert crit.name == "naca0012_critzos" and crit.has_cm and not shel.has_cm
    assert crit.origin.startswith("NACA 0012") and "TN 3361" in crit.origin
    assert "SAND80-2114" in shel.origin
    assert set(shel.cm) == {0.0}
    assert crit.alpha_deg[0] == -180.0 and crit.alpha_deg[-1] == 180.0


def test_unknown_name_lists_available():
    with pytest.raises(ValueError, match="unknown airfoil 'naca0015'") as err:
        load_airfoil("naca0015")
    for name in NAMES:
        assert name in str(err.value)


def test_validation_rejects_bad_tables():
    a = (-180.0, 0.0, 90.0, 180.0)
    z = (0.0,) * 4
    with pytest.raises(ValueError, match="increasing"):
        AirfoilTable("x", "", (-180.0, 90.0, 0.0, 180.0), z, z, z)
    with pytest.raises(ValueError, match="-180 to 180"):
        AirfoilTable("x", "", (-170.0, 0.0, 90.0, 180.0), z, z, z)
    with pytest.raises(ValueError, match="non-finite"):
        AirfoilTable("x", "", a, (0.0, math.nan, 0.0, 0.0), z, z)
    with pytest.raises(ValueError, match="step_deg"):
        compile_airfoil(load_airfoil(), step_deg=0.7)


def test_table_points_reproduced(table_and_arrays):
    table, arr = table_and_arrays
    for a, cl, cd, cm in zip(table.alpha_deg, table.cl, table.cd, table.cm):
        got = airfoil_coefficients(math.radians(a), 0.0, *arr)
        assert got == pytest.approx((cl, cd, cm), abs=1e-9, rel=0.0), a


@pytest.mark.parametrize("name", NAMES)
def test_raw_table_points_reproduced(name):
    """The digitised points stay loadable (raw=True) and are reproduced by the lookup too."""
    table = load_airfoil(name, raw=True)
    arr = compile_airfoil(table)
    for a, cl, cd, cm in zip(table.alpha_deg, table.cl, table.cd, table.cm):
        assert airfoil_coefficients(math.radians(a), 0.0, *arr) == pytest.approx((cl, cd, cm), abs=1e-9, rel=0.0)


def test_critzos_attached_range_symmetrised():
    """NACA 0012 is symmetric: in |alpha| <= 15 deg the loaded Critzos table has Cl odd, Cd even
    (both the digitised positive-alpha branch) and Cm odd, with Cm = 0 where the file holds the
    digitiser's constant -0.0149 (-9..9 deg after mirroring); outside the range, and for the
    positive branch's Cl and Cd, the raw points are unchanged. The raw file is not symmetric
    (Cl -0.557 at -5 deg against +0.538 at +5, Cd 0.0178 against 0.0093)."""
    raw, sym = load_airfoil("naca0012_critzos", raw=True), load_airfoil("naca0012_critzos")
    assert SYMMETRISE_DEG["naca0012_critzos"] == 15.0
    a = np.array(raw.alpha_deg)
    rc = {k: np.array(getattr(raw, k)) for k in ("cl", "cd", "cm")}
    sc = {k: np.array(getattr(sym, k)) for k in ("cl", "cd", "cm")}
    i5, im5 = int(np.flatnonzero(a == 5.0)[0]), int(np.flatnonzero(a == -5.0)[0])
    assert (rc["cl"][im5], rc["cl"][i5], rc["cd"][im5], rc["cd"][i5]) == (-0.5573, 0.5384, 0.0178, 0.0093)
    for i in np.flatnonzero(np.abs(a) <= 15.0):
        j = int(np.flatnonzero(a == -a[i])[0])
        assert sc["cl"][i] == -sc["cl"][j] and sc["cd"][i] == sc["cd"][j] and sc["cm"][i] == -sc["cm"][j]
        if a[i] >= 0:
            assert sc["cl"][i] == rc["cl"][i] and sc["cd"][i] == rc["cd"][i]
        if abs(a[i]) <= 9.0:
            assert sc["cm"][i] == 0.0
        assert abs(sc["cm"][i]) <= 0.035
    out = np.abs(a) > 15.0
    for k in ("cl", "cd", "cm"):
        assert np.array_equal(sc[k][out], rc[k][out])
    assert "symmetrised" in sym.origin and "symmetrised" not in raw.origin
    # the kernel sees the symmetric data: Cl(-a) = -Cl(a), Cd(-a) = Cd(a) between table points too
    # (up to 14 deg: PCHIP slopes at +-15 deg depend on the unsymmetric points at +-16 deg)
    arr = compile_airfoil(sym)
    for deg in (0.3, 2.7, 6.1, 11.4, 13.6):
        p, m = (airfoil_coefficients(math.radians(s_ * deg), 0.0, *arr) for s_ in (1.0, -1.0))
        assert p[0] == pytest.approx(-m[0], abs=1e-12) and p[1] == pytest.approx(m[1], abs=1e-12)
        assert p[2] == pytest.approx(-m[2], abs=1e-12)


def test_symmetrised_needs_mirror_points():
    a = (-180.0, -10.0, 0.0, 5.0, 180.0)
    z = (0.0,) * 5
    with pytest.raises(ValueError, match="cannot symmetrise, no point at alpha = 10.0"):
        symmetrised(AirfoilTable("x", "", a, z, z, z), 15.0)


def test_periodicity(table_and_arrays):
    _, arr = table_and_arrays
    rng = np.random.default_rng(1)
    for a in np.concatenate((rng.uniform(-math.pi, math.pi, 200), [-math.pi, 0.0, 3.0])):
        for mach in (0.0, 0.4):
            base = airfoil_coefficients(a, mach, *arr)
            for k in (-2, 1, 3):
                assert airfoil_coefficients(a + k * 2 * math.pi, mach, *arr) == pytest.approx(
                    base, abs=1e-12, rel=0.0)
    assert airfoil_coefficients(math.pi, 0.0, *arr) == pytest.approx(
        airfoil_coefficients(-math.pi, 0.0, *arr), abs=1e-12, rel=0.0)


def test_continuity(table_and_arrays):
    # Bound: scipy's PCHIP slope at a knot is a weighted harmonic mean of the two
    # adjacent secants with weights w1, w2 and w2/w1 <= 2, so |d_k| <= 3*min|secant|
    # (or 0). On an interval, the cubic Hermite derivative is linear in the normalised
    # end slopes (d_k/secant, d_k+1/secant), both in [0, 3]; its maximum over that box
    # is 3*|secant|. Linear interpolation of PCHIP samples cannot be steeper than the
    # PCHIP itself (mean value theorem). So at M = 0 a 0.01 deg step changes a
    # coefficient by at most 3 * max|table secant| [1/deg] * 0.01 deg.
    table, arr = table_and_arrays
    deg = np.linspace(-180.0, 180.0, 36001)  # 0.01 deg apart
    a = np.asarray(table.alpha_deg)
    for j, col in enumerate((table.cl, table.cd, table.cm)):
        y = np.array(col)
        y[0] = y[-1] = 0.5 * (y[0] + y[-1])
        bound = 3.0 * np.max(np.abs(np.diff(y) / np.diff(a))) * 0.01 + 1e-12
        vals = coefficients(arr, np.radians(deg))[j]
        assert np.max(np.abs(np.diff(vals))) <= bound
    # The same across the +/-180 seam.
    seam = coefficients(arr, np.radians(np.array([179.99, 180.0, 180.01])))
    for j in range(3):
        assert np.max(np.abs(np.diff(seam[j]))) <= 0.01


def test_no_overshoot(table_and_arrays):
    table, arr = table_and_arrays
    a = np.asarray(table.alpha_deg)
    frac = np.linspace(0.0, 1.0, 41)[1:-1]
    for k in range(len(a) - 1):
        deg = a[k] + frac * (a[k + 1] - a[k])
        vals = coefficients(arr, np.radians(deg))
        for j, col in enumerate((table.cl, table.cd, table.cm)):
            lo, hi = min(col[k], col[k + 1]), max(col[k], col[k + 1])
            assert np.all(vals[j] >= lo - 1e-12) and np.all(vals[j] <= hi + 1e-12), (j, a[k])


def test_mach_correction(critzos):
    f = 1.0 / math.sqrt(1.0 - 0.25)
    cl0, cd0, cm0 = airfoil_coefficients(math.radians(4.0), 0.0, *critzos)
    cl5, cd5, cm5 = airfoil_coefficients(math.radians(4.0), 0.5, *critzos)
    assert abs(cl5 - cl0 * f) <= 1e-12
    assert (cd5, cm5) == (cd0, cm0)
    for deg in (60.0, -60.0, 176.0, -176.0, 25.0):  # post-stall and reverse flow: unchanged
        assert airfoil_coefficients(math.radians(deg), 0.5, *critzos) == \
            airfoil_coefficients(math.radians(deg), 0.0, *critzos)
    # Linear fade: half the Prandtl-Glauert increment at 15 deg.
    c0 = airfoil_coefficients(math.radians(15.0), 0.0, *critzos)[0]
    c5 = airfoil_coefficients(math.radians(15.0), 0.5, *critzos)[0]
    assert c5 == pytest.approx(c0 * (1.0 + 0.5 * (f - 1.0)), rel=1e-12)
    # Mach clipped to [0, 0.7] inside the factor.
    a = math.radians(-5.0)
    assert airfoil_coefficients(a, 0.95, *critzos) == airfoil_coefficients(a, 0.7, *critzos)
    assert airfoil_coefficients(a, -0.3, *critzos) == airfoil_coefficients(a, 0.0, *critzos)


def test_known_values_critzos(critzos):
    cl14 = airfoil_coefficients(math.radians(14.0), 0.0, *critzos)[0]
    assert cl14 == pytest.approx(1.316, abs=1e-9)
    deg = np.arange(0.0, 30.0, 0.01)
    cl = coefficients(critzos, np.radians(deg))[0]
    assert cl.max() == pytest.approx(1.316, abs=1e-9)
    assert deg[np.argmax(cl)] == pytest.approx(14.0, abs=0.011)
    assert airfoil_coefficients(math.radians(90.0), 0.0, *critzos)[1] == pytest.approx(2.08, abs=1e-3)


def test_coefficients_shapes(critzos):
    cl, cd, cm = coefficients(critzos, 0.1, 0.3)
    assert isinstance(cl, float)
    assert (cl, cd, cm) == airfoil_coefficients(0.1, 0.3, *critzos)
    out = coefficients(critzos, np.zeros((2, 3)), np.array([0.0, 0.2, 0.4]))
    assert all(o.shape == (2, 3) for o in out)


def test_jit_matches_py_func(critzos):
    rng = np.random.default_rng(7)
    for a, m in zip(rng.uniform(-12.0, 12.0, 300), rng.uniform(-0.1, 0.9, 300)):
        jit = airfoil_coefficients(a, m, *critzos)
        py = airfoil_coefficients.py_func(a, m, *critzos)
        assert jit == pytest.approx(py, abs=1e-14, rel=1e-14)
