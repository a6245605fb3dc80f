"""Validated description of a two-bladed teetering rotor and its blade sections.

Everything is SI: metres, kilograms, radians, N m^2. Chordwise positions
(elastic axis ``x_ea``, centre of gravity ``x_cg``, aerodynamic centre ``x_ac``)
are fractions of the local chord measured from the leading edge. Station arrays
run root to tip, with ``r_m`` measured from the rotor axis.

Objects are frozen and hashable (arrays are stored as tuples) so a case can be
keyed by its parameters; :meth:`Rotor.with_overrides` gives the uniform GJ, EA
and CG overrides that the dashboard sliders set.
"""
from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field, replace, asdict
from typing import Optional

import numpy as np


#: the largest chord allowed, as a fraction of the tip radius (blade aspect ratio R/c >= 4)
MAX_CHORD_FRACTION = 0.25


class RotorError(ValueError):
    """A rotor description is invalid. The message names field, value and allowed range."""


def _short(v):
    """A long list shown by its start and its length in messages."""
    if isinstance(v, (list, tuple)) and len(v) > 12:
        return f"[{', '.join(repr(x) for x in list(v)[:4])}, ... ({len(v)} values)]"
    return list(v) if isinstance(v, tuple) else v


def _fail(name: str, value, allowed: str):
    raise RotorError(f"{name} = {value!r} is not allowed: {allowed}")


