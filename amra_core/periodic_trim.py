"""Forward-flight trim continued from a neighbouring trim (issue 8 §5: maps along a column).

The residuals are those of :func:`amra_core.trim.trim_forward` (revolution averages of torque,
vertical and horizontal rotor force of the gliding isolated rotor, over rotor speed, descent rate
and shaft tilt, with the blade motion converged by marching). What changes along a column walk is
the work: the march starts from the neighbour's periodic state, the advance ratio is held inside
every evaluation (airspeed = mu Omega R / cos(tilt), no outer fixed point), and the Newton
iteration starts from the neighbour's Jacobian and updates it by Broyden's rule, so a step costs
tens of revolutions instead of a fresh finite-difference Jacobian per iteration. Each trial's
blade motion is shot onto its periodic orbit (:mod:`amra_core.shooting`) with a matrix the walk
forms once and again when its GJ has moved by a quarter, so an evaluation costs two revolutions
and its averages carry no slow transient.
"""
from __future__ import annotations

import math
from typing import Optional

import numpy as np

from . import kernels
from .model import CompiledModel, Y_OMEGA, Y_V0, Y_VD, stable_time_step, transfer_state
from .equilibrium import TrimResult, _march_revs, gj_mean_of, omega_guess
from . import verdict
from .shooting import PeriodicShooting

_H = {c: i for i, c in enumerate(kernels.HISTORY_COLUMNS)}
#: residual tolerance (as trim_forward: max of the scaled residuals)
TOL = 2e-4
_LIM = np.array([5.0, 2.0, math.radians(2.0)])  # largest Newton update of omega, vd, tilt
_FD = np.array([0.2, 0.1, math.radians(0.2)])  # finite-difference steps
#: a walk's shooting matrix serves trims within this distance in log GJ of the one it was formed at
SHOOTING_REUSE_LN_GJ = math.log(1.25)


