"""Trim: steady autorotation for the flight condition, found by continuation from a stiff blade.

:func:`trim` follows the trim branch in GJ from a 30x stiffer blade down to the requested one
(:mod:`amra_core.continuation`), solving each point with :mod:`amra_core.equilibrium`, so the result
is the physical branch and not a spurious root. When no steady autorotation exists,
:class:`TrimResult` says ``no-autorotation``, why, and the last converged point of the continuation
(where the trim branch ended).

The names of :mod:`amra_core.equilibrium` and :mod:`amra_core.continuation` that callers used from
this module are re-exported here.
"""
from __future__ import annotations

import math
from typing import Optional

import numpy as np

from .continuation import _faster_branch, _with_gj_scale, continue_to, predict  # noqa: F401
from .equilibrium import (FORWARD_COLD_START_MU, FORWARD_MIN_STEP_MU, FORWARD_STEP_MU, MU_RANGE,  # noqa: F401
                          STEP_OMEGA_REL, STEP_SPEED_VH, STEP_TWIST_RAD, on_branch,
                          WINDMILL_BRAKE_RATIO, TrimResult, _hover_induced, _plausible, _solve_at,
                          _trim_axial_from, branch_of, gj_mean_of, omega_guess, trim_axial, trim_forward,
                          trim_forward_continued, windmill_brake_state)
from .floquet import UNSTABLE_REAL_PART, floquet_krylov
from .model import CompiledModel, stable_time_step


#: Mean GJ [N m^2/rad] above which the trim's stiff start gains nothing: 30x the top of the boundary
#: map's GJ range (3000), where the elastic twist is 1/60 of the nominal McCutcheon blade's (GJ 1478).
#: A stiffer start only shortens the explicit time step of the forward-flight marching (at GJ 3e7 the
#: torsion mode sets 50 us: a rigid GJ 1e6 trim at mu 0.5 took 7 s, 6.6 s of it at the start).
STIFF_START_GJ_NM2 = 9.0e4


def trim(model: CompiledModel, omega_hold: Optional[float] = None, n_steps: int = 8,
         stiff_factor: float = 30.0, rel_tol: float = 0.02) -> TrimResult:
    """Trim for the model's flight condition, following the trim branch by continuation in GJ
    from a ``stiff_factor`` times stiffer blade down to the model's GJ (so the solution is the
    physical branch, not a spurious root). Steps start at ``n_steps`` per the whole range in log GJ;
    a step whose result leaves the branch (:func:`on_branch`: a jump in rotor speed, descent rate,
    inflow or twist, or another branch class) is halved, never restarted from scratch. If the step
    falls below ``rel_tol`` the branch has ended (a fold: the torque balance has no solution): the
    result is ``no-autorotation`` with ``branch_end`` (GJ scale, mean GJ, rotor speed, descent rate
    and tip twist of the last trimmed point, and a windmill-brake equilibrium at the requested GJ
    if one exists) and that point's state and model in ``state``/``model``, from which a simulation
    can start (model-notes §7). In forward flight ``branch_end["last_trim_max_multiplier"]`` is the
    largest Floquet multiplier of that last trimmed point (the fold's own one left out,
    :func:`_largest_multiplier`), and ``last_trim_unstable`` says whether it shows that point already
    unstable. Then the reason does not call the end a fold: the continuation cannot hold an unstable
    periodic orbit, and the branch may go on below (rigid McCutcheon, mu 0.1: it ends at GJ 299,
    and settled shooting trims GJ 290 and 280, also unstable). The stiff start is never stiffer than
    STIFF_START_GJ_NM2 (mean GJ) unless the blade itself is: a blade of GJ 1e6 starts at its own GJ,
    not at 3e7."""
    hold = omega_hold if omega_hold is not None else model.flight.omega_hold_rad_s
    if hold is not None and not model.flight.is_axial:
        return _solve_at(model, hold, None)  # rotor speed held (Table 1): no autorotation branch to follow
    stiff_factor = min(stiff_factor, max(1.0, STIFF_START_GJ_NM2 / gj_mean_of(model)))
    m_stiff = model if stiff_factor <= 1.0 else _with_gj_scale(model, stiff_factor)
    try:
        first = _solve_at(m_stiff, hold, None)
    except FloatingPointError as exc:
        first = TrimResult("no-autorotation", reason=str(exc), model=m_stiff)
    if first.status == "thrust-limited":
        return _solve_at(model, hold, None)
    if not _plausible(first, None) or first.branch != "normal":
        first.status = "no-autorotation"
        first.reason = first.reason or f"no steady autorotation even for a {stiff_factor:g}x stiffer blade"
        return first
    ln_f, h_max = math.log(stiff_factor), math.log(stiff_factor) / max(n_steps - 1, 1)
    h_min = math.log1p(rel_tol)
    prev, prev2, h_prev = first, None, h_max
    ln_cur, h = ln_f, h_max
    while ln_cur > 0.0:
        h = min(h, ln_cur)
        ln_new = ln_cur - h
        m_f = model if ln_new <= 0.0 else _with_gj_scale(model, math.exp(ln_new))
        res = continue_to(m_f, hold, prev, prev2, h / h_prev)
        if res.status == "thrust-limited":
            return res if ln_new <= 0.0 else _solve_at(model, hold, None)
        if on_branch(res, prev, prev2, h / h_prev):
            prev2, prev, h_prev, ln_cur = prev, res, h, ln_new
            h = min(h * 1.5, h_max)
            continue
        if h > h_min * (1 + 1e-9) and ln_cur > 0.0:
            h = max(h / 2, h_min)
            continue
        return _branch_end(model, hold, first, prev, math.exp(ln_cur))
    return prev


