"""The periodic blade motion of forward flight, by Newton shooting on the slow states.

A forward-flight trim needs, at each trial of rotor speed, descent rate and shaft tilt, the blade
motion that repeats every revolution. Marching to it waits for the least damped mode: the lag
mode of the coupled blade (8.5 Hz, damping ratio 0.018 near GJ 1500 N m²/rad at mu 0.3) keeps
about 85 % of a disturbance per revolution, so four revolutions leave half of it and the
revolution averages the trim balances wander by about 1e-3 of the weight.

Shooting solves the periodicity ``P(y) = y`` (``P``: one revolution of the held-speed model)
directly. Its Jacobian is taken over the *slow* states only: teeter, lag, the structural
coordinates and their rates, inflow and the inflow harmonics. The Wagner lag states (time
constants of 3 to 25 ms against a revolution of 170 ms) forget their start within a revolution,
so their columns of the one-revolution transition matrix are nil and they follow the slow ones.
With ``Phi_s``, the columns of the transition matrix for the slow states (one revolution per
column), one Newton step from any ``y`` near the orbit is

    ds = (I - Phi_ss)^-1 (P_s(y) - y_s),    y* = P(y) + Phi_s ds

for the whole state (azimuth advanced by one revolution). ``Phi_s`` is reused while the controls
change (a chord Newton: the projection's own error shrinks with each step the trim takes); the
callers form it again when their iteration stalls with it (:func:`amra_core.equilibrium.trim_forward`,
:class:`amra_core.periodic_trim.PeriodicContinuation`). A *settling* shooting
(:attr:`PeriodicShooting.settle`) repeats the step until the gap is below :data:`SETTLE_GAP`, and
forms the matrix again where a step does not halve the gap. On an unstable orbit, one step leaves
a gap that the next revolution amplifies. The continuation in advance ratio retries a failed step
this way (:func:`amra_core.equilibrium.trim_forward_continued`).

A matrix reused at another GJ is first written in that model's structural coordinates. At the FEM
levels they are modal, and the modes come from an eigensolver: from one GJ to the next a mode may
change sign, and the two blades' nearly equal-frequency pairs turn within their plane. Used in the
wrong coordinates, the matrix threw the projection off (fem-torsion, McCutcheon, mu 0.5: the trim's
continuation in GJ ended its branch anywhere from mean GJ 2041 to 2989 N m^2/rad for seven GJ
values within 1 % of the blade's own 1478; in the right coordinates, 2097-2175). What still stops the
continuation there: below GJ 3,000-4,000 that periodic orbit is unstable (Floquet multipliers -2.6
to -5.5 per revolution), and the revolution marched after one projection amplifies what is left
of the periodicity gap. Whether the blade's own GJ then trims (35.90 rad/s on one machine) or the
branch ends near 2100 (on another) depends on the last bits; :func:`amra_core.trim.trim` says
when such an end is on an unstable orbit and so not shown to be a fold.
"""
from __future__ import annotations

import math

import numpy as np

from . import kernel_guard, kernels
from .model import CompiledModel, Y_OMEGA, Y_PSI, Y_VD

#: relative finite-difference step of a column (as stability.monodromy's forward scheme)
FD_STEP = 3e-6
#: a settling projection (:attr:`PeriodicShooting.settle`) repeats the Newton step while the
#: periodicity gap [state units] is above this, at most :data:`SETTLE_PROJECTIONS` more times
SETTLE_GAP = 1e-7
SETTLE_PROJECTIONS = 4
#: matrices a settling shooting forms again at most (each costs a revolution per slow state: 55 at
#: fem-coupled); past them it settles with the one it has. The settled trims that converged formed up
#: to 15 (rigid), 16 (fem-torsion) and 6 (fem-coupled) (McCutcheon, mu 0.5); one that did not went on
#: to 215 (fem-coupled, 11 s of an 18 s trim).
SETTLE_BUILDS = 16


def slow_states(model: CompiledModel) -> np.ndarray:
    """Indices of the states shooting solves for: all but azimuth, the held rotor speed and
    descent rate, and the Wagner lag states."""
    wagner = model.aero_slice()
    return np.array([i for i in range(model.n_y) if i not in (Y_PSI, Y_OMEGA, Y_VD)
                     and not wagner.start <= i < wagner.stop], dtype=np.int64)


def steps_per_rev(omega_rad_s: float, dt: float) -> tuple:
    """(steps, step [s]) of one revolution in whole steps no longer than ``dt``."""
    steps = max(int(round(2 * math.pi / max(omega_rad_s, 1.0) / dt)), 16)
    return steps, 2 * math.pi / max(omega_rad_s, 1.0) / steps


def one_rev(model: CompiledModel, y: np.ndarray, dt: float) -> np.ndarray:
    """The state one revolution after ``y`` (rotor speed and descent rate held by the model)."""
    steps, h = steps_per_rev(y[Y_OMEGA], dt)
    out = y.copy()
    hist = np.zeros((1, kernels.N_HIST)); st = np.zeros((1, len(y)))
    _, _, status = kernel_guard.advance(out, 0.0, h, steps, 10**9, model.arrays, hist, st, -1.0)
    if status != 0:
        raise FloatingPointError("non-finite state while shooting for the periodic solution")
    return out


