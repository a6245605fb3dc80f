"""Every control mirrored in the URL, so a case can be shared as a link and reopens exactly.

:func:`apply_query` validates each value as a widget's is (bounds, types, finite numbers), the
preset first so explicit values win; each bad one gives a message naming it. It runs when the
session is created; :func:`sync_url` then keeps the URL in step (``pn.state.location.sync``).
"""
from __future__ import annotations

import math
import urllib.parse

import param

#: control name -> URL key
URL_KEYS = {"preset": "preset", "rotor": "rotor", "gj_nm2": "gj", "ea_pct": "ea", "cg_pct": "cg", "mu": "mu",
            "airspeed_m_s": "v", "omega_hold_rad_s": "omega_hold", "fidelity": "fidelity", "aero": "aero",
            "inflow": "inflow", "run_s": "run_s", "soften_at_s": "soften_at", "speed": "speed", "present": "present", "map_columns": "map_columns",
            "map_coarse": "map_coarse"}
_BY_KEY = {v: k for k, v in URL_KEYS.items()}


def _coerce(p: param.Parameter, name: str, raw):
    if isinstance(p, param.Boolean):
        text = str(raw).strip().lower()
        if text in ("1", "true", "yes", "on"):
            return True
        if text in ("0", "false", "no", "off"):
            return False
        raise ValueError(f"{name} = {raw!r} is not allowed: must be true or false")
    if isinstance(p, param.Integer):
        if isinstance(raw, float) and raw.is_integer():
            raw = int(raw)
        if isinstance(raw, str):
            if not raw.strip().lstrip("+-").isascii() or not raw.strip().lstrip("+-").isdigit():
                raise ValueError(f"{name} = {raw!r} is not allowed: must be an integer")
            raw = int(raw)
    elif isinstance(p, param.Number):
        if isinstance(raw, str):
            raw = float(raw)
        if isinstance(raw, (int, float)) and not isinstance(raw, bool) and not math.isfinite(raw):
            raise ValueError(f"{name} = {raw!r} is not allowed: must be a finite number")
    elif isinstance(p, param.Selector) and not isinstance(raw, str):
        raw = str(raw)
    return raw


def apply_query(controls: param.Parameterized, query: dict) -> list:
    """Apply URL query values (already parsed, e.g. ``Location.query_params``); return messages
    for those rejected (the control keeps its value)."""
    errors = []
    keys = sorted((k for k in query if k in _BY_KEY), key=lambda k: k != "preset")
    for key in keys:
        name = _BY_KEY[key]
        p = controls.param[name]
        raw = query[key]
        try:
            value = _coerce(p, key, raw)
            if name == "rotor" and value == "uploaded file":
                raise ValueError("an uploaded rotor cannot be shared by link (upload the file again)")
            controls.param.update({name: value})
        except Exception as exc:  # noqa: BLE001 - every bad value becomes a message
            allowed = ""
            if isinstance(p, param.Number) and p.bounds:
                allowed = f" (allowed {p.bounds[0]:g} to {p.bounds[1]:g})"
            elif isinstance(p, param.Selector):
                allowed = f" (allowed: {', '.join(map(str, p.objects))})"
            elif isinstance(p, param.Boolean):
                allowed = " (allowed: true or false)"
            errors.append(f"link parameter {key} = {raw!r} was ignored{allowed}: {_short(exc)}")
    return errors


def _short(exc: Exception) -> str:
    text = str(exc).split("\n")[0]
    return text if len(text) < 200 else text[:200] + " ..."


def query_string(controls: param.Parameterized) -> str:
    """The URL query for the current values (what a shared link carries)."""
    return urllib.parse.urlencode({key: getattr(controls, name) for name, key in URL_KEYS.items()})


def parse_link_query(query: str) -> dict:
    """A URL query string (with or without the leading '?') parsed as ``Location.query_params``
    parses it, or, where Panel's parser raises, as plain strings.

    Panel's parser takes ``str.isdigit()`` for "an integer", so a value like '²' reaches ``int()``
    and raises; the raw strings are then coerced (or rejected with a message) per control by
    :func:`apply_query`."""
    from panel.util import parse_query
    query = query.lstrip("?")
    if not query:
        return {}
    try:
        return parse_query("?" + query)
    except ValueError:
        return dict(urllib.parse.parse_qsl(query, keep_blank_values=True))


def session_query() -> dict:
    """The query of the session's request, parsed by :func:`parse_link_query`."""
    import panel as pn
    args = pn.state.session_args or {}
    flat = {k: (v[-1].decode("utf-8", "replace") if isinstance(v[-1], bytes) else str(v[-1]))
            for k, v in args.items() if v}
    return parse_link_query(urllib.parse.urlencode(flat))


def apply_session_query(controls: param.Parameterized, notify) -> None:
    """At session creation: apply the link's values, so the first paint already shows the case."""
    for msg in apply_query(controls, session_query()):
        notify(msg)


def sync_url(controls: param.Parameterized) -> None:
    """After the page has loaded: mirror every control in the URL (the browser's location is
    known by then; values already applied by :func:`apply_session_query` are not re-reported)."""
    import panel as pn
    loc = pn.state.location
    if loc is not None:
        # every value but the preset: Location.sync applies the link's values in one batch, after
        # which the preset's watcher would overwrite the edits (?preset=nominal&gj=100 opened at
        # GJ 1500); the values alone reproduce the case, and a link's preset was applied first
        # by apply_session_query
        loc.sync(controls, {k: v for k, v in URL_KEYS.items() if k != "preset"}, on_error=lambda bad: None)