def _branch_end(model: CompiledModel, hold, first: TrimResult, prev: TrimResult, lo: float) -> TrimResult:
    """The result for a trim branch that ends (folds) at GJ scale ``lo`` above the model's GJ."""
    gj_mean = gj_mean_of(model)
    out = TrimResult("no-autorotation", model=prev.model, state=prev.state)
    # which way the rotor speed was heading along the branch tells the two folds apart
    runaway = "overspeed" if prev.omega_rad_s > first.omega_rad_s else "collapse"
    if runaway == "overspeed":
        # the branch may fold back onto a faster one (an S-curve): a trim there is the
        # state the rotor jumps to; only without one does it run away
        jump = _faster_branch(model, hold, prev)
        if jump is not None:
            jump.reason = (f"the trim branch through the stiff blade folds at mean GJ "
                           f"{gj_mean * lo:.0f} N m^2/rad; this trim is on the faster branch")
            return jump
    multiplier = _largest_multiplier(prev) if not model.flight.is_axial else None
    period_s = 2.0 * math.pi / prev.omega_rad_s
    unstable = bool(multiplier is not None and math.log(max(multiplier, 1e-300)) / period_s > UNSTABLE_REAL_PART)
    if unstable:
        out.reason = (f"no trim found below mean GJ {gj_mean * lo:.0f} N m^2/rad, and that is not shown to be a "
                      f"fold: the last trimmed point of the branch followed down in GJ is already unstable (its "
                      f"largest Floquet multiplier is {multiplier:.3f} per revolution), and the continuation cannot "
                      f"hold an unstable periodic orbit. An unstable (fluttering) autorotation may go on below")
    elif runaway == "collapse":
        out.reason = ("no steady autorotation: following the trim branch down in GJ, the torque balance "
                      "loses its solution (elastic nose-up twist raises the blade pitch until drag wins)")
    else:
        out.reason = ("no steady autorotation: following the trim branch down in GJ, the elastic nose-down "
                      "twist lowers the blade pitch as the rotor speeds up, until no rotor speed balances "
                      "the torque (the rotor runs away upwards)")
    out.branch_end = {"gj_scale": float(lo), "gj_mean_nm2": gj_mean * float(lo),
                      "omega_rad_s": float(prev.omega_rad_s),
                      "descent_rate_m_s": float(prev.descent_rate_m_s),
                      "disk_tilt_rad": float(prev.disk_tilt_rad),
                      "tip_twist_rad": float(prev.tip_twist_rad),
                      "omega_stiff_rad_s": float(first.omega_rad_s), "runaway": runaway,
                      "last_trim_max_multiplier": multiplier, "last_trim_unstable": unstable}
    wb = windmill_brake_state(model, hold)
    if wb is not None:
        out.branch_end["windmill_brake_descent_rate_m_s"] = float(wb.descent_rate_m_s)
        out.reason += (f"; an equilibrium exists on the windmill-brake side (descent rate {wb.descent_rate_m_s:.1f} m/s, "
                       f"{wb.descent_ratio:.1f} v_h), which is not autorotation")
    out.start = prev
    return out


def _largest_multiplier(res: TrimResult) -> float:
    """The largest Floquet multiplier magnitude [per revolution] of a forward-flight trim ``res``
    (Arnoldi, :func:`amra_core.floquet.floquet_krylov`, at the step :func:`amra_core.stability.analyse`
    uses), leaving out the real positive multiplier nearest 1: at a fold that one passes through 1 (the
    branch's own direction), whatever the other modes do. Fem-torsion McCutcheon, mu 0.5, last trim
    (GJ 2103): -5.45, -3.04 and +0.996, the last one left out. Above 1 (by more than
    :data:`amra_core.floquet.UNSTABLE_REAL_PART` in a revolution) the periodic autorotation is unstable
    apart from the fold."""
    dt = stable_time_step(res.model, 1.3 * res.omega_rad_s)
    z = floquet_krylov(res.model, res.state, dt)[0]
    positive = np.flatnonzero((np.abs(z.imag) <= 1e-9 * np.abs(z)) & (z.real > 0.0))
    if len(positive):
        z = np.delete(z, positive[np.argmin(np.abs(z[positive].real - 1.0))])
    return float(np.abs(z).max()) if len(z) else 0.0
