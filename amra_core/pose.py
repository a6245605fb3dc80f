"""The rotor's shape at an instant, and a mode's shape through one cycle: what an animation draws.

:func:`rotor_pose` reads both blades' out-of-plane displacement (teeter included: w = beta r on a
rigid blade) and elastic twist at the aerodynamic stations from a state vector, through the same
kinematics the kernels use (:func:`amra_core.kernel_guard.station_loads`), so what is drawn is what
the solver integrates. :func:`mode_animation` gives the frames of one linear mode about the trim,
``Re(v e^{i phi})`` for phases phi through one cycle, for the mode nearest a given eigenvalue
(as the modes table lists it), normalised so the largest displacement over the cycle is 1 in the
unit the caller chooses to exaggerate (tip flap or twist): the shape is exact, its size is free.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import kernel_guard
from .model import S_C, S_R, S_XEA, Y_PSI, CompiledModel


@dataclass(frozen=True)
class RotorPose:
    """Both blades at one instant. ``r_m`` (n,) station radii [m]; ``flap_m`` (2, n) out-of-plane
    displacement of blades 0 and 1, teeter included, up positive [m]; ``twist_rad`` (2, n) elastic
    twist, nose-up positive [rad]; ``teeter_rad`` hub teeter angle [rad]; ``azimuth_rad`` blade 0's
    azimuth in [0, 2 pi); the section a drawing turns by the outermost twist: ``chord_m`` its chord
    [m], ``x_ea`` its elastic axis [chord fraction]; ``radius_m`` the rotor's radius [m]."""

    r_m: np.ndarray
    flap_m: np.ndarray
    twist_rad: np.ndarray
    teeter_rad: float
    azimuth_rad: float
    chord_m: float
    x_ea: float
    radius_m: float

    def to_dict(self) -> dict:
        return {"r_m": self.r_m.tolist(), "flap_m": self.flap_m.tolist(), "twist_rad": self.twist_rad.tolist(),
                "teeter_rad": self.teeter_rad, "azimuth_rad": self.azimuth_rad, "chord_m": self.chord_m,
                "x_ea": self.x_ea, "radius_m": self.radius_m}


def rotor_pose(model: CompiledModel, y: np.ndarray) -> RotorPose:
    """The pose of state ``y`` of ``model`` (shapes checked by the kernel guard)."""
    out = np.zeros((2, model.n_st, 5))
    kernel_guard.station_loads(np.ascontiguousarray(y, dtype=float), model.arrays, out)
    x, _ = model.physical(y)
    st = model.arrays.st
    return RotorPose(st[:, S_R].copy(), out[:, :, 4].copy(), out[:, :, 3].copy(), float(x[0]),
                     float(math.fmod(y[Y_PSI], 2 * math.pi)) % (2 * math.pi), float(st[-1, S_C]),
                     float(st[-1, S_XEA]), float(model.rotor.radius_m))


@dataclass(frozen=True)
class ModeAnimation:
    """One mode's frames through a cycle: ``eigenvalue`` (real part [1/s], imaginary [rad/s]) of the
    mode found; ``frames`` the poses' displacements about the trim, scaled so the largest flap
    displacement over the cycle is 1 (``scale`` ``"flap"``) or the largest twist is 1 (``"twist"``),
    the other quantity in the same ratio; ``phases_rad`` the phase of each frame."""

    eigenvalue: complex
    phases_rad: np.ndarray
    flap: np.ndarray  #: (n_frames, 2, n) normalised flap displacement
    twist: np.ndarray  #: (n_frames, 2, n) twist, in the same ratio
    teeter: np.ndarray  #: (n_frames,) teeter, in the same ratio as flap [rad per unit]
    scale: str
    flap_per_twist_m_rad: float  #: largest flap [m] per largest twist [rad] in this mode: its true mix


def _eigenpairs(model: CompiledModel, y0: np.ndarray):
    """(exponents, vectors without psi) of the linearisation about ``y0``: Jacobian eigenvalues in axial
    flight, Floquet exponents in forward flight at their modes' own frequencies, as the modes table's
    (:func:`amra_core.stability.floquet_modes`): matched against their principal values, a pick of
    the table's 24.6 Hz unstable mode (mu 0.3) animated a damped 2.77 Hz one."""
    from .blade_symmetry import eig_axial
    from .stability import floquet_modes, jacobian  # the modes table's own
    if model.flight.is_axial:
        return eig_axial(model, jacobian(model, y0))
    lam, vecs, _ = floquet_modes(model, y0)
    return lam, vecs


def mode_animation(model: CompiledModel, y0: np.ndarray, real_part_per_s: float, frequency_hz: float,
                   n_frames: int = 24, scale: str = "flap") -> ModeAnimation:
    """Frames of the mode of the linearisation about the trim ``y0`` whose exponent is nearest
    ``real_part_per_s + i 2 pi frequency_hz`` (a row of the modes table)."""
    if scale not in ("flap", "twist"):
        raise ValueError(f"scale = {scale!r} is not allowed: choose 'flap' or 'twist'")
    if not 2 <= int(n_frames) <= 360:
        raise ValueError(f"n_frames = {n_frames!r} is not allowed: must be an integer in [2, 360]")
    lam, vecs = _eigenpairs(model, y0)
    target = complex(real_part_per_s, 2 * math.pi * frequency_hz)
    k = min(range(len(lam)), key=lambda i: min(abs(lam[i] - target), abs(lam[i] - target.conjugate())))
    v = vecs[:, k]
    base = rotor_pose(model, y0)
    phases = np.linspace(0.0, 2 * math.pi, int(n_frames), endpoint=False)
    # the vectors leave out psi (Y_PSI = 0, the time-like coordinate): insert 0 for it. Flap and twist
    # are linear in the structural coordinates, so the step size only has to keep y0 + dy finite
    eps = 1e-3 / (np.max(np.abs(v)) or 1.0)
    flap, twist, teeter = [], [], []
    for ph in phases:
        dy = np.concatenate(([0.0], (v * np.exp(1j * ph)).real)) * eps
        p = rotor_pose(model, y0 + dy)
        flap.append((p.flap_m - base.flap_m) / eps)
        twist.append((p.twist_rad - base.twist_rad) / eps)
        teeter.append((p.teeter_rad - base.teeter_rad) / eps)
    flap, twist, teeter = np.array(flap), np.array(twist), np.array(teeter)
    f_max, t_max = float(np.max(np.abs(flap))), float(np.max(np.abs(twist)))
    norm = (f_max if scale == "flap" else t_max) or 1.0
    return ModeAnimation(complex(lam[k]), phases, flap / norm, twist / norm, teeter / norm, scale,
                         f_max / t_max if t_max > 0 else math.inf)
