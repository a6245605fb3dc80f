"""Fold and flutter boundaries of a map column, from its intervals (issue 21 §2).

A column walk (:mod:`amra_core.column`) covers the GJ range with intervals of one kind each:
``stable``, ``flutter`` (trimmed on the normal branch with a mode of positive real part; the
interval says which mode, :func:`amra_core.column.instability`), ``fold`` (no normal-branch trim),
``overspeed`` (the normal branch continued, rotor speed risen and descent beyond 2 v_h),
``windmill-brake`` (a separate root below a fold) and ``failed``. From them, per column:

* ``fold_gj`` [N m^2/rad]: no normal autorotation below (the lowest computed GJ above the highest
  ``fold`` / ``overspeed`` / ``windmill-brake`` interval, or above a fold approach merged into it);
* ``flutter_gj``: the lowest computed GJ above the highest *strong* flutter interval (None if none);
* ``critical_gj``: the larger of the two (None if neither; ``inf`` when the column is not stable at
  ``gj_max``); weak windows are reported but never move it.

**Strength.** A flutter interval is ``weak`` when its most unstable oscillating mode has a damping
ratio above ``-weak_damping`` (and nothing non-oscillatory grows) *and* a 20 s run from its most
unstable point with the default kick keeps its rotor speed and stays within ``weak_amplitude_deg``
of twist and teeter (:func:`amra_core.boundary.tasks.interval_outcomes`); else ``strong``. A
monotonic (non-oscillating) growth is always strong, except in a fold approach. Both conditions are
needed: the damping ratio alone does not tell what an instability leads to (see
:data:`WEAK_DAMPING`).

**Fold approach.** A flutter interval directly above a ``fold`` interval in which no blade mode
(teeter, flap, torsion, lag) oscillates with a damping ratio below ``-weak_damping``, and whose run
stays small (as for a weak window), is the fold's own approach (at the fold a real eigenvalue of the rotor speed / inflow / descent equilibrium
passes through zero; measured, rigid axial EA 0.32 CG 0.36: GJ 270-281 above
the branch end at 273, a 0.23 Hz inflow mode at +0.15 1/s and a 3.9 Hz teeter mode at damping ratio
-0.0035): it is merged into the fold (``fold_approach: true``) and moves ``fold_gj`` to its top.

**The default thresholds** :data:`WEAK_DAMPING` = 0.02 and :data:`WEAK_AMPLITUDE_DEG` = 1 deg (see
their comments for the evidence).
"""
from __future__ import annotations

import math
from typing import Optional

#: Flutter intervals whose most unstable oscillating mode has a damping ratio above -WEAK_DAMPING may be
#: weak (if their run stays small, WEAK_AMPLITUDE_DEG). Evidence, paper-boundary EA 0.32, theodorsen,
#: axial, CG 0.24-0.50 (2 % maps): the peak damping ratios of the flutter intervals fall in two groups,
#: -0.0004, -0.002, -0.006, -0.013, -0.016, -0.017 and -0.025, -0.039, -0.049, -0.050, -0.054 ... -0.39,
#: with the gap between -0.017 and -0.025; 0.02 lies in it. A damping ratio of -0.02 at the 11-14 Hz
#: torsion modes is a growth of 1.4-1.8 1/s.
WEAK_DAMPING = 0.02
#: ...and a weak window's 20 s run from the default kick (0.29 deg twist, 0.57 deg teeter) stays within
#: this many degrees of twist and teeter [deg]. Evidence (the same maps, half peak-to-peak over the last
#: third of the run): rigid CG 0.40 GJ 645 (damping ratio -0.013, 12 Hz torsion): 0.38 / 0.13 deg, the
#: audit's marginal window; but rigid CG 0.30 GJ 690 (-0.006, 20 Hz flap): 10 / 17 deg with the rotor
#: speed swinging +/-4 rad/s, and fem-coupled CG 0.30 GJ 320 (-0.016, 12.6 Hz torsion): 7 / 3 deg.
#: Strong windows saturate anywhere from 0.6 deg (rigid CG 0.38 GJ 555, -0.049) to 12 / 15 deg (rigid
#: CG 0.28 GJ 618, -0.025): the damping ratio does not predict the size of the limit cycle, the run does.
WEAK_AMPLITUDE_DEG = 1.0

NO_AUTOROTATION = ("fold", "overspeed", "windmill-brake")


