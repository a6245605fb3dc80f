"""Exports that stand alone: a file name that says which case it holds, and a CSV whose header
lines (``# key: value``) carry the case's parameters and the solver version, with numbers written
to sensible precision (8 significant digits: a relative resolution of 1e-8, finer than the
integrator's own accuracy (see ``amra bench``) so decays can still be fitted from the file, without
the 17-digit round-off noise of a float's full repr). Read back with ``numpy.loadtxt(f, delimiter=",", skiprows=...)``,
``pandas.read_csv(f, comment="#")`` or any spreadsheet (the ``#`` lines are text).
"""
from __future__ import annotations

import csv
import io
import math
import re
from typing import Iterable, Mapping

import numpy as np

from . import __version__
from .layout import P_VH

#: significant digits of exported numbers
EXPORT_DIGITS = 8


def _fmt(v) -> str:
    if isinstance(v, float):  # non-finite values as nan / inf / -inf, which numpy and pandas read back
        return repr(v) if not math.isfinite(v) else f"{v:.{EXPORT_DIGITS}g}"
    return str(v)


def file_name(kind: str, *, case: str = "", fidelity: str = "", gj_nm2: float | None = None,
              cg_pct: float | None = None, mu: float | None = None, ea_pct: float | None = None,
              aero: str = "", extension: str = "csv") -> str:
    """``amra-fig10-rigid-gj100-cg40.csv``-style names: the kind or case label, fidelity, aero model,
    EA [% chord], GJ [N m^2/rad], CG [% chord] and, in forward flight, mu; characters outside
    [a-z0-9.-] dropped."""
    parts = ["amra", case or kind]
    if fidelity:
        parts.append(fidelity)
    if aero:
        parts.append(aero)
    if ea_pct is not None:
        parts.append(f"ea{ea_pct:.3g}")
    if gj_nm2 is not None:
        parts.append(f"gj{gj_nm2:.4g}")
    if cg_pct is not None:
        parts.append(f"cg{cg_pct:.3g}")
    if mu:
        parts.append(f"mu{mu:.3g}")
    if case and kind not in case:
        parts.append(kind)
    slug = "-".join(re.sub(r"[^a-z0-9.-]+", "", p.lower().replace(" ", "")) for p in parts if p)
    return f"{slug}.{extension}"


def header_lines(meta: Mapping[str, object]) -> list[str]:
    """``# key: value`` lines: the solver version first, then ``meta`` in its order."""
    lines = [f"# AMRA {__version__}"]
    lines += [f"# {k}: " + str(_fmt(v)).replace("\n", " ") for k, v in meta.items()]  # one line each
    return lines


def table_csv(columns: Iterable[str], rows, meta: Mapping[str, object] | None = None) -> str:
    """A CSV text: header lines from ``meta``, one line of column names (units in the names), then
    ``rows`` (a 2-D array or a list of rows: floats to :data:`EXPORT_DIGITS` digits, ``nan``/``inf``
    where not finite)."""
    out = io.StringIO()
    for line in header_lines(meta or {}):
        out.write(line + "\n")
    # quoted where needed: a map cell's reason has commas ("... descent rate 23.1 m/s (4.12 v_h), not
    # autorotation"), which split its row into more fields than the header had
    w = csv.writer(out, lineterminator="\n")
    w.writerow(list(columns))
    for row in (rows.tolist() if isinstance(rows, np.ndarray) else rows):
        w.writerow([_fmt(float(v) if isinstance(v, (int, float, np.floating)) and not isinstance(v, bool) else v)
                    for v in row])
    return out.getvalue()


def case_meta(case, changes: Iterable[str] = (), verdict: str | None = None) -> dict:
    """The parameters of a :class:`~amra_core.simulation.Case` for a header, in the page's units
    (GJ N m^2/rad, EA and CG % chord, mu, s)."""
    fl, se = case.flight, case.settings
    meta = {"rotor": case.rotor.name, "gj_nm2 (span mean)": float(case.rotor.stations.mean("gj_nm2")),
            "ea_pct_chord (span mean)": 100 * float(case.rotor.stations.mean("x_ea")),
            "cg_pct_chord (span mean)": 100 * float(case.rotor.stations.mean("x_cg")),
            "fidelity": se.fidelity, "aero": se.aero, "inflow": se.inflow,
            "mu": float(fl.mu or 0.0),
            # with mu given the airspeed follows the trim (mu Omega R / cos tilt): not 0 m/s
            "airspeed_m_s": "set by mu at the trim's rotor speed" if fl.mu else float(fl.airspeed_m_s or 0.0),
            "run_s": float(case.t_end_s), "case_key": case.key()}
    for i, text in enumerate(changes):
        meta[f"change {i + 1}"] = text
    if verdict:
        meta["verdict"] = verdict
    return meta


def run_meta(sim, verdict=None, run_state: str | None = None) -> dict:
    """A run's header: its case and changes (:func:`case_meta`), how it started (from a trim, or from
    a branch end with the parameters switched on at t = 0: read alone, t = 0 looked like a trim of
    the case), how far it got (``t_reached_s``, and ``run_state``: the caller's words, e.g. a run
    still going or stopped by its user, else whether it reached its end) and its ``verdict`` (an
    :class:`amra_core.verdict.Verdict`: class, outcome, the run's fitted growth rate, frequency,
    collapse time, rotor-speed headline). A file saved mid-run or after a Stop said only ``run_s: 30``
    above rows ending at 12.7 s. The case is the one the run started with, as the file's name says
    (a file named GJ 500 said GJ 300 above its rows after a change to 300); the changes follow it."""
    meta = case_meta(sim.start_case, [what for _, _, what in sim.changes])
    if sim.case.flight.mu:  # the airspeed the trim set (the case alone can only say how it is set)
        meta["airspeed_m_s"] = float(sim.model.arrays.p[P_VH])
        meta["airspeed_from"] = "mu at the trim's rotor speed"
    meta["start"] = sim.start_note
    reached, end = float(sim.t), float(sim.case.t_end_s)
    meta["t_reached_s"] = reached
    if run_state is None:
        if sim.status not in ("running", "not-started"):  # the solver ended it (failure, rotor stopped, ...)
            run_state = f"ended at t = {reached:.2f} s of {end:g} s: {sim.status}"
        else:
            run_state = "reached its end" if reached >= end - 1e-9 else f"at t = {reached:.2f} s of {end:g} s"
    meta["run_state"] = run_state
    if verdict is not None:
        meta |= {"verdict": verdict.verdict, "outcome": verdict.outcome,
                 "growth_rate_per_s (run's fit)": "" if verdict.growth_rate_per_s is None else verdict.growth_rate_per_s,
                 "frequency_hz": "" if verdict.frequency_hz is None else verdict.frequency_hz,
                 "collapse_time_s": "" if verdict.collapse_time_s is None else verdict.collapse_time_s,
                 "rotor_speed": verdict.rotor_speed, "explanation": verdict.explanation}
    return meta
