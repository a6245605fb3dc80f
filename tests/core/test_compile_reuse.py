"""A GJ sweep compiles only what depends on GJ: the reused parts give the same model as a fresh
compile, every model owns the arrays the kernels get, and the one-call Jacobian kernel equals the
column-by-column finite differences it replaced."""
from __future__ import annotations

import numpy as np
import pytest

from amra_core import kernel_guard, model as model_mod
from amra_core.flight import FlightCondition, SolverSettings
from amra_core.model import compile_model
from amra_core.rotor_io import load_preset
from amra_core.shapes import make_mesh
from amra_core.stability import jacobian
from amra_core.structure import assemble, torsion_stiffness
from amra_core.trim import trim

FIDELITIES = ("rigid", "fem-torsion", "fem-coupled")


@pytest.mark.parametrize("fidelity", FIDELITIES)
def test_the_gj_part_of_k0_is_split_off_exactly(fidelity):
    rotor = load_preset("paper-boundary").with_overrides(gj_nm2=321.0, x_cg=0.36)
    mesh = make_mesh(fidelity, rotor.root_cutout_m, rotor.radius_m, 10)
    whole, rest = assemble(rotor, mesh), assemble(rotor, mesh, torsion=False)
    k_gj = torsion_stiffness(rotor, mesh)
    np.testing.assert_allclose(rest.K0 + k_gj, whole.K0, rtol=0, atol=1e-12 * np.abs(whole.K0).max())
    # linear in GJ, and nothing else of the structure depends on it
    doubled = torsion_stiffness(rotor.with_overrides(gj_nm2=642.0), mesh)
    np.testing.assert_allclose(doubled, 2.0 * k_gj, rtol=1e-13, atol=0)
    other = assemble(rotor.with_overrides(gj_nm2=5000.0), mesh, torsion=False)
    for name in ("M", "K0", "K2", "H", "f", "g0", "S2", "I2", "HL", "gl0"):
        np.testing.assert_array_equal(getattr(other, name), getattr(rest, name))


def _arrays(m):
    return {k: np.asarray(v) for k, v in m.arrays._asdict().items()}


@pytest.mark.parametrize("fidelity", FIDELITIES)
def test_a_model_from_reused_parts_equals_a_fresh_compile(fidelity):
    base = load_preset("mccutcheon")
    settings = SolverSettings(fidelity=fidelity)
    for gj in (40.0, 400.0, 4000.0):  # different numbers of retained FEM modes
        compile_model(base.with_overrides(gj_nm2=gj * 1.7), FlightCondition(), settings)  # fill the cache
        reused = compile_model(base.with_overrides(gj_nm2=gj), FlightCondition(), settings)
        model_mod._gj_free_parts.cache_clear()
        fresh = compile_model(base.with_overrides(gj_nm2=gj), FlightCondition(), settings)
        a, b = _arrays(reused), _arrays(fresh)
        for k in a:
            np.testing.assert_array_equal(a[k], b[k], err_msg=k)
        assert reused.n_s == fresh.n_s and reused.n_y == fresh.n_y


def test_every_model_owns_the_arrays_the_kernels_get():
    base = load_preset("mccutcheon")
    one = compile_model(base.with_overrides(gj_nm2=300.0))
    two = compile_model(base.with_overrides(gj_nm2=300.0))
    for k, v in one.arrays._asdict().items():
        w = getattr(two.arrays, k)
        if isinstance(v, np.ndarray):
            assert v.flags.writeable and v.flags.c_contiguous, k
            assert not np.shares_memory(v, w), f"{k} is shared between two compiled models"
    # and the shared parts are read-only, so a change to them fails loudly instead of leaking
    parts = model_mod._gj_free_parts(base.with_overrides(gj_nm2=1.0), FlightCondition(), SolverSettings(), False)
    with pytest.raises(ValueError):
        parts.structure.M[0, 0] = 1.0


@pytest.mark.parametrize("fidelity", FIDELITIES)
def test_the_jacobian_kernel_equals_column_by_column_differences(fidelity):
    rotor = load_preset("paper-boundary").with_overrides(gj_nm2=400.0, x_cg=0.36)
    m = compile_model(rotor, FlightCondition(), SolverSettings(fidelity=fidelity))
    tr = trim(m)
    m = tr.model or m
    y0 = tr.state
    n = len(y0)
    ref = np.zeros((n - 1, n - 1))
    dp, dm, loads = np.zeros(n), np.zeros(n), np.zeros(8)
    for i in range(1, n):
        h = 1e-6 * max(1.0, abs(y0[i]))
        yp = y0.copy(); yp[i] += h
        ym = y0.copy(); ym[i] -= h
        kernel_guard.evaluate(yp, m.arrays, dp, loads)
        kernel_guard.evaluate(ym, m.arrays, dm, loads)
        ref[:, i - 1] = (dp[1:] - dm[1:]) / (2 * h)
    np.testing.assert_array_equal(jacobian(m, y0), ref)
    with pytest.raises(kernel_guard.KernelShapeError):
        kernel_guard.jacobian(y0[:-1].copy(), m.arrays, np.zeros((n - 2, n - 2)))
    with pytest.raises(kernel_guard.KernelShapeError):
        kernel_guard.jacobian(y0, m.arrays, np.zeros((n - 2, n - 2)))


@pytest.mark.parametrize("fidelity", FIDELITIES)
def test_the_compiled_stiffness_is_the_assembled_one_for_uniform_and_varying_gj(fidelity):
    """The reused GJ-free parts plus the torsional stiffness give the K0 a fresh assembly gives, for a
    uniform GJ and for one varying along the span."""
    from dataclasses import replace
    settings = SolverSettings(fidelity=fidelity)
    uniform = load_preset("paper-boundary").with_overrides(gj_nm2=777.0, x_cg=0.36)
    gj = np.linspace(1500.0, 300.0, len(uniform.stations.r_m))
    varying = replace(uniform, stations=replace(uniform.stations, gj_nm2=tuple(gj)))
    for rotor in (uniform, varying):
        m = compile_model(rotor, FlightCondition(), settings)
        mesh = make_mesh(fidelity, rotor.root_cutout_m, rotor.radius_m, settings.n_elements, settings.rigid_spring)
        whole = assemble(rotor, mesh, added_mass=model_mod.apparent_mass(rotor, FlightCondition().density_kg_m3))
        np.testing.assert_allclose(m.structure.K0, whole.K0, rtol=0, atol=1e-13 * np.abs(whole.K0).max())
