"""The blade-exchange symmetry of axial flight (amra_core.blade_symmetry): the model is symmetric
under relabelling the blades, and the eigenproblem split into its collective and cyclic blocks gives
what the full eigenproblem gives."""
import numpy as np
import pytest

from amra_core import kernel_guard
from amra_core.blade_symmetry import eig_axial, exchange_bases
from amra_core.flight import FlightCondition, SolverSettings
from amra_core.layout import N_LOADS
from amra_core.model import compile_model
from amra_core.rotor_io import load_preset
from amra_core.stability import analyse, jacobian
from amra_core.trim import trim

CASES = [("rigid", "uniform"), ("fem-torsion", "three-state"), ("fem-coupled", "uniform")]


def _trimmed(fidelity, inflow, gj=300.0, cg=0.30):
    rotor = load_preset("paper-boundary").with_overrides(gj_nm2=gj, x_ea=0.32, x_cg=cg)
    tr = trim(compile_model(rotor, FlightCondition(), SolverSettings(fidelity=fidelity, inflow=inflow)))
    assert tr.ok
    return tr


def _exchange(model):
    T_plus, T_minus = exchange_bases(model)
    return T_plus @ T_plus.T - T_minus @ T_minus.T, T_plus, T_minus


@pytest.mark.parametrize("fidelity,inflow", CASES)
def test_the_right_hand_side_is_symmetric_under_exchanging_the_blades(fidelity, inflow):
    """f(P y) = P f(y) at states that are not symmetric themselves (the trim plus a random
    perturbation of every state): the model treats both blades alike, the premise of the split."""
    tr = _trimmed(fidelity, inflow)
    m = tr.model
    P, T_plus, T_minus = _exchange(m)
    basis = np.hstack([T_plus, T_minus])
    assert np.allclose(basis.T @ basis, np.eye(m.n_y - 1), atol=1e-12)  # orthonormal, complete
    assert np.allclose(P @ P, np.eye(m.n_y - 1), atol=1e-12)  # an involution
    rng = np.random.default_rng(7)
    for _ in range(3):
        y = tr.state.copy()
        y[1:] += 0.02 * rng.standard_normal(m.n_y - 1) * (np.abs(y[1:]) + 0.05)
        py = y.copy()
        py[1:] = P @ y[1:]
        f, fp = np.zeros(m.n_y), np.zeros(m.n_y)
        kernel_guard.evaluate(y, m.arrays, f, np.zeros(N_LOADS))
        kernel_guard.evaluate(py, m.arrays, fp, np.zeros(N_LOADS))
        assert np.abs(fp[1:] - P @ f[1:]).max() <= 1e-9 * np.abs(f[1:]).max()
        assert np.abs(P @ (y[1:] - py[1:])).max() > 1e-4  # the state was not symmetric itself


@pytest.mark.parametrize("fidelity,inflow", CASES)
def test_split_eigenproblem_equals_the_full_one(fidelity, inflow):
    tr = _trimmed(fidelity, inflow)
    J = jacobian(tr.model, tr.state)
    lam, V = eig_axial(tr.model, J)
    full = np.linalg.eig(J)[0]
    assert len(lam) == len(full) == J.shape[0]
    for z in full:  # every eigenvalue found, to roundoff
        assert np.abs(lam - z).min() <= 1e-9 * (1.0 + abs(z))
    residual = np.abs(J @ V - V * lam).max(axis=0)
    assert residual.max() <= 1e-9 * np.abs(J).max()
    assert np.allclose(np.linalg.norm(V, axis=0), 1.0)


def test_teeter_is_cyclic_and_rotor_speed_collective():
    """The split sorts the modes physically: each eigenvector is wholly collective or wholly cyclic;
    modes with teeter in them are cyclic, modes that move the rotor speed collective."""
    tr = _trimmed("fem-coupled", "three-state", gj=1500.0, cg=0.40)
    res = analyse(tr.model, tr)
    _, T_plus, T_minus = _exchange(tr.model)
    J = jacobian(tr.model, tr.state)
    lam, V = eig_axial(tr.model, J)
    cyclic = np.linalg.norm(T_minus.T @ V, axis=0)  # 1: wholly cyclic, 0: wholly collective
    assert np.all((cyclic < 1e-8) | (cyclic > 1 - 1e-8))
    checked = {"cyclic": 0, "collective": 0}
    for md in res.modes:
        if md.label == "aero lag":
            continue
        k = int(np.argmin(np.abs(lam - complex(md.real_part_per_s, 2 * np.pi * md.frequency_hz))))
        if md.participation["teeter"] > 0.05:  # teeter moves the blades oppositely
            assert cyclic[k] > 0.99, md
            checked["cyclic"] += 1
        if md.participation["rotor speed"] > 0.1:  # only collective motion changes the rotor speed
            assert cyclic[k] < 0.01, md
            checked["collective"] += 1
    assert checked["cyclic"] >= 5 and checked["collective"] >= 2  # the collective lag at ~62 Hz among them


def test_an_asymmetric_jacobian_is_solved_whole():
    """A Jacobian that does not commute with the exchange (here: one asymmetric entry) is not split:
    the result is numpy's full eigen-decomposition."""
    tr = _trimmed("rigid", "uniform")
    J = jacobian(tr.model, tr.state)
    J[3, 7] += 0.5 * np.abs(J).max()
    lam, V = eig_axial(tr.model, J)
    ref, ref_v = np.linalg.eig(J)
    assert np.array_equal(lam, ref) and np.array_equal(V, ref_v)