class PeriodicContinuation:
    """Holds the Jacobian between the steps of one column walk (one instance per walk)."""

    def __init__(self):
        self.J: Optional[np.ndarray] = None
        self.revolutions = 0
        self.shooting = PeriodicShooting()  #: the walk's shooting matrix (formed again far from its GJ)
        self._shooting_gj = math.nan

    def _airspeed(self, model: CompiledModel, omega: float, tilt: float) -> float:
        fl = model.flight
        if fl.mu is not None:
            return fl.mu * omega * model.rotor.radius_m / math.cos(tilt)
        return fl.airspeed_m_s

    def _held(self, model: CompiledModel, z) -> CompiledModel:
        """``model`` at the trial (rotor speed, descent rate, tilt) ``z``, both speeds held."""
        return model.with_controls(alpha_s_rad=z[2], airspeed_m_s=self._airspeed(model, z[0], z[2]),
                                   hold_omega=True, hold_vd=True)

    def _evaluate(self, model, y, z, n_revs, dt):
        m = self._held(model, z)
        y[Y_OMEGA], y[Y_VD] = z[0], z[1]
        if self.shooting.lu is not None:  # onto this trial's periodic orbit, then one revolution
            y, _ = self.shooting.project(m, y, dt)
            self.revolutions += 1
            n_revs = 1
        y, avg, last = _march_revs(m, y, n_revs, dt)
        self.revolutions += n_revs
        w = model.rotor.vehicle_mass_kg * model.flight.gravity_m_s2
        res = np.array([avg[_H["torque_nm"]] / (0.05 * w * model.rotor.radius_m),
                        avg[_H["vertical_force_n"]] / w - 1.0, avg[_H["horizontal_force_n"]] / w])
        return y, res, avg, last

    def _fd_jacobian(self, model, y, z, res, dt):
        J = np.zeros((3, 3))
        for k in range(3):
            zp = z.copy(); zp[k] += _FD[k]
            _, rp, _, _ = self._evaluate(model, y.copy(), zp, 3, dt)
            J[:, k] = (rp - res) / _FD[k]
        return J

    def step(self, model: CompiledModel, prev: TrimResult, prev2: Optional[TrimResult] = None, s: float = 1.0,
             max_iter: int = 14) -> TrimResult:
        """The free-autorotation forward trim of ``model`` continued from ``prev`` (a trim of a
        neighbouring model; with ``prev2`` the rotor speed, descent rate and tilt start from the secant
        ``prev + s (prev - prev2)``). ``no-autorotation`` when it does not converge, also with a
        shooting matrix formed at this GJ (a reused one misleads the projection where a mode's
        multiplier nears 1: rigid mu 0.1 CG 0.36 stopped at GJ 469 instead of 391)."""
        res = self._step(model, prev, prev2, s, max_iter)
        if not res.ok and self.shooting.lu is not None and self._shooting_gj != gj_mean_of(model):
            self.shooting = PeriodicShooting()
            res = self._step(model, prev, prev2, s, max_iter)
        return res

    def _step(self, model: CompiledModel, prev: TrimResult, prev2: Optional[TrimResult], s: float,
              max_iter: int) -> TrimResult:
        y = transfer_state(prev.state, prev.model, model)
        z = np.array([prev.omega_rad_s, prev.descent_rate_m_s, prev.disk_tilt_rad])
        if prev2 is not None and s:
            z = z + s * (z - np.array([prev2.omega_rad_s, prev2.descent_rate_m_s, prev2.disk_tilt_rad]))
        dt = stable_time_step(model, z[0])
        try:
            gj = gj_mean_of(model)
            if not self.shooting.fits(model) or abs(math.log(gj / self._shooting_gj)) > SHOOTING_REUSE_LN_GJ:
                self.shooting = PeriodicShooting()
            y, res, avg, last = self._evaluate(model, y, z, 6, dt)
            if self.shooting.lu is None:
                self.revolutions += self.shooting.build(self._held(model, z), y, dt)
                self._shooting_gj = gj
                y, res, avg, last = self._evaluate(model, y, z, 1, dt)
            J = self.J.copy() if self.J is not None else self._fd_jacobian(model, y, z, res, dt)
            fresh = self.J is None
            for it in range(max_iter):
                if np.max(np.abs(res)) < TOL:
                    break
                try:
                    dz = -np.linalg.solve(J, res)
                except np.linalg.LinAlgError:
                    dz = None
                if dz is None or not np.all(np.isfinite(dz)):
                    if fresh:
                        break
                    J, fresh = self._fd_jacobian(model, y, z, res, dt), True
                    continue
                dz = np.clip(dz, -_LIM, _LIM)
                y, res_new, avg, last = self._evaluate(model, y, z + dz, 4, dt)
                z = z + dz
                J = J + np.outer((res_new - res) - J @ dz, dz) / float(dz @ dz)  # Broyden
                if it == max_iter // 2 and not fresh and np.max(np.abs(res_new)) > 10 * TOL:
                    J, fresh = self._fd_jacobian(model, y, z, res_new, dt), True  # the update went astray
                res = res_new
        except FloatingPointError as exc:
            return TrimResult("no-autorotation", reason=str(exc), model=model)
        ok = (np.max(np.abs(res)) < 1e-3 and np.all(np.isfinite(y))
              and 0.2 * omega_guess(model) < z[0] < 4 * omega_guess(model))
        if not ok:
            return TrimResult("no-autorotation", reason=f"continued forward-flight trim did not converge "
                                                        f"(residuals {np.round(res, 4).tolist()})", model=model)
        self.J = J
        v = self._airspeed(model, z[0], z[2])
        final = model.with_controls(alpha_s_rad=z[2], airspeed_m_s=v, hold_omega=False, hold_vd=False)
        return TrimResult("trimmed", y.copy(), float(z[0]), float(z[1]), float(z[2]), v, float(y[Y_V0]),
                          float(avg[_H["thrust_n"]]), float(avg[_H["torque_nm"]]), verdict.teeter_amplitude_rad(last),
                          float(np.mean(last[:, _H["tip_twist_0_rad"]])), model=final)
