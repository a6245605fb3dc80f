"""Floquet multipliers of a periodic orbit: the one-revolution transition matrix (monodromy) by
finite differences of marched revolutions, and its least damped multipliers by Arnoldi without
forming it. Below :mod:`amra_core.stability` (which turns them into modes and verdicts) and beside
:mod:`amra_core.trim`, which asks how stable the last point of a trim branch is."""
from __future__ import annotations

import math
from typing import Optional

import numpy as np

from . import kernel_guard, kernels
from .model import Y_OMEGA, CompiledModel

#: a mode with real part above this [1/s] is unstable (below: numerically neutral)
UNSTABLE_REAL_PART = 1e-3


#: relative difference steps of the monodromy's columns (see :func:`monodromy`)
FD_STEP_FORWARD = 3e-6
FD_STEP_CENTRAL = 1e-6


#: states kept per revolution of every marched revolution, to read each Floquet mode's harmonics
HARMONIC_SAMPLES = 64
#: a Floquet exponent is unfolded to its dominant harmonic among |h| <= this (h times the rotor speed)
MAX_HARMONIC = 12


def _one_revolution(model: CompiledModel, y0: np.ndarray, dt: float):
    """``(march, T, times)``: ``march(y, out=None)`` advances ``y`` in place by one revolution ``T``
    [s] of the rotor speed of ``y0``, in whole steps of at most ``dt`` (at least 32), and returns it;
    with ``out`` (``len(times)`` rows) it also writes the state without psi at ``times`` [s] along
    the way (about :data:`HARMONIC_SAMPLES`, the first at 0)."""
    steps = max(int(round(2 * math.pi / y0[Y_OMEGA] / dt)), 32)
    T = 2 * math.pi / y0[Y_OMEGA]
    every = max(1, steps // HARMONIC_SAMPLES)
    n_rec = (steps + every - 1) // every  # the kernel writes a row every `every` steps, from step 0
    times = np.arange(n_rec) * every * (T / steps)
    hist = np.zeros((n_rec, kernels.N_HIST)); st = np.zeros((n_rec, len(y0)))

    def march(y: np.ndarray, out=None) -> np.ndarray:
        kernel_guard.advance(y, 0.0, T / steps, steps, every, model.arrays, hist, st, -1.0)
        if out is not None:
            out[:] = st[:, 1:]
        return y
    return march, T, times


def harmonics(lam: np.ndarray, paths: np.ndarray, times: np.ndarray, T: float, omega: float):
    """``(h, C)``: the Fourier coefficients ``C[k, :, j]`` of harmonic ``h[k]`` (``|h| <=``
    :data:`MAX_HARMONIC`) of the periodic part of Floquet mode ``j``. A mode's linearised motion is
    ``exp(lam t) P(t)`` with ``P`` of period ``T`` (``lam`` principal, ``log(z) / T``), so
    ``P(t) = sum_h C_h exp(i h Omega t)`` and the mode moves at the frequencies ``Im(lam) + h Omega``
    at once: which one is "its" frequency is read from ``C`` (:func:`amra_core.stability.analyse`,
    after Bauchau & Nikishkov 2001, J. Am. Helicopter Soc. 46(3)).

    ``paths`` (``len(times)``, states, exponents): each exponent's eigenvector marched over one
    revolution (the linearised motion, from the monodromy's marches) at ``times`` [s] in [0, T)."""
    P = paths * np.exp(-np.outer(times, lam))[:, None, :]
    # trapezoids over [0, T], closed by the periodicity P(T) = P(0)
    w = 0.5 * np.diff(np.append(times, T))
    w[1:] += 0.5 * np.diff(times)
    w[0] += 0.5 * (T - times[-1])
    h = np.arange(-MAX_HARMONIC, MAX_HARMONIC + 1)
    E = np.exp(-1j * omega * np.outer(h, times)) * (w / T)[None, :]
    return h, np.einsum("ht,tnm->hnm", E, P)


def monodromy(model: CompiledModel, y0: np.ndarray, dt: float, scheme: str = "forward",
              observe: Optional[np.ndarray] = None):
    """One-revolution state transition (without psi); returns (Phi, T), with ``observe`` (signals:
    rows on the state without psi) also those signals of ``Phi(t_k, 0)`` at the ``times`` t_k of
    :func:`_one_revolution` (``(len(times), signals, n)``) and the times: ``(Phi, T, paths, times)``,
    for :func:`harmonics`.

    ``scheme='forward'`` (default): one-sided differences against one unperturbed march (n + 1
    marches of one revolution, relative step 3e-6: the best balance of truncation and round-off
    found; the least damped exponents agree with central differences to 2e-4 1/s, tested: 2e-5
    before the lag-pivot coupling of the twist's in-plane momentum). On the 16-column mu = 0.1 maps
    at EA 0.32 (2 %, 2026-12-01) both schemes give the same intervals in every fem-coupled column
    (167.6 s central against 118.7 s forward) and in 15 of 16 rigid ones (29.8 s against 20.8 s);
    at rigid CG 0.36 only central finds a flutter window 391-399 N m^2/rad directly above the fold,
    as wide as the tolerance (critical GJ 402 against 395);
    ``'central'``: central differences (2 n marches)."""
    if scheme not in ("forward", "central"):
        raise ValueError(f"scheme = {scheme!r} is not allowed: choose 'forward' or 'central'")
    march, T, times = _one_revolution(model, y0, dt)
    n = len(y0)
    Phi = np.zeros((n - 1, n - 1))
    paths = None if observe is None else np.zeros((len(times), len(observe), n - 1))  # G Phi(t_k, 0), by columns
    # the states along the marches are copied out only when their signals are asked for
    a, b = (None, None) if observe is None else (np.zeros((len(times), n - 1)), np.zeros((len(times), n - 1)))
    if scheme == "forward":
        yb = march(y0.copy(), b)
    for i in range(1, n):
        h = (FD_STEP_FORWARD if scheme == "forward" else FD_STEP_CENTRAL) * max(1.0, abs(y0[i]))
        yp = y0.copy(); yp[i] += h
        march(yp, a)
        if scheme == "forward":
            Phi[:, i - 1] = (yp[1:] - yb[1:]) / h
            if paths is not None:
                paths[:, :, i - 1] = (a - b) @ observe.T / h
        else:
            ym = y0.copy(); ym[i] -= h
            march(ym, b)
            Phi[:, i - 1] = (yp[1:] - ym[1:]) / (2 * h)
            if paths is not None:
                paths[:, :, i - 1] = (a - b) @ observe.T / (2 * h)
    if paths is not None:
        return Phi, T, paths, times
    return Phi, T


#: least damped Floquet multipliers the Krylov scheme resolves (``analyse(..., "krylov")``)
KRYLOV_MODES = 20
#: largest Krylov dimension (one revolution each); a model with fewer states gets its full matrix
KRYLOV_MAX_DIM = 64
#: Ritz residual of each resolved multiplier, relative to its magnitude
KRYLOV_TOL = 1e-8


def floquet_krylov(model: CompiledModel, y0: np.ndarray, dt: float, n_modes: int = KRYLOV_MODES,
                   observe: Optional[np.ndarray] = None):
    """The ``n_modes`` largest Floquet multipliers (the least damped modes; a complex pair counts
    twice) and their eigenvectors by Arnoldi on the monodromy matrix, which is never formed: each
    Krylov vector costs one perturbed revolution, the one-sided difference of :func:`monodromy`
    along that direction (relative step 3e-6 of each state's scale ``max(1, |y|)``, the same
    diagonal scaling on both sides, so the spectrum is the monodromy's).

    The multipliers of the Wagner lag states (e^(-T/tau), about 1e-3 here) and of the well damped
    structural modes form a cluster far inside the least damped few, so those converge in about
    half the ``n + 1`` revolutions of the full matrix (32 of 66 at rigid, 51-54 of 106 at
    fem-coupled, mu 0.1: ``tests/core/test_column.py``). Deterministic (a fixed start vector), so a
    map is repeatable.
    Returns ``(z, V, T, revolutions, n_resolved, converged)``: the Ritz values sorted by magnitude
    (descending; the first ``n_resolved`` are the resolved multipliers, the rest are rough
    estimates of the remaining spectrum), their vectors (columns, state without psi), the period
    [s], the revolutions marched, and whether the resolved ones met :data:`KRYLOV_TOL` within
    :data:`KRYLOV_MAX_DIM` vectors (:func:`analyse` forms the full matrix when they did not).
    ``observe`` (signals: rows on the state without psi): also those signals of each Ritz vector's
    linearised motion over the revolution, at the ``times`` of :func:`_one_revolution`
    (``(len(times), signals, Ritz values)``), for :func:`harmonics`: ``(..., converged, paths, times)``."""
    march, T, times = _one_revolution(model, y0, dt)
    n = len(y0) - 1
    scale = np.maximum(1.0, np.abs(y0[1:]))
    # the states along the marches are copied out only when their signals are asked for
    b, a = (None, None) if observe is None else (np.zeros((len(times), n)), np.zeros((len(times), n)))
    base = march(y0.copy(), b)[1:]
    W = None if observe is None else np.zeros((len(times), len(observe), min(n, KRYLOV_MAX_DIM)))  # G Phi(t) D Q_j
    m_max = min(n, KRYLOV_MAX_DIM)
    Q = np.zeros((n, m_max + 1)); H = np.zeros((m_max + 1, m_max))
    q = np.random.default_rng(20261206).standard_normal(n)
    Q[:, 0] = q / np.linalg.norm(q)
    revs = 1
    for j in range(m_max):
        y = y0.copy(); y[1:] += FD_STEP_FORWARD * scale * Q[:, j]
        w = (march(y, a)[1:] - base) / FD_STEP_FORWARD / scale
        if W is not None:  # the physical motion along D Q_j (the Ritz vectors' D Q s are physical too)
            W[:, :, j] = (a - b) @ observe.T / FD_STEP_FORWARD
        revs += 1
        for _ in range(2):  # classical Gram-Schmidt, twice: orthogonal to round-off
            c = Q[:, :j + 1].T @ w
            w -= Q[:, :j + 1] @ c
            H[:j + 1, j] += c
        H[j + 1, j] = np.linalg.norm(w)
        invariant = H[j + 1, j] <= 1e-12 * np.abs(H[:j + 1, :j + 1]).max()
        if not invariant:
            Q[:, j + 1] = w / H[j + 1, j]
        if j + 1 >= min(n_modes + 2, m_max) or invariant:
            th, S = np.linalg.eig(H[:j + 1, :j + 1])
            keep = _largest(th, n_modes)
            res = np.abs(H[j + 1, j] * S[j, keep])
            converged = invariant or j + 1 == n or bool(np.all(res <= KRYLOV_TOL * np.abs(th[keep])))
            if converged or j + 1 == m_max:
                break
    order = np.argsort(-np.abs(th), kind="stable")  # the resolved ones (keep) first, then the rest
    out = (th[order], scale[:, None] * (Q[:, :j + 1] @ S[:, order]), T, revs, len(keep), converged)
    if W is not None:
        return (*out, W[:, :, :j + 1] @ S[:, order], times)
    return out


def _largest(values: np.ndarray, k: int) -> np.ndarray:
    """Indices of the ``k`` largest ``values`` in magnitude, descending, with a complex pair kept whole."""
    order = np.argsort(-np.abs(values), kind="stable")
    if len(order) <= k:
        return order
    cut = np.abs(values[order[k - 1]]) * (1.0 - 1e-9)
    return order[np.abs(values[order]) >= cut]
