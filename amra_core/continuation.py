"""Continuation of the trim branch in GJ: a secant predictor, the test that a solution continues
the branch, and one continuation step (issue 8 §2).

Used by :func:`amra_core.trim.trim` (from a stiff blade down to the requested GJ) and by the map's
column walk (:mod:`amra_core.column`). A step is never a cold start: a cold start lands easily on
the windmill-brake root, a separate equilibrium with 2-4 times the descent rate (model-notes §7).
"""
from __future__ import annotations

import math
from dataclasses import replace
from typing import Optional

import numpy as np

from .equilibrium import TrimResult, _plausible, _solve_at, _trim_axial_from
from .model import CompiledModel, Y_OMEGA, Y_PSI, compile_model, transfer_state


def predict(prev: TrimResult, prev2: Optional[TrimResult], s: float, target: CompiledModel) -> np.ndarray:
    """Secant predictor of the state on ``target``: ``prev + s (prev - prev2)`` (``s``: the new step
    over the last one, in log GJ), both mapped onto ``target``'s layout; ``prev`` alone without ``prev2``."""
    y1 = transfer_state(prev.state, prev.model, target)
    if prev2 is None or s == 0.0:
        return y1
    y0 = transfer_state(prev2.state, prev2.model, target)
    y = y1 + s * (y1 - y0)
    y[Y_PSI] = y1[Y_PSI]
    return y


def _forward_prediction(prev: TrimResult, prev2: TrimResult, s: float, target: CompiledModel) -> TrimResult:
    """The secant prediction of a forward-flight trim on ``target``: state, rotor speed, descent
    rate and shaft tilt extrapolated as :func:`predict` does. (Started from ``prev`` itself, the
    Newton iteration had the whole step's change to close; where the branch bends, as the rigid
    McCutcheon one at mu 0.5 near GJ 2,350 N m^2/rad, it failed, and the branch was reported as
    ending there.)"""
    def ahead(a: float, b: float) -> float:
        return a + s * (a - b)
    return replace(prev, state=predict(prev, prev2, s, target), model=target,
                   omega_rad_s=ahead(prev.omega_rad_s, prev2.omega_rad_s),
                   descent_rate_m_s=ahead(prev.descent_rate_m_s, prev2.descent_rate_m_s),
                   disk_tilt_rad=ahead(prev.disk_tilt_rad, prev2.disk_tilt_rad))


def mark_continued(res: TrimResult, prev: TrimResult) -> TrimResult:
    """Record on ``res`` that it continues the branch through ``prev``: the rotor speed where that
    branch started (``prev``'s own when ``prev`` was solved on its own), which tells an overspeeding
    normal branch from the windmill-brake root (:attr:`TrimResult.branch`)."""
    if res is not None and res.ok:
        start = prev.omega_branch_start_rad_s
        res.omega_branch_start_rad_s = float(start if math.isfinite(start) else prev.omega_rad_s)
    return res


def continue_to(model: CompiledModel, hold, prev: TrimResult, prev2: Optional[TrimResult] = None,
                s: float = 1.0) -> TrimResult:
    """One continuation step: the trim of ``model`` from the predictor through ``prev``/``prev2``
    (never a cold start), marked as continued from ``prev``. The caller checks :func:`on_branch`."""
    return mark_continued(_continue_to(model, hold, prev, prev2, s), prev)


def _continue_to(model: CompiledModel, hold, prev: TrimResult, prev2: Optional[TrimResult], s: float) -> TrimResult:
    try:
        if model.flight.is_axial:
            # the jitted Newton only: where it fails from the predictor the caller halves the step
            # (scipy's hybr, tried here before, rescued none of 183 failed steps over the rigid,
            # fem-torsion and fem-coupled axial maps, and cost 8 % of a rigid map)
            res = _trim_axial_from(model, predict(prev, prev2, s, model), hold, fallback=False)
            if not res.ok and prev2 is not None:
                res = _trim_axial_from(model, predict(prev, None, 0.0, model), hold, fallback=False)
            if res.ok and hold is not None:
                res.model = model.with_controls(hold_omega=True)
            return res
        return _solve_at(model, hold, prev if prev2 is None else _forward_prediction(prev, prev2, s, model))
    except FloatingPointError as exc:
        return TrimResult("no-autorotation", reason=str(exc), model=model)


def _faster_branch(model: CompiledModel, hold, prev: TrimResult) -> Optional[TrimResult]:
    """A normal-branch trim of ``model`` faster than the fold point ``prev`` (axial flight), or None."""
    if not model.flight.is_axial or hold is not None:
        return None
    y = transfer_state(prev.state, prev.model, model)
    for factor in (1.1, 1.25, 1.4):
        g = y.copy(); g[Y_OMEGA] *= factor
        res = _trim_axial_from(model, g, None)
        if _plausible(res, None) and res.branch == "normal" and res.omega_rad_s > prev.omega_rad_s * 1.02:
            return res
    return None


def _with_gj_scale(model: CompiledModel, factor: float) -> CompiledModel:
    from dataclasses import replace
    rotor = model.rotor
    gj = tuple(np.asarray(rotor.stations.gj_nm2) * factor)
    r_f = replace(rotor, stations=replace(rotor.stations, gj_nm2=gj))
    return compile_model(r_f, model.flight, model.settings)
