"""Read rotor descriptions from TOML (presets in ``assets/rotors`` or a user's own file).

File layout (see ``assets/rotors/mccutcheon.toml``): top-level rotor scalars,
a ``[blade]`` table of station arrays (a scalar means uniform along the span;
``twist_deg``/``incidence_deg`` may be given in degrees), an optional
``[point_mass]`` table and a ``[sources]`` table naming where each value comes from.
Every problem raises :class:`RotorError` naming the field, the value and what is allowed.
"""
from __future__ import annotations

import errno
import math
import os
import re
import stat
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


#: rotor files larger than this are refused before they are parsed [bytes]
MAX_FILE_BYTES = 1 << 20
#: deepest bracket nesting and longest dotted key accepted (the presets use 1 and 1)
MAX_NESTING = 32
MAX_KEY_PARTS = 32


def preset_names() -> list[str]:
    return sorted(p.stem for p in PRESET_DIR.glob("*.toml"))


def load_preset(name: str) -> Rotor:
    """A shipped preset by name (``mccutcheon``, ``paper-boundary``): exactly one of
    :func:`preset_names`, never a path."""
    names = preset_names()
    if not isinstance(name, str) or name not in names:
        shown = name if not isinstance(name, str) or len(name) <= 60 else name[:57] + "..."
        raise RotorError(f"preset = {shown!r} is not allowed: choose one of {', '.join(names)}")
    return load_rotor_file(PRESET_DIR / f"{name}.toml")


