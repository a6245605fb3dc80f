"""Full-range (+/-180 deg) NACA 0012 section aerodynamics for jitted kernels.

Data path: table file in ``assets/airfoils/`` -> :func:`load_airfoil`
(:class:`AirfoilTable`, validated, origin line kept) -> :func:`compile_airfoil`
(:class:`AirfoilArrays`: coefficients resampled by PCHIP onto a uniform fine
grid) -> :func:`airfoil_coefficients` (``@kernel``, O(1) linear lookup plus
a Mach correction of the attached-flow lift, see its docstring).

Conventions: angle of attack in radians inside kernels (degrees in tables),
coefficients per unit span based on chord, Cm about the quarter chord,
positive nose-up (TN 3361 convention; the digitised file does not state the
reference point - to be verified, as its origin line says).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

# the jitted lookup and its Mach-correction constants live in amra_core.airfoil_kernel
from .airfoil_kernel import MACH_CLIP, PG_FULL_DEG, PG_NONE_DEG, _coefficients_many, airfoil_coefficients  # noqa: F401

#: Directory of the shipped airfoil tables.
AIRFOIL_DIR = Path(__file__).resolve().parents[1] / "assets" / "airfoils"

#: Available table names -> file in :data:`AIRFOIL_DIR`.
AIRFOIL_FILES = {
    "naca0012_critzos": "naca0012_critzos_tn3361_re1p8e6.csv",  # Re 1.8e6, Cl Cd Cm
    "naca0012_sheldahl360k": "naca0012_sheldahl_klimas_re360k.dat",  # Re 3.6e5, no Cm
}

#: Tables of symmetric sections whose attached range is symmetrised on loading, with the
#: half-range [deg] (see :func:`symmetrised` and assets/airfoils/README.md).
SYMMETRISE_DEG = {"naca0012_critzos": 15.0}



@dataclass(frozen=True)
class AirfoilTable:
    """A section table as read from its file (degrees, dimensionless coefficients).

    Attributes
    ----------
    name : str
        Registry name (a key of :data:`AIRFOIL_FILES`, or free text).
    origin : str
        The file's origin line (text after the leading ``#``).
    alpha_deg : tuple of float
        Angle of attack [deg], strictly increasing from -180 to 180.
    cl, cd, cm : tuple of float
        Lift, drag and quarter-chord moment coefficients [-]; ``cm`` is all
        zeros when the source has no moment data.
    has_cm : bool
        Whether the source provides Cm.
    """

    name: str
    origin: str
    alpha_deg: tuple
    cl: tuple
    cd: tuple
    cm: tuple
    has_cm: bool = True

    def __post_init__(self):
        cols = {k: tuple(float(v) for v in getattr(self, k)) for k in ("alpha_deg", "cl", "cd", "cm")}
        for k, v in cols.items():
            object.__setattr__(self, k, v)
        a = np.asarray(self.alpha_deg)
        if len({len(v) for v in cols.values()}) != 1 or a.size < 4:
            raise ValueError(f"airfoil {self.name!r}: columns must have equal length >= 4")
        if not all(np.all(np.isfinite(v)) for v in cols.values()):
            raise ValueError(f"airfoil {self.name!r}: non-finite value in table")
        if np.any(np.diff(a) <= 0.0):
            raise ValueError(f"airfoil {self.name!r}: alpha must be strictly increasing")
        if abs(a[0] + 180.0) > 1e-9 or abs(a[-1] - 180.0) > 1e-9:
            raise ValueError(f"airfoil {self.name!r}: alpha must run from -180 to 180 deg, "
                             f"got {a[0]} .. {a[-1]}")


class AirfoilArrays(NamedTuple):
    """Uniform-grid coefficients for :func:`airfoil_coefficients`.

    The field order matches the kernel's trailing arguments, so
    ``airfoil_coefficients(alpha, mach, *arrays)`` works.

    Attributes
    ----------
    alpha0_rad : float
        First grid angle, -pi [rad].
    dalpha_rad : float
        Grid step [rad].
    cl, cd, cm : ndarray of float64
        Coefficients [-] at ``alpha0_rad + i * dalpha_rad``, i = 0..n (the last
        point is +pi and equals the first).
    """

    alpha0_rad: float
    dalpha_rad: float
    cl: np.ndarray
    cd: np.ndarray
    cm: np.ndarray


def load_airfoil(name: str = "naca0012_critzos", raw: bool = False) -> AirfoilTable:
    """Read a shipped table from ``assets/airfoils``.

    Parameters
    ----------
    name : str
        One of :data:`AIRFOIL_FILES`: ``"naca0012_critzos"`` (default; NACA TN 3361,
        Re 1.8e6, Cl/Cd/Cm) or ``"naca0012_sheldahl360k"`` (SAND80-2114, Re 3.6e5, no Cm).
    raw : bool
        False (default): tables listed in :data:`SYMMETRISE_DEG` come back with their attached
        range symmetrised (:func:`symmetrised`), as the solver uses them. True: the file's
        points as digitised.

    Returns
    -------
    AirfoilTable

    Raises
    ------
    ValueError
        Unknown name (the message lists the available names) or invalid table.
    """
    if name not in AIRFOIL_FILES:
        raise ValueError(f"unknown airfoil {name!r}; available: {', '.join(sorted(AIRFOIL_FILES))}")
    origin, rows = "", []
    for line in (AIRFOIL_DIR / AIRFOIL_FILES[name]).read_text(encoding="utf-8").splitlines():
        line = line.strip()
        if line.startswith("#"):
            origin = origin or line[1:].strip()
        elif line:
            rows.append([float(v) for v in line.replace(",", " ").split()])
    data = np.array(rows, dtype=float)
    if data.ndim != 2 or data.shape[1] not in (3, 4):
        raise ValueError(f"airfoil {name!r}: expected 3 or 4 columns (alpha, Cl, Cd[, Cm])")
    has_cm = data.shape[1] == 4
    cm = data[:, 3] if has_cm else np.zeros(len(data))
    table = AirfoilTable(name, origin, tuple(data[:, 0]), tuple(data[:, 1]), tuple(data[:, 2]),
                         tuple(cm), has_cm)
    if not raw and name in SYMMETRISE_DEG:
        table = symmetrised(table, SYMMETRISE_DEG[name])
    return table


def symmetrised(table: AirfoilTable, limit_deg: float) -> AirfoilTable:
    """The table of a symmetric section with its range ``|alpha| <= limit_deg`` made symmetric:
    Cl odd and Cd even, both taken from the positive-alpha branch (mirrored onto negative
    alpha), and Cm replaced by its odd part ``(Cm(a) - Cm(-a))/2`` (so a constant offset, as the
    digitised Critzos file has from -9 to 15 deg, becomes 0). Every point in the range needs its
    mirror point in the table. Why the positive branch: assets/airfoils/README.md."""
    a = np.asarray(table.alpha_deg)
    cl, cd, cm = (np.array(v, dtype=float) for v in (table.cl, table.cd, table.cm))
    inside = np.flatnonzero(np.abs(a) <= limit_deg + 1e-12)
    partner = {}
    for i in inside:
        j = np.flatnonzero(np.abs(a + a[i]) <= 1e-9)
        if j.size != 1:
            raise ValueError(f"airfoil {table.name!r}: cannot symmetrise, no point at alpha = {-a[i]} deg "
                             f"mirroring {a[i]} deg")
        partner[i] = int(j[0])
    new_cl, new_cd, new_cm = cl.copy(), cd.copy(), cm.copy()
    for i, j in partner.items():
        pos = i if a[i] >= 0 else j
        sgn = 1.0 if a[i] >= 0 else -1.0
        new_cl[i] = sgn * cl[pos] if a[i] != 0 else 0.0
        new_cd[i] = cd[pos]
        new_cm[i] = 0.5 * (cm[i] - cm[j])
    origin = (f"{table.origin} [symmetrised for |alpha| <= {limit_deg:g} deg on loading: Cl, Cd "
              f"from the positive branch, Cm odd part; raw points: load_airfoil(raw=True)]")
    return AirfoilTable(table.name, origin, table.alpha_deg, tuple(new_cl), tuple(new_cd), tuple(new_cm),
                        table.has_cm)


def compile_airfoil(table: AirfoilTable, step_deg: float = 0.25) -> AirfoilArrays:
    """Resample a table onto a uniform periodic grid over [-180, 180] deg.

    Each coefficient is interpolated with a shape-preserving PCHIP
    (``scipy.interpolate.PchipInterpolator``: no overshoot, e.g. at the abrupt
    Critzos stall drop 14 -> 15 deg). If the -180 and +180 rows differ they are
    averaged; the table is then repeated at -360/+360 deg before fitting so the
    interpolant and its slope are periodic across +/-180 deg. With the default
    0.25 deg step every integer-degree table point is a grid point, so table
    values are reproduced exactly by the linear lookup.

    Parameters
    ----------
    table : AirfoilTable
    step_deg : float
        Grid step [deg]; must divide 360.

    Returns
    -------
    AirfoilArrays
    """
    n = int(round(360.0 / step_deg))
    if step_deg <= 0.0 or abs(n * step_deg - 360.0) > 1e-9:
        raise ValueError(f"step_deg must divide 360, got {step_deg}")
    a = np.asarray(table.alpha_deg)[:-1]  # drop +180, it is -180 + 360
    a_ext = np.concatenate((a - 360.0, a, a + 360.0))
    grid_deg = -180.0 + step_deg * np.arange(n + 1)
    # imported here, not at module level: scipy.interpolate takes ~0.3 s to import, and a process
    # that never resamples a table (loads a stored result, answers --help) need not pay it
    from scipy.interpolate import PchipInterpolator
    grids = []
    for col in (table.cl, table.cd, table.cm):
        y = np.array(col, dtype=float)
        y[0] = 0.5 * (y[0] + y[-1])
        y = y[:-1]
        g = PchipInterpolator(a_ext, np.concatenate((y, y, y)))(grid_deg)
        g[-1] = g[0]
        grids.append(np.ascontiguousarray(g, dtype=np.float64))
    return AirfoilArrays(-math.pi, math.radians(step_deg), *grids)




def coefficients(table_arrays: AirfoilArrays, alpha_rad, mach=0.0):
    """Vectorised :func:`airfoil_coefficients` for plots and reports (not for kernels).

    Parameters
    ----------
    table_arrays : AirfoilArrays
    alpha_rad : float or array_like
        Angle of attack [rad].
    mach : float or array_like
        Mach number [-], broadcast against ``alpha_rad``.

    Returns
    -------
    cl, cd, cm : ndarray (or float for scalar inputs)
        Coefficients [-] with the broadcast shape of the inputs.
    """
    a, m = np.broadcast_arrays(np.asarray(alpha_rad, dtype=float), np.asarray(mach, dtype=float))
    out = _coefficients_many(np.ascontiguousarray(a).ravel(), np.ascontiguousarray(m).ravel(),
                             *table_arrays)
    if a.ndim == 0:
        return float(out[0, 0]), float(out[1, 0]), float(out[2, 0])
    return tuple(out[j].reshape(a.shape) for j in range(3))