def _check_number(name: str, value, lo=None, hi=None, lo_open=False, hi_open=False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        _fail(name, value, "must be a number")
    v = float(value)
    rng = f"{'(' if lo_open else '['}{'-inf' if lo is None else lo}, {'inf' if hi is None else hi}{')' if hi_open else ']'}"
    if not math.isfinite(v):
        _fail(name, value, f"must be a finite number in {rng}")
    if lo is not None and (v < lo or (lo_open and v == lo)):
        _fail(name, value, f"must lie in {rng}")
    if hi is not None and (v > hi or (hi_open and v == hi)):
        _fail(name, value, f"must lie in {rng}")
    return v


#: the largest tip radius allowed [m] (no rotorcraft blade is longer; the largest is ~17 m)
MAX_RADIUS_M = 50.0
#: upper bounds of the station magnitudes: orders of magnitude beyond any rotor blade (a heavy
#: helicopter blade is ~10-50 kg/m, GJ and EI up to ~1e6 N m^2), so that a typing slip such as
#: 1e308 is named as such instead of overflowing in the section checks or the kernels
MAX_SECTION_MASS_KG_M = 1e4
MAX_SECTION_INERTIA_KG_M = 1e3
MAX_STIFFNESS_NM2 = 1e10

#: the largest hub inertia allowed [kg m^2] (a 50 m rotor's blades are ~1e6 kg m^2; a hub is far less)
MAX_HUB_INERTIA_KG_M2 = 1e6

#: Station fields: name -> (lower bound, lower bound open?, upper bound, unit/meaning)
STATION_FIELDS = {
    "r_m": (0.0, False, MAX_RADIUS_M, "radius from the rotor axis [m]"),
    "chord_m": (0.0, True, MAX_CHORD_FRACTION * MAX_RADIUS_M, "chord [m]"),
    "twist_rad": (-math.pi / 4, False, math.pi / 4, "built-in twist, nose-up positive [rad]"),
    "mass_kg_m": (0.0, True, MAX_SECTION_MASS_KG_M, "mass per length [kg/m]"),
    "torsional_inertia_kg_m": (0.0, True, MAX_SECTION_INERTIA_KG_M,
                               "torsional inertia per length about the EA [kg m^2/m]"),
    "gj_nm2": (0.0, True, MAX_STIFFNESS_NM2, "torsional stiffness [N m^2/rad]"),
    "ei_flap_nm2": (0.0, True, MAX_STIFFNESS_NM2, "flapwise bending stiffness [N m^2]"),
    "ei_lag_nm2": (0.0, True, MAX_STIFFNESS_NM2, "lagwise bending stiffness [N m^2]"),
    "x_ea": (0.0, False, 1.0, "elastic axis [fraction of chord from the leading edge]"),
    "x_cg": (0.0, False, 1.0, "centre of gravity [fraction of chord from the leading edge]"),
    "x_ac": (0.0, False, 1.0, "aerodynamic centre [fraction of chord from the leading edge]"),
}


#: a section's inertia about its own CG must be at least this fraction of the parallel-axis term
#: m ((x_cg - x_ea) c)^2: exactly at the bound the section is a line mass and the mass matrix is singular
INERTIA_MARGIN = 1e-3


def inertia_message(st: "BladeStations", i: int, need: float, x_ea=None, x_cg=None) -> str:
    ea = st.x_ea[i] if x_ea is None else x_ea
    cg = st.x_cg[i] if x_cg is None else x_cg
    m, c, inertia = st.mass_kg_m[i], st.chord_m[i], st.torsional_inertia_kg_m[i]
    d_max = math.sqrt(inertia / (m * (1.0 + INERTIA_MARGIN))) / c
    return (f"x_cg = {cg!r} with x_ea = {ea!r} is not allowed at station {i} (r = {st.r_m[i]:g} m): the "
            f"torsional inertia about the elastic axis, torsional_inertia_kg_m = {inertia:.6g} kg m^2/m, must be "
            f"at least m ((x_cg - x_ea) c)^2 = {need:.6g} kg m^2/m (mass_kg_m = {m:g}, chord_m = {c:g}) or no "
            f"real mass distribution has it; here |x_cg - x_ea| must be below {d_max:.4f} chord "
            f"(x_cg in [{max(0.0, ea - d_max):.4f}, {min(1.0, ea + d_max):.4f}] for this EA), or raise the inertia")


@dataclass(frozen=True)
class BladeStations:
    """Spanwise blade properties at stations, root to tip; linear between stations."""

    r_m: tuple
    chord_m: tuple
    twist_rad: tuple
    mass_kg_m: tuple
    torsional_inertia_kg_m: tuple
    gj_nm2: tuple
    ei_flap_nm2: tuple
    ei_lag_nm2: tuple
    x_ea: tuple
    x_cg: tuple
    x_ac: tuple

    def __post_init__(self):
        n = None
        for name, (lo, lo_open, hi, _) in STATION_FIELDS.items():
            raw = getattr(self, name)
            if isinstance(raw, (int, float)):
                _fail(f"stations.{name}", raw, "must be a list with one value per station")
            if n is not None and len(raw) != n and len(raw) > 1000:  # do not check a huge list value by value
                _fail(f"stations.{name}", _short(raw), f"must have {n} values, one per station (as r_m)")
            vals = tuple(
                _check_number(f"stations.{name}[{i}]", v, lo, hi, lo_open) for i, v in enumerate(raw)
            )
            object.__setattr__(self, name, vals)
            if n is None:
                n = len(vals)
                if n < 2:
                    _fail(f"stations.{name}", list(raw), "needs at least 2 stations (root and tip)")
            elif len(vals) != n:
                _fail(f"stations.{name}", list(raw), f"must have {n} values, one per station (as r_m)")
        r = self.r_m
        for i in range(1, len(r)):
            if not r[i] > r[i - 1]:
                _fail(f"stations.r_m[{i}]", r[i], f"stations must be in increasing order of radius (> {r[i - 1]})")
        i, need = self.inertia_violation()
        if i is not None:
            raise RotorError(inertia_message(self, i, need))

    def inertia_violation(self, x_ea=None, x_cg=None):
        """``(station, bound)`` of the first station whose torsional inertia about the EA is below
        the parallel-axis bound m ((x_cg - x_ea) c)^2 (times 1 + :data:`INERTIA_MARGIN`), with
        ``x_ea``/``x_cg`` overriding the stations' own; ``(None, None)`` when every station is
        physical. Below the bound the section's inertia about its own CG would be negative: no
        real mass distribution has it, and the mass matrix is not positive definite."""
        for i in range(len(self.r_m)):
            ea = self.x_ea[i] if x_ea is None else x_ea
            cg = self.x_cg[i] if x_cg is None else x_cg
            need = self.mass_kg_m[i] * ((cg - ea) * self.chord_m[i]) ** 2 * (1.0 + INERTIA_MARGIN)
            if self.torsional_inertia_kg_m[i] < need:
                return i, need
        return None, None

    def array(self, name: str) -> np.ndarray:
        return np.asarray(getattr(self, name), dtype=float)

    def at(self, name: str, r) -> np.ndarray:
        """Property ``name`` linearly interpolated at radius ``r`` [m]."""
        return np.interp(r, self.r_m, getattr(self, name))

    def mean(self, name: str) -> float:
        """Span-average of a property over the stations' extent (trapezoidal)."""
        r, v = self.array("r_m"), self.array(name)
        return float(np.trapezoid(v, r) / (r[-1] - r[0]))


@dataclass(frozen=True)
class PointMass:
    """An optional concentrated mass on each blade (e.g. tip weight)."""

    r_m: float
    mass_kg: float
    x_chord: float = 0.25  #: chordwise position [fraction of chord from the leading edge]

    def validate(self, radius_m: float, root_m: float):
        _check_number("point_mass.r_m", self.r_m, root_m, radius_m)
        _check_number("point_mass.mass_kg", self.mass_kg, 0.0, 1e4)
        _check_number("point_mass.x_chord", self.x_chord, 0.0, 1.0)


@dataclass(frozen=True)
class Rotor:
    """A two-bladed teetering rotor in autorotation, plus the vehicle it carries.

    Attributes (SI): ``radius_m`` tip radius; ``root_cutout_m`` radius where the
    flexible, lifting blade begins (clamped there to the rigid hub bar);
    ``incidence_rad`` fixed blade pitch at the root (nose up); hub teeter and
    polar inertias [kg m^2]; ``vehicle_mass_kg`` weight carried by the rotor;
    ``structural_damping_ratio`` viscous damping of the blade's own non-rotating flap, torsion
    and lag modes [fraction of critical] (the seed model has none; 0 reproduces it).
    """

    name: str
    radius_m: float
    root_cutout_m: float
    n_blades: int
    incidence_rad: float
    vehicle_mass_kg: float
    hub_teeter_inertia_kg_m2: float
    hub_polar_inertia_kg_m2: float
    stations: BladeStations
    point_mass: Optional[PointMass] = None
    airfoil: str = "naca0012_critzos"
    structural_damping_ratio: float = 0.0
    sources: tuple = field(default=(), compare=False, hash=False)

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name.strip() or len(self.name) > 200:
            _fail("name", self.name, "must be a non-empty text of at most 200 characters")
        if not isinstance(self.stations, BladeStations):
            _fail("stations", self.stations, "must be BladeStations")
        R = _check_number("radius_m", self.radius_m, 0.0, MAX_RADIUS_M, lo_open=True)
        r0 = _check_number("root_cutout_m", self.root_cutout_m, 0.0, 0.8 * R, hi_open=True)
        if isinstance(self.n_blades, bool) or not isinstance(self.n_blades, (int, np.integer)) or self.n_blades != 2:
            _fail("n_blades", self.n_blades, "must be the integer 2 (AMRA models a two-bladed teetering rotor)")
        from .airfoil import AIRFOIL_FILES  # lazily: the table list only
        if not isinstance(self.airfoil, str) or self.airfoil not in AIRFOIL_FILES:
            _fail("airfoil", self.airfoil, f"choose one of {', '.join(sorted(AIRFOIL_FILES))}")
        for i, c in enumerate(self.stations.chord_m):
            if not c <= MAX_CHORD_FRACTION * R:
                _fail(f"stations.chord_m[{i}]", c, f"must be at most {MAX_CHORD_FRACTION:g} x radius_m = "
                      f"{MAX_CHORD_FRACTION * R:g} m (a slender blade: the strip theory of the model needs R/c >= "
                      f"{1 / MAX_CHORD_FRACTION:g})")
        if not isinstance(self.sources, tuple) or not all(
                isinstance(x, tuple) and len(x) == 2 and isinstance(x[0], str) and isinstance(x[1], str)
                for x in self.sources):
            _fail("sources", self.sources, "must be a table of field = \"where the value comes from\" texts")
        if self.point_mass is not None and not isinstance(self.point_mass, PointMass):
            _fail("point_mass", self.point_mass, "must be a PointMass (r_m, mass_kg, x_chord)")
        _check_number("incidence_rad", self.incidence_rad, -math.radians(20), math.radians(20))
        _check_number("vehicle_mass_kg", self.vehicle_mass_kg, 0.0, 1e5, lo_open=True)
        _check_number("hub_teeter_inertia_kg_m2", self.hub_teeter_inertia_kg_m2, 0.0, MAX_HUB_INERTIA_KG_M2)
        _check_number("hub_polar_inertia_kg_m2", self.hub_polar_inertia_kg_m2, 0.0, MAX_HUB_INERTIA_KG_M2)
        _check_number("structural_damping_ratio", self.structural_damping_ratio, 0.0, 0.2)
        r = self.stations.r_m
        if abs(r[0] - r0) > 1e-9:
            _fail("stations.r_m[0]", r[0], f"the first station must be at the root cut-out ({r0} m)")
        if abs(r[-1] - R) > 1e-9:
            _fail(f"stations.r_m[{len(r) - 1}]", r[-1], f"the last station must be at the tip radius ({R} m)")
        if self.point_mass is not None:
            self.point_mass.validate(R, r0)

    # -- derived quantities -------------------------------------------------
    @property
    def blade_length_m(self) -> float:
        return self.radius_m - self.root_cutout_m

    @property
    def disc_area_m2(self) -> float:
        return math.pi * self.radius_m**2

    def with_overrides(self, gj_nm2=None, x_ea=None, x_cg=None, ei_flap_nm2=None) -> "Rotor":
        """A copy with uniform GJ [N m^2/rad], EA and CG [chord fraction] along the span."""
        n = len(self.stations.r_m)
        changes = {}
        if gj_nm2 is not None:
            changes["gj_nm2"] = (_check_number("gj_nm2", gj_nm2, 0.0, MAX_STIFFNESS_NM2, lo_open=True),) * n
        if ei_flap_nm2 is not None:
            changes["ei_flap_nm2"] = (_check_number("ei_flap_nm2", ei_flap_nm2, 0.0, MAX_STIFFNESS_NM2,
                                                    lo_open=True),) * n
        if x_ea is not None:
            changes["x_ea"] = (_check_number("ea (x_ea)", x_ea, 0.0, 1.0),) * n
        if x_cg is not None:
            changes["x_cg"] = (_check_number("cg (x_cg)", x_cg, 0.0, 1.0),) * n
        if not changes:
            return self
        if x_ea is not None or x_cg is not None:  # the EA/CG combination must be a physical section
            ea, cg = (None if x_ea is None else float(x_ea)), (None if x_cg is None else float(x_cg))
            i, need = self.stations.inertia_violation(x_ea=ea, x_cg=cg)
            if i is not None:
                raise RotorError(inertia_message(self.stations, i, need, x_ea=ea, x_cg=cg))
        # fast path (map keys build thousands of these): the unchanged fields were validated when
        # this rotor was built and the changed ones just now, so copy instead of re-validating all
        stations = copy.copy(self.stations)
        for k, v in changes.items():
            object.__setattr__(stations, k, v)
        out = copy.copy(self)
        object.__setattr__(out, "stations", stations)
        return out

    def to_dict(self) -> dict:
        """The resolved rotor as the solver uses it (SI, chord fractions, root to tip)."""
        st = {k: list(getattr(self.stations, k)) for k in STATION_FIELDS}
        out = {
            "name": self.name,
            "radius_m": self.radius_m,
            "root_cutout_m": self.root_cutout_m,
            "chord_m": self.stations.mean("chord_m"),
            "n_blades": self.n_blades,
            "incidence_rad": self.incidence_rad,
            "vehicle_mass_kg": self.vehicle_mass_kg,
            "hub_teeter_inertia_kg_m2": self.hub_teeter_inertia_kg_m2,
            "hub_polar_inertia_kg_m2": self.hub_polar_inertia_kg_m2,
            "airfoil": self.airfoil,
            "structural_damping_ratio": self.structural_damping_ratio,
            "point_mass": asdict(self.point_mass) if self.point_mass else None,
            "stations": st,
        }
        if self.sources:
            out["sources"] = dict(self.sources)
        return out
