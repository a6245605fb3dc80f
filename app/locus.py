"""Modes along GJ for the current CG: the source of the root locus.

The source is ``amra_core.column.walk_column`` (trim continuation down a CG column with the modes
at each step, the fold and flutter crossings bracketed). Where that module is missing (older core),
:func:`walk` samples ``amra_core.stability.analyse`` at a handful of log-spaced GJ values. Both
return :class:`LocusPoint` lists, so the view does not change.
"""
from __future__ import annotations

import importlib.util
import math
import threading
from dataclasses import dataclass
from typing import Optional

import numpy as np

from amra_core.flight import FlightCondition, SolverSettings
from amra_core.model import compile_model
from amra_core.rotor import Rotor
from amra_core.stability import analyse

N_SAMPLES = 9
LOCUS_REL_TOL = 0.05  #: bracket of the fold and of flutter crossings along the locus [-]


@dataclass(frozen=True)
class LocusPoint:
    """The modes of the trim at one GJ [N m^2/rad]; ``trimmed`` False where no autorotation exists
    (then ``modes`` is empty)."""

    gj_nm2: float
    trimmed: bool
    modes: tuple  #: stability.Mode, aero-lag modes left out
    max_real_part_per_s: Optional[float]
    stable: bool


def walk(rotor: Rotor, flight: FlightCondition, settings: SolverSettings, cg: float, gj_min_nm2: float,
         gj_max_nm2: float, cancel: Optional[threading.Event] = None) -> list:
    """Locus points from ``gj_max_nm2`` down to ``gj_min_nm2`` at chordwise CG ``cg`` [chord fraction]."""
    if importlib.util.find_spec("amra_core.column") is not None:
        return _walk_with_column(rotor, flight, settings, cg, gj_min_nm2, gj_max_nm2, cancel)
    return _walk_with_analyse(rotor, flight, settings, cg, gj_min_nm2, gj_max_nm2, cancel)


def _physical(modes) -> tuple:
    return tuple(m for m in modes if m.label != "aero lag")


def _walk_with_analyse(rotor, flight, settings, cg, gj_min, gj_max, cancel, n=N_SAMPLES) -> list:
    out = []
    for gj in np.geomspace(gj_max, gj_min, n):
        if cancel is not None and cancel.is_set():
            break
        res = analyse(compile_model(rotor.with_overrides(gj_nm2=float(gj), x_cg=cg), flight, settings))
        modes = _physical(res.modes)
        out.append(LocusPoint(float(gj), res.trim.ok, modes,
                              max((m.real_part_per_s for m in modes), default=None), res.stable))
    return out


def _walk_with_column(rotor, flight, settings, cg, gj_min, gj_max, cancel) -> list:
    from amra_core.column import walk_column
    cw = walk_column(rotor, flight, settings, cg, gj_min, gj_max, rel_tol=LOCUS_REL_TOL, cancel=cancel)
    out = []
    for p in cw.points:
        trimmed = p.branch == "normal" and p.trim is not None
        modes = _physical(p.modes or ()) if trimmed else ()
        re = p.max_real_part_per_s if trimmed and math.isfinite(p.max_real_part_per_s) else None
        out.append(LocusPoint(float(p.gj_nm2), trimmed, modes, re, bool(p.stable)))
    return out
