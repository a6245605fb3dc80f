"""Jitted section-coefficient lookup (the kernel half of :mod:`amra_core.airfoil`).
Compiled under the floating-point policy of :mod:`amra_core.jit` (fast math without ``reassoc``).

Kept apart from the table loading and resampling (which use SciPy and files) so the jitted core
imports only jitted code: :mod:`amra_core.kernels` calls :func:`airfoil_coefficients` on the
uniform grids that :func:`amra_core.airfoil.compile_airfoil` builds.
"""
from __future__ import annotations

import math

import numpy as np

from .jit import inline_kernel, kernel

#: hash of the amra_core modules imported above: Numba's cache does not see them
#: (tests/core/test_kernel_cache_stamps.py)
CACHE_STAMP = "29b2b72e9273f3e8"

MACH_CLIP = 0.7  #: Mach number at which the Prandtl-Glauert factor is capped [-].
PG_FULL_DEG = 10.0  #: |alpha| up to which the full Prandtl-Glauert factor applies [deg].
PG_NONE_DEG = 20.0  #: |alpha| from which no Prandtl-Glauert factor applies [deg].


@inline_kernel
def clamp(x, lo, hi):
    """``x`` limited to [lo, hi] (NaN passes through), by selects: Numba's ``min``/``max`` builtins
    keep a loop from being vectorised."""
    return lo if x < lo else (hi if x > hi else x)


@inline_kernel
def table_position(alpha_rad, alpha0_rad, dalpha_rad, n):
    """Where an angle of attack falls on a uniform grid of ``n`` points from ``alpha0_rad`` in steps
    of ``dalpha_rad``: (cell index as a float, clamped to [0, n - 2]; fraction of the cell;
    the angle wrapped into [-pi, pi)). Branch-free (vectorisable); the index is made an integer,
    and clamped again as one, by :func:`table_values`."""
    two_pi = 2.0 * math.pi
    a = alpha_rad - two_pi * math.floor((alpha_rad + math.pi) / two_pi)
    x = (a - alpha0_rad) / dalpha_rad
    cell = clamp(math.floor(x), 0.0, n - 2.0)
    return cell, x - cell, a


@inline_kernel
def table_values(cell, frac, cl_grid, cd_grid, cm_grid):
    """Cl, Cd, Cm interpolated linearly in cell ``cell`` at ``frac`` (from :func:`table_position`).
    The index is clamped as an integer, so even a NaN angle reads inside the grids."""
    i = min(max(int(cell), 0), cl_grid.shape[0] - 2)
    cl = cl_grid[i] + frac * (cl_grid[i + 1] - cl_grid[i])
    cd = cd_grid[i] + frac * (cd_grid[i + 1] - cd_grid[i])
    cm = cm_grid[i] + frac * (cm_grid[i + 1] - cm_grid[i])
    return cl, cd, cm


@inline_kernel
def mach_factor(alpha_wrapped_rad, mach):
    """The factor on Cl of the Mach correction (see :func:`airfoil_coefficients`), branch-free:
    ``1 + w (PG - 1)`` with ``w`` 1 up to PG_FULL_DEG, fading linearly to 0 at PG_NONE_DEG."""
    m = clamp(mach, 0.0, MACH_CLIP)
    pg = 1.0 / math.sqrt(1.0 - m * m)
    abs_deg = abs(alpha_wrapped_rad) * (180.0 / math.pi)
    w = clamp((PG_NONE_DEG - abs_deg) * (1.0 / (PG_NONE_DEG - PG_FULL_DEG)), 0.0, 1.0)
    return 1.0 + w * (pg - 1.0)


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

    The three steps (:func:`table_position`, :func:`table_values`, :func:`mach_factor`) are the
    ones the right-hand side runs over all blade stations at once, so both give the same numbers.

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
    cell, frac, a = table_position(alpha_rad, alpha0_rad, dalpha_rad, cl_grid.shape[0])
    cl, cd, cm = table_values(cell, frac, cl_grid, cd_grid, cm_grid)
    return cl * mach_factor(a, mach), cd, cm


@kernel
def _coefficients_many(alpha_rad, mach, alpha0_rad, dalpha_rad, cl_grid, cd_grid, cm_grid):
    n = alpha_rad.shape[0]
    out = np.empty((3, n))
    for k in range(n):
        out[0, k], out[1, k], out[2, k] = airfoil_coefficients(
            alpha_rad[k], mach[k], alpha0_rad, dalpha_rad, cl_grid, cd_grid, cm_grid)
    return out