def _run_small(iv: dict, weak_amplitude_deg: float) -> bool:
    """True if the interval's run (:func:`amra_core.boundary.tasks.interval_outcomes`) kept its rotor
    speed and stayed within ``weak_amplitude_deg`` of twist and teeter; True without a run."""
    if "run_outcome" not in iv:
        return True
    amp = iv.get("run_amplitude") or {}
    if iv["run_outcome"] == "rotor-speed-collapse" or iv.get("run_verdict") in ("no-autorotation", "numerical-failure"):
        return False
    return all(amp.get(k) is not None and amp[k] < weak_amplitude_deg for k in ("twist_deg", "teeter_deg"))


def strength_of(iv: dict, weak_damping: float = WEAK_DAMPING, weak_amplitude_deg: float = WEAK_AMPLITUDE_DEG) -> str:
    """``weak`` | ``strong`` of a flutter interval (module docstring). Intervals judged by time
    marching carry the fitted ``peak_growth_rate_1_s`` and ``damping_ratio`` of their most unstable
    cell instead of mode data; without either they are ``strong``: nothing says they are marginal."""
    osc, mono = iv.get("oscillatory"), iv.get("monotonic_growth_rate_1_s")
    if osc is None and mono is None:
        weak = iv.get("peak_growth_rate_1_s") is not None and iv.get("damping_ratio") is not None \
            and -iv["damping_ratio"] < weak_damping
    else:
        weak = mono is None and -osc["damping_ratio"] < weak_damping
    return "weak" if weak and _run_small(iv, weak_amplitude_deg) else "strong"


def _fold_approach_modes(iv: dict, weak_damping: float) -> bool:
    """True when nothing in ``iv`` but the equilibrium's own modes (rotor speed, inflow, descent, or
    a monotonic growth) is strongly unstable: no blade mode oscillates with a damping ratio below
    ``-weak_damping``."""
    if iv.get("oscillatory") is None and iv.get("monotonic_growth_rate_1_s") is None:
        return False  # no mode data (judged by time marching): not known to be an approach
    blade = iv.get("oscillatory_blade")
    return blade is None or -blade["damping_ratio"] < weak_damping


def classify(intervals: list, gj_max: float, weak_damping: float = WEAK_DAMPING,
             weak_amplitude_deg: float = WEAK_AMPLITUDE_DEG) -> dict:
    """Per column (module docstring): ``intervals`` (copies, ascending, each flutter interval with
    ``strength`` and ``fold_approach``), ``fold_gj``, ``branch_end_gj`` (top of the highest
    no-autorotation interval before merging), ``flutter_gj``, ``critical_gj``, ``kind`` (which one
    sets the critical GJ: ``fold`` | ``flutter``) and ``resolved`` (its edge bracketed to tolerance)."""
    ivs = sorted((dict(iv) for iv in intervals), key=lambda iv: iv["gj_lo_nm2"])
    for i, iv in enumerate(ivs):
        if iv["kind"] != "flutter":
            continue
        below = ivs[i - 1] if i > 0 else None
        iv["fold_approach"] = bool(below is not None and (below["kind"] == "fold" or below.get("fold_approach"))
                                   and _fold_approach_modes(iv, weak_damping) and _run_small(iv, weak_amplitude_deg))
        iv["strength"] = strength_of(iv, weak_damping, weak_amplitude_deg) if not iv["fold_approach"] else "weak"

    def above(i: int) -> Optional[float]:
        """The lowest computed GJ above interval i (None at the top of the range)."""
        if i + 1 >= len(ivs):
            return None
        nxt = ivs[i + 1]
        return nxt.get("gj_lo_point_nm2", nxt["gj_lo_nm2"])

    def top_of(pred) -> tuple:
        idx = [i for i, iv in enumerate(ivs) if pred(iv)]
        if not idx:
            return None, None
        i = idx[-1]
        g = above(i)
        return (math.inf if g is None else g), ivs[i]

    branch_end, _ = top_of(lambda iv: iv["kind"] in NO_AUTOROTATION)
    fold, fold_iv = top_of(lambda iv: iv["kind"] in NO_AUTOROTATION or iv.get("fold_approach"))
    flutter, flutter_iv = top_of(lambda iv: iv["kind"] == "flutter" and not iv.get("fold_approach")
                                 and iv.get("strength") == "strong")
    cands = [(g, k, iv) for g, k, iv in ((fold, "fold", fold_iv), (flutter, "flutter", flutter_iv)) if g is not None]
    crit, kind, resolved = None, None, True
    if cands:
        crit, kind, civ = max(cands, key=lambda c: c[0])
        resolved = bool(civ.get("resolved", True))
    top = ivs[-1] if ivs else None
    if top is not None and top["kind"] == "failed":
        resolved = False
    return {"intervals": ivs, "fold_gj": fold, "branch_end_gj": branch_end, "flutter_gj": flutter,
            "critical_gj": crit, "kind": kind, "resolved": resolved}