class PeriodicShooting:
    """Newton shooting onto the periodic orbit (module docstring); ``revolutions`` counts the
    revolutions it marched."""

    def __init__(self):
        self.phi_s = None  #: (n_y, n_slow) one-revolution transition columns of the slow states
        self.lu = None  #: I - Phi_ss, factored
        self.idx = None
        self.basis = None  #: the structural basis (``CompiledModel.phi``) the matrix is written in
        self.revolutions = 0
        self.builds = 0
        #: True: :meth:`project` repeats its Newton step until the gap is below :data:`SETTLE_GAP`, and
        #: forms the matrix again at the current state when a step does not halve the gap (module
        #: docstring: the fallback of a failed continuation step)
        self.settle = False
        self.settle_builds = 0  #: matrices formed again by settling projections (at most SETTLE_BUILDS)

    def fits(self, model: CompiledModel) -> bool:
        """True if a matrix is formed and for ``model``'s state layout (the retained modes change
        with GJ at the fem fidelities)."""
        return (self.lu is not None and self.phi_s.shape[0] == model.n_y
                and np.array_equal(self.idx, slow_states(model)))

    def copy(self) -> "PeriodicShooting":
        """The same matrix, with its own counters (the matrix itself is never changed in place)."""
        out = PeriodicShooting()
        out.phi_s, out.lu, out.idx, out.basis = self.phi_s, self.lu, self.idx, self.basis
        return out

    def _in_basis_of(self, model: CompiledModel) -> None:
        """Write the matrix in ``model``'s structural coordinates (module docstring): with ``T`` the
        map from the old coordinates to the new ones (``phi_pinv_new @ phi_old``, both states' physical
        FEM coordinates alike) and ``S`` the state map (``T`` on the coordinates and on their rates,
        identity elsewhere), the matrix becomes ``S Phi_s S_ss^-1``. New arrays: copies sharing
        the old ones keep them."""
        import scipy.linalg as sla
        if model.phi is self.basis or np.array_equal(model.phi, self.basis):
            return
        t = model.phi_pinv @ self.basis
        s = np.eye(model.n_y)
        s[model.x_slice(), model.x_slice()] = t
        s[model.xd_slice(), model.xd_slice()] = t
        s_ss = s[np.ix_(self.idx, self.idx)]
        self.phi_s = np.linalg.solve(s_ss.T, (s @ self.phi_s).T).T
        self.lu = sla.lu_factor(np.eye(len(self.idx)) - self.phi_s[self.idx])
        self.basis = model.phi

    def build(self, model: CompiledModel, y: np.ndarray, dt: float) -> int:
        """Form the slow columns of the one-revolution transition matrix at ``y``; returns the
        revolutions that took."""
        import scipy.linalg as sla
        idx = slow_states(model)
        base = one_rev(model, y, dt)
        phi = np.empty((len(y), len(idx)))
        for j, i in enumerate(idx):
            h = FD_STEP * max(1.0, abs(y[i]))
            yp = y.copy(); yp[i] += h
            phi[:, j] = (one_rev(model, yp, dt) - base) / h
        self.revolutions += len(idx) + 1
        self.builds += 1
        self.idx, self.phi_s, self.basis = idx, phi, model.phi
        self.lu = sla.lu_factor(np.eye(len(idx)) - phi[idx])
        return len(idx) + 1

    def project(self, model: CompiledModel, y: np.ndarray, dt: float) -> tuple:
        """A Newton step towards the periodic orbit from ``y`` (one revolution marched; with
        :attr:`settle`, repeated until the orbit is reached); returns (the new state, the periodicity
        error it started from: max |P_s(y) - y_s|)."""
        out, gap0 = self._step(model, y, dt)
        gap = gap0
        for _ in range(SETTLE_PROJECTIONS if self.settle else 0):
            if gap < SETTLE_GAP:
                break
            nxt, new_gap = self._step(model, out, dt)
            if new_gap > 0.5 * gap and self.settle_builds < SETTLE_BUILDS:  # the matrix no longer
                self.settle_builds += 1                                       # serves: form it here
                self.build(model, out, dt)
                nxt, new_gap = self._step(model, out, dt)
            out, gap = nxt, new_gap
        return out, gap0

    def _step(self, model: CompiledModel, y: np.ndarray, dt: float) -> tuple:
        import scipy.linalg as sla
        self._in_basis_of(model)
        p = one_rev(model, y, dt)
        self.revolutions += 1
        gap = p[self.idx] - y[self.idx]
        ds = sla.lu_solve(self.lu, gap)
        out = p + self.phi_s @ ds
        out[Y_OMEGA], out[Y_VD] = y[Y_OMEGA], y[Y_VD]
        return out, float(np.max(np.abs(gap)))
