"""The right-hand side forms the products of its structural matrices with the coordinates and their
rates by columns (``ModelArrays.xq``, ``xqd``: one vectorised pass over the coordinates). Those must
be the numbers of the row-by-row dot products it replaced, bit for bit, for both kinds of basis
(the rigid level's physical coordinates with a mass matrix, the FEM levels' mass-normalised modes),
and the guard must refuse copies that are not the model's own matrices."""
import numpy as np
import pytest

from amra_core import kernel_guard, kernels
from amra_core.flight import FlightCondition, SolverSettings
from amra_core.jit import kernel
from amra_core.layout import (N_XQ, N_XQD, N_Y_FIXED, P_NS, P_UNIT_MASS, XQ_GLH0, XQ_GYH, XQ_K0, XQ_K2,
                              XQ_LI0, XQ_LI1, XQ_LS0, XQ_LS1, XQ_UGLH0, XQ_UGYH, XQD_C, XQD_GLH0, XQD_GYH,
                              with_coordinate_products)
from amra_core.model import compile_model


@kernel
def _row_by_row(y, m):
    """The products as the right-hand side formed them until 2026-12-07: per row i, one dot
    product per matrix, terms added in the order k = 0, 1, ... (same compiler flags)."""
    ns = int(m.p[P_NS]); x0 = N_Y_FIXED; xd0 = N_Y_FIXED + ns
    out = np.zeros((N_XQ + N_XQD, ns))
    for i in range(ns):
        for k in range(ns):
            q = y[x0 + k]; qd = y[xd0 + k]
            out[XQ_K0, i] += m.k0[i, k] * q
            out[XQ_K2, i] += m.k2[i, k] * q
            out[XQ_GYH, i] += m.gyh[i, k] * q
            out[XQ_LS0, i] += m.ls2[0, i, k] * q
            out[XQ_LS1, i] += m.ls2[1, i, k] * q
            out[XQ_LI0, i] += m.li2[0, i, k] * q
            out[XQ_LI1, i] += m.li2[1, i, k] * q
            out[XQ_GLH0, i] += m.glh[0, i, k] * q
            out[XQ_UGYH, i] += m.ugyh[i, k] * q
            out[XQ_UGLH0, i] += m.uglh[0, i, k] * q
            out[N_XQ + XQD_C, i] += m.c[i, k] * qd
            out[N_XQ + XQD_GYH, i] += m.gyh[i, k] * qd
            out[N_XQ + XQD_GLH0, i] += m.glh[0, i, k] * qd
    return out


@pytest.mark.parametrize("fidelity", ["rigid", "fem-torsion", "fem-coupled"])
def test_the_column_products_are_the_row_by_row_dot_products_bit_for_bit(mccutcheon, fidelity):
    model = compile_model(mccutcheon, FlightCondition(mu=0.2), SolverSettings(fidelity))
    m = model.arrays
    ns = model.n_s
    rng = np.random.default_rng(7)
    unit_mass = m.p[P_UNIT_MASS] > 0.5
    assert unit_mass == (fidelity != "rigid")  # both branches of the kernel are covered
    for _ in range(5):
        y = np.zeros(model.n_y)
        y[1] = rng.uniform(25, 45); y[2] = rng.uniform(5, 12); y[3] = rng.uniform(2, 6)
        y[N_Y_FIXED:N_Y_FIXED + 2 * ns] = rng.normal(0, 0.05, 2 * ns)
        dy = np.zeros(model.n_y); loads = np.zeros(8)
        work, cw = kernels.new_work(m)
        kernels.rhs(y, dy, m, loads, work, cw)
        got = work[kernels.W_PQ:kernels.W_PQ + (N_XQ + N_XQD) * ns].reshape(N_XQ + N_XQD, ns)
        want = _row_by_row(y, m)
        rows = [r for r in range(N_XQ + N_XQD) if not (unit_mass and r in (XQ_UGYH, XQ_UGLH0))]
        assert np.abs(want[rows]).max() > 0.0
        np.testing.assert_array_equal(got[rows], want[rows])


def test_the_guard_refuses_column_copies_that_are_not_the_models_matrices(mccutcheon):
    """xq, xqd edited on one side, or left over from before a matrix changed, pass every shape
    check but not this one; rebuilt with with_coordinate_products they pass."""
    a = compile_model(mccutcheon, FlightCondition(), SolverSettings("fem-coupled"))
    y = np.zeros(a.n_y); y[1] = 38.0
    dy, loads = np.zeros(a.n_y), np.zeros(8)
    for field in ("xq", "xqd"):
        bad = a.arrays._replace(**{field: getattr(a.arrays, field) * 1.01})
        with pytest.raises(kernel_guard.KernelShapeError, match="xq"):
            kernel_guard.evaluate(y, bad, dy, loads)
    stale = a.arrays._replace(k2=a.arrays.k2 * 1.01)
    with pytest.raises(kernel_guard.KernelShapeError, match="k2"):
        kernel_guard.evaluate(y, stale, dy, loads)
    kernel_guard.evaluate(y, with_coordinate_products(stale), dy, loads)
    assert np.isfinite(dy).all()