def read_rotor_text(path) -> str:
    """The text of the rotor file ``path``: a regular file (never a FIFO or a device, which could
    hang or never end), at most :data:`MAX_FILE_BYTES`, UTF-8; :class:`RotorError` otherwise."""
    p = str(path)
    if not p or "\x00" in p:
        raise RotorError(f"rotor file {p!r} cannot be read: not a usable file name")
    try:
        fd = os.open(p, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    except OSError as exc:
        why = "a symbolic link loop" if exc.errno == errno.ELOOP else (exc.strerror or str(exc))
        raise RotorError(f"rotor file {p!r} cannot be read: {why}") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            kind = {stat.S_IFDIR: "a directory", stat.S_IFIFO: "a FIFO (named pipe)", stat.S_IFCHR: "a device",
                    stat.S_IFBLK: "a device", stat.S_IFSOCK: "a socket"}.get(stat.S_IFMT(st.st_mode), "not a file")
            raise RotorError(f"rotor file {p!r} cannot be read: it is {kind}, not a regular file")
        if st.st_size > MAX_FILE_BYTES:
            raise RotorError(f"rotor file {p!r} is too large: {st.st_size} bytes, at most {MAX_FILE_BYTES} "
                             f"bytes (1 MiB) allowed")
        chunks, total = [], 0
        while True:
            try:
                b = os.read(fd, 65536)
            except OSError as exc:
                raise RotorError(f"rotor file {p!r} cannot be read: {exc.strerror or exc}") from None
            if not b:
                break
            total += len(b)
            if total > MAX_FILE_BYTES:  # grew while we read it
                raise RotorError(f"rotor file {p!r} is too large: more than {MAX_FILE_BYTES} bytes (1 MiB)")
            chunks.append(b)
    finally:
        os.close(fd)
    return decode_rotor_bytes(b"".join(chunks), p)


def decode_rotor_bytes(data: bytes, source: str) -> str:
    """``data`` as UTF-8 text; :class:`RotorError` naming ``source`` and the first bad byte otherwise."""
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        raise RotorError(f"rotor file {source!r} is not UTF-8 text: byte {data[exc.start]:#04x} at offset "
                         f"{exc.start} (line {line}); is it a binary file?") from None


def prescan_toml(text: str) -> None:
    """Reject, before parsing, what would make the TOML parser recurse too deep or grow without
    bound: brackets nested deeper than :data:`MAX_NESTING`, dotted keys of more than
    :data:`MAX_KEY_PARTS` parts (a 20 000-part key in 40 kB costs the parser gigabytes)."""
    depth = max_depth = 0
    dots = 0  # dots in the current run of key/number characters
    i, n, line = 0, len(text), 1
    while i < n:
        ch = text[i]
        if ch in "\"'":
            q3 = text.startswith(ch * 3, i)
            end_tok = ch * 3 if q3 else ch
            j = i + len(end_tok)
            while j < n:
                c = text[j]
                if c == "\\" and ch == '"':
                    j += 2
                    continue
                if text.startswith(end_tok, j):
                    break
                if c == "\n":
                    if not q3:
                        break
                    line += 1
                j += 1
            i = j + len(end_tok)
            continue  # a quoted key part continues the run
        if ch == "#":
            j = text.find("\n", i)
            i = n if j < 0 else j
            dots = 0
            continue
        if ch in "[{":
            depth += 1
            if depth > MAX_NESTING:
                raise RotorError(f"TOML nested deeper than {MAX_NESTING} levels (line {line}) is not allowed: "
                                 f"a rotor file needs at most one level")
            max_depth = max(max_depth, depth)
            dots = 0
        elif ch in "]}":
            depth = max(0, depth - 1)
            dots = 0
        elif ch == ".":
            dots += 1
            if dots >= MAX_KEY_PARTS:
                raise RotorError(f"a dotted key of more than {MAX_KEY_PARTS} parts (line {line}) is not allowed")
        elif ch.isalnum() or ch in "_- \t":
            pass
        else:
            if ch == "\n":
                line += 1
            dots = 0
        i += 1


def load_rotor_file(path) -> Rotor:
    """A rotor from a TOML file; clear :class:`RotorError` for every kind of bad input."""
    path = Path(path)
    return rotor_from_toml(read_rotor_text(path), str(path), short_name=path.name)


def rotor_from_toml(text: str, source: str, short_name: str | None = None) -> Rotor:
    """A rotor from the text of a TOML rotor file, whatever it came from (a file, a browser's
    upload): prescanned (:func:`prescan_toml`) before it is parsed, so no input makes the parser
    recurse too deep or grow without bound; a clear :class:`RotorError` naming ``source`` for every
    kind of bad input (``short_name``, if given, names it in the messages about the values)."""
    try:
        prescan_toml(text)
    except RotorError as exc:
        raise RotorError(f"rotor file {source!r}: {exc}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise RotorError(f"rotor file {source!r} is not valid TOML: {exc}") from None
    except (RecursionError, MemoryError):
        raise RotorError(f"rotor file {source!r} is too deeply nested or too large to parse") from None
    try:
        return rotor_from_dict(data)
    except RotorError as exc:
        raise RotorError(f"{short_name}: {exc}" if short_name else f"rotor file {source!r}: {exc}") from None


def rotor_from_dict(data: dict) -> Rotor:
    data = dict(data)
    blade = data.pop("blade", None)
    if not isinstance(blade, dict):
        raise RotorError("blade = (missing) is not allowed: a [blade] table of station arrays is required")
    sources = data.pop("sources", {})
    if not isinstance(sources, dict):
        raise RotorError(f"sources = {_short(sources)} is not allowed: must be a [sources] table of "
                         f"field = \"where the value comes from\" texts")
    for key, text in sources.items():  # the entry that is wrong, not the whole table
        if not isinstance(text, str):
            raise RotorError(f"sources.{key} = {_short(text)} is not allowed: each [sources] entry is a text "
                             f"saying where the value comes from")
    point = data.pop("point_mass", None)
    if point is not None and not isinstance(point, dict):
        raise RotorError(f"point_mass = {_short(point)} is not allowed: must be a [point_mass] table "
                         f"(r_m, mass_kg, x_chord)")
    top = {}
    for key in _TOP_REQUIRED:
        if key not in data:
            raise RotorError(f"{key} = (missing) is not allowed: the field is required")
        top[key] = data.pop(key)
    for key, default in _TOP_OPTIONAL.items():
        top[key] = data.pop(key, default)
    if not isinstance(top["name"], str):
        raise RotorError(f"name = {_short(top['name'])} is not allowed: must be a text in quotes")
    if "incidence_deg" in data and "incidence_rad" in data:
        raise RotorError("incidence_deg and incidence_rad are both given: give one")
    in_degrees = []  # angles the file gives in degrees (its messages name them so)
    if "incidence_deg" in data:
        in_degrees.append("incidence")
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
        if deg_key in blade and rad_key in blade:
            raise RotorError(f"blade.{deg_key} and blade.{rad_key} are both given: give one")
        if deg_key in blade:
            in_degrees.append(f"blade.{deg_key.removesuffix('_deg')}")
            v = blade.pop(deg_key)
            blade[rad_key] = [math.radians(x) if _is_num(x) else x for x in v] if isinstance(v, list) else (
                math.radians(v) if _is_num(v) else v)
    if "r_m" not in blade:
        raise RotorError("blade.r_m = (missing) is not allowed: station radii are required")
    r = blade["r_m"]
    if not isinstance(r, list):
        raise RotorError(f"blade.r_m = {r!r} is not allowed: must be a list of radii [m], root to tip")
    n = len(r)
    fields, blade_given = {}, {}
    for name in STATION_FIELDS:
        if name not in blade:
            raise RotorError(f"blade.{name} = (missing) is not allowed: the field is required")
        v = blade_given[name] = blade.pop(name)
        fields[name] = tuple(v) if isinstance(v, list) else (v,) * n
    if blade:
        k = sorted(blade)[0]
        raise RotorError(f"blade.{k} = {blade[k]!r} is not allowed: unknown field")
    scalars = [name for name in STATION_FIELDS if not isinstance(blade_given[name], list)]
    try:
        stations = BladeStations(**fields)
        pm = None
        if point is not None:
            try:
                pm = PointMass(**point)
            except TypeError as exc:
                raise RotorError(f"point_mass = {point!r} is not allowed: needs r_m, mass_kg and optional x_chord "
                                 f"({exc})") from None
        return Rotor(stations=stations, point_mass=pm, sources=tuple(sorted(sources.items())), **top)
    except RotorError as exc:
        raise RotorError(_as_in_the_file(str(exc), scalars, in_degrees)) from None


_NUM = r"[-+]?(?:inf|nan|[0-9]+\.?[0-9]*(?:e[-+]?[0-9]+)?)"


def _as_in_the_file(message: str, scalars: list, in_degrees: list = ()) -> str:
    """A message about the blade's stations named as the file writes them: its ``[blade]`` table, a
    value given once for the whole span without a station index ("stations.chord_m[0] = -0.197" read
    as a list the file does not have), and an angle the file gives in degrees in degrees
    (``in_degrees``: names without their ``_rad``; "incidence_rad = 1.3962634015954636 ... [-0.349...,
    0.349...]" answered a file that says ``incidence_deg = 80``)."""
    message = message.replace("stations.", "blade.")
    for name in scalars:
        message = re.sub(rf"blade\.{name}\[\d+\]", f"blade.{name}", message)
    for base in in_degrees:
        def degrees(text: str) -> str:  # every number of a value or a range, radians to degrees
            return re.sub(_NUM, lambda n: f"{math.degrees(float(n.group())):.6g}", text)

        def to_deg(m):
            reason = re.sub(rf"\[{_NUM}, {_NUM}\]", lambda r: degrees(r.group()) + " deg", m.group("why"))
            return f"{base}_deg{m.group('i') or ''} = {degrees(m.group('v'))} is not allowed: {reason}"
        message = re.sub(rf"{re.escape(base)}_rad(?P<i>\[\d+\])? = (?P<v>.*?) is not allowed: (?P<why>.*)$", to_deg,
                         message)
    return message


def _short(v) -> str:
    t = repr(v)
    return t if len(t) <= 80 else t[:77] + "..."


def _is_num(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)
