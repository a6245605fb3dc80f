"""Jitted section-coefficient lookup (the kernel half of :mod:`amra_core.airfoil`).
Compiled under the floating-point policy of :mod:`amra_core.jit` (fast math without ``reassoc``).

Kept apart from the table loading and resampling (which use SciPy and files) so the jitted core
imports only jitted code: :mod:`amra_core.kernels` calls :func:`airfoil_coefficients` on the
uniform grids that :func:`amra_core.airfoil.compile_airfoil` builds.
"""
from __future__ import annotations

import math

import numpy as np

from .jit import kernel

MACH_CLIP = 0.7  #: Mach number at which the Prandtl-Glauert factor is capped [-].
PG_FULL_DEG = 10.0  #: |alpha| up to which the full Prandtl-Glauert factor applies [deg].
PG_NONE_DEG = 20.0  #: |alpha| from which no Prandtl-Glauert factor applies [deg].


@kernel
def airfoil_coefficients(alpha_rad, mach, alpha0_rad, dalpha_rad, cl_grid, cd_grid, cm_grid):
    """Section Cl, Cd, Cm at an angle of attack and Mach number (jitted).

    Alpha is wrapped into [-pi, pi) and the uniform grid of :func:`compile_airfoil`
    is interpolated linearly (index computed directly, no search).

    Mach correction (the only one): Prandtl-Glauert factor ``1/sqrt(1 - M^2)``
    on Cl in the attached-flow range only, with M clipped to [0, 0.7] inside
    the factor: full factor for |alpha| <= 10 deg, fading linearly to none at
    |alpha| = 20 deg, none beyond. The reverse-flow attached range about
    +/-180 deg is NOT corrected. Cd and Cm get no Mach correction: NACA 0012
    drag divergence is near M 0.75, above the tip Mach (~0.5) of the rotors in
    scope, and the tables give no compressible Cm data.

    Parameters
    ----------
    alpha_rad : float
        Angle of attack [rad], any value (wrapped).
    mach : float
        Local Mach number [-].
    alpha0_rad, dalpha_rad, cl_grid, cd_grid, cm_grid
        The fields of :class:`AirfoilArrays` ([rad], [rad], [-], [-], [-]).

    Returns
    -------
    cl, cd, cm : float
        Lift, drag and quarter-chord moment coefficients [-].
    """
    two_pi = 2.0 * math.pi
    a = alpha_rad - two_pi * math.floor((alpha_rad + math.pi) / two_pi)
    x = (a - alpha0_rad) / dalpha_rad
    i = int(math.floor(x))
    n = cl_grid.shape[0]
    if i < 0:
        i = 0
    elif i > n - 2:
        i = n - 2
    t = x - i
    cl = cl_grid[i] + t * (cl_grid[i + 1] - cl_grid[i])
    cd = cd_grid[i] + t * (cd_grid[i + 1] - cd_grid[i])
    cm = cm_grid[i] + t * (cm_grid[i + 1] - cm_grid[i])
    m = min(max(mach, 0.0), MACH_CLIP)
    if m > 0.0:
        abs_deg = abs(a) * (180.0 / math.pi)
        if abs_deg < PG_NONE_DEG:
            f = 1.0 / math.sqrt(1.0 - m * m)
            if abs_deg <= PG_FULL_DEG:
                cl *= f
            else:
                cl *= 1.0 + (PG_NONE_DEG - abs_deg) / (PG_NONE_DEG - PG_FULL_DEG) * (f - 1.0)
    return cl, cd, cm


@kernel
def _coefficients_many(alpha_rad, mach, alpha0_rad, dalpha_rad, cl_grid, cd_grid, cm_grid):
    n = alpha_rad.shape[0]
    out = np.empty((3, n))
    for k in range(n):
        out[0, k], out[1, k], out[2, k] = airfoil_coefficients(
            alpha_rad[k], mach[k], alpha0_rad, dalpha_rad, cl_grid, cd_grid, cm_grid)
    return out
