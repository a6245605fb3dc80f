"""Read rotor descriptions from TOML (presets in ``assets/rotors`` or a user's own file).

File layout (see ``assets/rotors/mccutcheon.toml``): top-level rotor scalars,
a ``[blade]`` table of station arrays (a scalar means uniform along the span;
``twist_deg``/``incidence_deg`` may be given in degrees), an optional
``[point_mass]`` table and a ``[sources]`` table naming where each value comes from.
Every problem raises :class:`RotorError` naming the field, the value and what is allowed.
"""
from __future__ import annotations

import math
import tomllib
from pathlib import Path

from .rotor import BladeStations, PointMass, Rotor, RotorError, STATION_FIELDS

ASSETS_DIR = Path(__file__).resolve().parents[1] / "assets"
PRESET_DIR = ASSETS_DIR / "rotors"

_TOP_REQUIRED = ("name", "radius_m", "root_cutout_m", "vehicle_mass_kg")
_TOP_OPTIONAL = {
    "n_blades": 2,
    "hub_teeter_inertia_kg_m2": 0.0,
    "hub_polar_inertia_kg_m2": 0.0,
    "airfoil": "naca0012_critzos",
    "structural_damping_ratio": 0.0,
}
_DEG_ALIASES = {"twist_deg": "twist_rad"}


def preset_names() -> list[str]:
    return sorted(p.stem for p in PRESET_DIR.glob("*.toml"))


def load_preset(name: str) -> Rotor:
    """A shipped preset by name (``mccutcheon``, ``paper-boundary``)."""
    path = PRESET_DIR / f"{name}.toml"
    if not path.is_file():
        raise RotorError(f"preset = {name!r} is not allowed: choose one of {', '.join(preset_names())}")
    return load_rotor_file(path)


def load_rotor_file(path) -> Rotor:
    """A rotor from a TOML file; clear :class:`RotorError` for every kind of bad input."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise RotorError(f"rotor file {str(path)!r} cannot be read: {exc.strerror}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise RotorError(f"rotor file {str(path)!r} is not valid TOML: {exc}") from None
    try:
        return rotor_from_dict(data)
    except RotorError as exc:
        raise RotorError(f"{path.name}: {exc}") from None


def rotor_from_dict(data: dict) -> Rotor:
    data = dict(data)
    blade = data.pop("blade", None)
    if not isinstance(blade, dict):
        raise RotorError("blade = (missing) is not allowed: a [blade] table of station arrays is required")
    sources = data.pop("sources", {}) or {}
    point = data.pop("point_mass", None)
    top = {}
    for key in _TOP_REQUIRED:
        if key not in data:
            raise RotorError(f"{key} = (missing) is not allowed: the field is required")
        top[key] = data.pop(key)
    for key, default in _TOP_OPTIONAL.items():
        top[key] = data.pop(key, default)
    if "incidence_deg" in data and "incidence_rad" in data:
        raise RotorError("incidence_deg and incidence_rad are both given: give one")
    if "incidence_deg" in data:
        inc = data.pop("incidence_deg")
        top["incidence_rad"] = math.radians(inc) if _is_num(inc) else inc
    elif "incidence_rad" in data:
        top["incidence_rad"] = data.pop("incidence_rad")
    else:
        raise RotorError("incidence_deg = (missing) is not allowed: the blade incidence is required")
    if data:
        raise RotorError(f"{sorted(data)[0]} = {data[sorted(data)[0]]!r} is not allowed: unknown field "
                         f"(known: {', '.join(list(_TOP_REQUIRED) + list(_TOP_OPTIONAL) + ['incidence_deg'])})")

    blade = dict(blade)
    for deg_key, rad_key in _DEG_ALIASES.items():
        if deg_key in blade:
            v = blade.pop(deg_key)
            blade[rad_key] = [math.radians(x) if _is_num(x) else x for x in v] if isinstance(v, list) else (
                math.radians(v) if _is_num(v) else v)
    if "r_m" not in blade:
        raise RotorError("blade.r_m = (missing) is not allowed: station radii are required")
    r = blade["r_m"]
    if not isinstance(r, list):
        raise RotorError(f"blade.r_m = {r!r} is not allowed: must be a list of radii [m], root to tip")
    n = len(r)
    fields = {}
    for name in STATION_FIELDS:
        if name not in blade:
            raise RotorError(f"blade.{name} = (missing) is not allowed: the field is required")
        v = blade.pop(name)
        fields[name] = tuple(v) if isinstance(v, list) else (v,) * n
    if blade:
        k = sorted(blade)[0]
        raise RotorError(f"blade.{k} = {blade[k]!r} is not allowed: unknown field")
    stations = BladeStations(**fields)
    pm = None
    if point is not None:
        try:
            pm = PointMass(**point)
        except TypeError as exc:
            raise RotorError(f"point_mass = {point!r} is not allowed: needs r_m, mass_kg and optional x_chord ({exc})") from None
    return Rotor(stations=stations, point_mass=pm, sources=tuple(sorted(sources.items())), **top)


def _is_num(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)
