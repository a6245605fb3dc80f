"""Walk one CG column of the stability map down its trim branch (issue 8 §2).

:func:`walk_column` starts at the stiffest blade of the range (``gj_max``) on the normal
autorotation branch and follows that branch downward in log GJ by continuation: every step starts
from the secant predictor of the last two points and is accepted only when rotor speed, descent
rate, inflow and tip twist continue the branch (:func:`amra_core.trim.on_branch`); otherwise the
step is halved. It is never restarted from scratch on the branch, so it cannot slip onto the
windmill-brake root. When the step falls below ``rel_tol`` the branch has ended: that is the
**fold**, bracketed to ``rel_tol``. At every point the least damped modes are computed
(eigenvalues in axial flight, Floquet exponents forward by Arnoldi on the monodromy: see
:data:`FLOQUET_SCHEME`) and every sign change of the largest real part is bisected, by
continuation from the bracketing points, to ``rel_tol``. The step is at most ``max_step`` (ratio)
and shrinks where the largest real part heads towards zero, so narrow unstable windows are seen.

Below a fold (and when no trim exists at ``gj_max``) the column is probed with cold starts on the
coarse grid ``n_probe`` (log-spaced over the range): a probe on the windmill-brake side
(V_c/v_h < -2) is a ``windmill-brake`` point (never stable autorotation); a probe on the normal
side starts a new branch segment, which is walked upward (to bracket where it begins, up to the
fold above) and downward like the first.

Point kinds (and interval kinds): ``stable``, ``flutter`` (trimmed on the normal branch with a
mode of positive real part; the cell verdict says ``divergence`` when it does not oscillate),
``fold`` (no normal-branch trim), ``windmill-brake``, ``failed`` (a numerical failure).
"""
from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass, field
from typing import Callable, Optional

import numpy as np

from .flight import FlightCondition, SolverSettings
from .model import CompiledModel, compile_model
from .periodic_trim import PeriodicContinuation
from .rotor import Rotor
from .stability import MIN_FLUTTER_HZ, UNSTABLE_REAL_PART, Mode, analyse
from .continuation import _faster_branch, continue_to, mark_continued
from .equilibrium import TrimResult, _plausible, _solve_at, on_branch, trim_axial, windmill_brake_state
from .trim import trim

KINDS = ("stable", "flutter", "fold", "overspeed", "windmill-brake", "failed")
#: largest continuation step (GJ ratio) along a column
MAX_STEP = 1.15


@dataclass(frozen=True)
class BranchPoint:
    """One point of a column walk at ``gj_nm2`` [N m^2/rad]: ``branch`` ``normal`` | ``overspeed`` |
    ``windmill-brake`` | ``none`` (:attr:`~amra_core.equilibrium.TrimResult.branch`); ``trim`` (None without equilibrium); ``modes``
    (:class:`~amra_core.stability.Mode`, empty off the normal branch); ``max_real_part_per_s``
    [1/s] (nan without modes); ``stable``: normal branch and every mode decays."""

    gj_nm2: float
    branch: str
    trim: Optional[TrimResult]
    modes: list
    max_real_part_per_s: float
    stable: bool
    reason: str = ""

    @property
    def kind(self) -> str:
        """``stable`` | ``flutter`` | ``fold`` | ``overspeed`` | ``windmill-brake`` | ``failed``."""
        if self.branch in ("windmill-brake", "overspeed"):
            return self.branch
        if self.branch == "none":
            return "fold"
        if not math.isfinite(self.max_real_part_per_s):
            return "failed"
        return "stable" if self.stable else "flutter"

    @property
    def critical(self) -> Optional[Mode]:
        return max(self.modes, key=lambda m: m.real_part_per_s) if self.modes else None


@dataclass
class ColumnWalk:
    """Result of :func:`walk_column`. ``points`` sorted by GJ (ascending); ``intervals``: dicts
    ``{kind, gj_lo_nm2, gj_hi_nm2, resolved}`` covering the range, edges at the geometric mean of
    the two points bracketing a change (``resolved``: both edges bracketed to ``rel_tol``);
    each carries ``gj_lo_point_nm2``/``gj_hi_point_nm2`` (its lowest and highest computed point) and,
    for ``flutter``, what is unstable (:func:`instability`); ``critical_gj_nm2``: the lowest point from which the column is stable up to ``gj_max`` (upper
    end of its bracket; None if stable throughout, inf if unstable at ``gj_max``); ``fold_gj_nm2``:
    the lowest GJ of the branch through ``gj_max`` when it folds inside the range (else None)."""

    cg: float
    gj_min_nm2: float
    gj_max_nm2: float
    rel_tol: float
    points: list = field(default_factory=list)
    intervals: list = field(default_factory=list)
    critical_gj_nm2: Optional[float] = None
    fold_gj_nm2: Optional[float] = None
    cancelled: bool = False
    n_trims: int = 0
    wall_time_s: float = 0.0


class _Cancelled(Exception):
    pass


#: the walk's Floquet analysis in forward flight (``stability.analyse``): only the least damped modes,
#: which are all the walk and the map read (stability, step control, the critical mode)
FLOQUET_SCHEME = "krylov"

#: real parts compared along the walk for the step control: the least damped few structural modes
N_STEP_MODES = 4


def _least_damped(p: BranchPoint) -> list:
    """The ``N_STEP_MODES`` largest real parts [1/s] of ``p``'s modes other than the aerodynamic lag
    states, sorted down (ranks, not tracked modes: a step-size heuristic only)."""
    return sorted((m.real_part_per_s for m in p.modes if m.label != "aero lag"), reverse=True)[:N_STEP_MODES]


class _Walker:
    def __init__(self, rotor, flight, settings, cg, gj_min, gj_max, rel_tol, on_point, cancel, max_step, n_probe,
                 modes=FLOQUET_SCHEME):
        self.base = rotor.with_overrides(x_cg=cg)
        self.flight, self.settings = flight, settings
        self.axial = flight.is_axial
        self.gj_min, self.gj_max = float(gj_min), float(gj_max)
        self.h_min = math.log1p(rel_tol)
        self.h_max = max(math.log(max_step), 2 * self.h_min)
        self.h_floor = min(2 * self.h_min, self.h_max)
        self.on_point, self.cancel = on_point, cancel
        self.points: dict = {}
        self.n_trims = 0
        self.n_probe = n_probe
        self.unresolved: set = set()  # GJ pairs whose bracket could not be narrowed
        self.top_omega: Optional[float] = None
        self._models: dict = {}
        self.periodic = PeriodicContinuation()
        self.modes_scheme = modes  #: stability.analyse's scheme at every point

    # ---------------------------------------------------------------- models and points
    def model(self, gj: float) -> CompiledModel:
        """The compiled model at ``gj`` (kept for the step retries and bisection at the same GJ)."""
        m = self._models.get(gj)
        if m is None:
            if len(self._models) > 8:
                self._models.clear()
            m = self._models[gj] = compile_model(self.base.with_overrides(gj_nm2=gj), self.flight, self.settings)
        return m

    def _check_cancel(self):
        if self.cancel is not None and self.cancel.is_set():
            raise _Cancelled

    def add(self, gj: float, tr: Optional[TrimResult], reason: str = "") -> BranchPoint:
        self._check_cancel()
        branch = tr.branch if tr is not None else "none"
        modes, sig, stable = [], float("nan"), False
        if branch in ("normal", "overspeed"):
            try:
                with np.errstate(all="ignore"):
                    res = analyse(tr.model, tr, self.modes_scheme)
                modes = res.modes
                sig = max(m.real_part_per_s for m in modes) if modes else float("nan")
                stable = bool(res.stable) and math.isfinite(sig) and branch == "normal"
                if not math.isfinite(sig):
                    reason = reason or "numerical failure: non-finite exponents"
            except Exception as exc:  # noqa: BLE001 - a failed point is a result
                reason = f"{type(exc).__name__}: {exc}"
        if branch == "overspeed":
            reason = reason or (f"the normal branch overspeeding: rotor speed {tr.omega_rad_s:.1f} rad/s (the branch "
                                f"started at {tr.omega_branch_start_rad_s:.1f}), descent rate {tr.descent_rate_m_s:.1f} "
                                f"m/s ({tr.descent_ratio:.2f} v_h), inflow {tr.inflow_m_s:.1f} m/s")
        elif branch == "windmill-brake":
            reason = reason or (f"equilibrium on the windmill-brake side: descent rate {tr.descent_rate_m_s:.1f} m/s "
                                f"({tr.descent_ratio:.2f} v_h), not autorotation")
        p = BranchPoint(float(gj), branch, tr, modes, sig, stable, reason)
        self.points[p.gj_nm2] = p
        if self.on_point is not None:
            self.on_point(p)
        return p

    def step(self, gj: float, a: BranchPoint, b: Optional[BranchPoint], s: float) -> Optional[TrimResult]:
        """Trim at ``gj`` continued from ``a`` (secant through ``b``); None if it leaves the branch."""
        self._check_cancel()
        self.n_trims += 1
        if not self.axial:  # periodic trim continued from a's orbit (Broyden-updated Jacobian)
            tr = mark_continued(self.periodic.step(self.model(gj), a.trim, None if b is None else b.trim, s), a.trim)
            if on_branch(tr, a.trim, None if b is None else b.trim, s):
                return tr
            if b is None:
                return None
            self.n_trims += 1  # the secant may overshoot near a fold: one more try from a alone
            tr = mark_continued(self.periodic.step(self.model(gj), a.trim), a.trim)
            return tr if on_branch(tr, a.trim, None, 0.0) else None
        tr = continue_to(self.model(gj), None, a.trim, None if b is None else b.trim, s)
        if on_branch(tr, a.trim, None if b is None else b.trim, s):
            return tr
        if b is not None:  # the secant may overshoot near a fold: one more try from a alone
            self.n_trims += 1
            tr = continue_to(self.model(gj), None, a.trim, None, 0.0)
            if on_branch(tr, a.trim, None, 0.0):
                return tr
        return None

    def cold(self, gj: float, ref: Optional[BranchPoint] = None) -> Optional[TrimResult]:
        """A cold-start equilibrium at ``gj`` (probe below a fold), or None. After a fold where the
        rotor speed was rising (``ref``: the branch end), the faster branch of an S-curve is tried first."""
        self._check_cancel()
        self.n_trims += 1
        m = self.model(gj)
        if ref is not None and ref.trim is not None and self.axial and self.top_omega is not None \
                and ref.trim.omega_rad_s > self.top_omega:
            jump = _faster_branch(m, None, ref.trim)
            if jump is not None:
                return jump
        try:
            tr = trim_axial(m) if self.axial else _solve_at(m, None, None)
        except FloatingPointError:
            tr = None
        if tr is not None and _plausible(tr, None):
            return tr
        if self.axial:
            return windmill_brake_state(m)
        return None

    # ---------------------------------------------------------------- bisection of sign changes
    @staticmethod
    def _sign(p: BranchPoint) -> Optional[bool]:
        return None if not math.isfinite(p.max_real_part_per_s) else p.max_real_part_per_s >= UNSTABLE_REAL_PART

    @staticmethod
    def _cls(p: BranchPoint) -> Optional[str]:
        """The class compared along a segment: stable | flutter | windmill-brake (None: failed)."""
        k = p.kind
        return None if k in ("failed", "fold") else k

    def bisect(self, hi: BranchPoint, lo: BranchPoint) -> None:
        """Bracket the change of class (stability, or the crossing of V_c/v_h = -2) between ``hi`` and
        ``lo`` (same branch segment) to rel_tol."""
        while math.log(hi.gj_nm2 / lo.gj_nm2) > self.h_min * (1 + 1e-9):
            t = 0.5
            gj = math.sqrt(hi.gj_nm2 * lo.gj_nm2)
            tr = self.step(gj, hi, lo, -t)
            if tr is None:
                tr = self.step(gj, lo, hi, -t)
            if tr is None:
                self.unresolved.add((lo.gj_nm2, hi.gj_nm2))
                return
            mid = self.add(gj, tr)
            if self._cls(mid) is None:
                self.unresolved.add((lo.gj_nm2, hi.gj_nm2))
                return
            if self._cls(mid) == self._cls(hi):
                hi = mid
            else:
                lo = mid

    # ---------------------------------------------------------------- walking a segment
    def walk(self, start: BranchPoint, direction: int, stop_gj: float) -> Optional[BranchPoint]:
        """Follow the branch through ``start`` towards ``stop_gj`` (direction -1: down in GJ,
        +1: up). Returns the last point when the branch folds first (None if it reaches stop_gj)."""
        prev, prev2 = start, None
        ln_cur, ln_stop = math.log(start.gj_nm2), math.log(stop_gj)
        h, h_prev = self.h_max, self.h_max
        while (ln_cur - ln_stop) * -direction > 1e-12:
            h = min(h, abs(ln_cur - ln_stop))
            ln_new = ln_cur + direction * h
            gj = stop_gj if abs(ln_new - ln_stop) < 1e-12 else math.exp(ln_new)
            tr = self.step(gj, prev, prev2, h / h_prev)
            if tr is None:
                if h <= self.h_min * (1 + 1e-9):  # fold: no branch a rel_tol step further
                    why = f"the trim branch ends (fold): no continuation from GJ {prev.gj_nm2:.1f} N m^2/rad"
                    if not self.axial and self._sign(prev):
                        why += " (forward flight: the periodic orbit there is unstable)"
                    self.add(gj, None, why)
                    return prev
                h = max(h / 2, self.h_min)
                continue
            p = self.add(gj, tr)
            sa, sb = self._sign(prev), self._sign(p)
            ca, cb = self._cls(prev), self._cls(p)
            if ca is not None and cb is not None and ca != cb:
                hi_, lo_ = (prev, p) if direction < 0 else (p, prev)
                self.bisect(hi_, lo_)
            h_next = min(1.5 * h, self.h_max)
            if sa is not None and sb is not None and sa == sb:
                # a least-damped real part heading for zero: shorten the step so a window is not jumped
                # (not only the largest: a torsion mode 4th in line can rise from -4 to +5 1/s within 7 %
                # of GJ and back, rigid axial CG 0.36 GJ 434-482, which the largest alone stepped over)
                for ra, rb in zip(_least_damped(prev), _least_damped(p)):
                    d_sig = rb - ra
                    if d_sig * rb < 0:
                        dist = abs(rb) / abs(d_sig) * h
                        h_next = min(h_next, max(0.5 * dist, self.h_floor))
            prev2, prev, h_prev, ln_cur = prev, p, h, ln_new
            h = h_next
        return None

    def top(self) -> Optional[TrimResult]:
        """The normal-branch trim at gj_max (by continuation from a stiffer blade)."""
        self.n_trims += 1
        m = self.model(self.gj_max)
        tr = None
        if not self.axial:
            try:
                tr = _solve_at(m, None, None)
            except FloatingPointError:
                tr = None
        if tr is None or not _plausible(tr, None) or tr.branch != "normal":
            tr = trim(m)
        return tr if tr.ok and tr.branch == "normal" else None

    def run(self) -> Optional[float]:
        tr = self.top()
        fold_gj = None
        below = self.gj_max
        end = None
        if tr is not None:
            self.top_omega = tr.omega_rad_s
            p = self.add(self.gj_max, tr)
            end = self.walk(p, -1, self.gj_min)
            if end is None:
                return None
            fold_gj = end.gj_nm2
            below = end.gj_nm2
        self.probe(below, upper_fold=fold_gj, ref=end)
        return fold_gj

    def probe(self, below: float, upper_fold: Optional[float], ref: Optional[BranchPoint] = None) -> None:
        """Cold-start probes on the coarse grid below ``below``; a normal-branch probe starts a
        new segment walked up (to ``upper`` at most) and down. Forward flight: not probed (a cold
        periodic trim costs as much as a whole column walk); the range below is ``fold``."""
        if not self.axial:
            if upper_fold is None and self.gj_max not in self.points:
                self.add(self.gj_max, None, "no normal-branch trim at the stiffest blade of the range")
            if self.gj_min not in self.points:
                self.add(self.gj_min, None, "not probed below the fold in forward flight")
            return
        grid = [g for g in np.geomspace(self.gj_min, self.gj_max, self.n_probe)[::-1] if g < below * (1 - 1e-9)]
        if upper_fold is None and not grid or (grid and grid[-1] > self.gj_min * (1 + 1e-9)):
            grid.append(self.gj_min)
        if upper_fold is None and self.gj_max not in self.points:
            self.add(self.gj_max, None, "no normal-branch trim at the stiffest blade of the range")
        upper = below
        for gj in grid:
            if gj in self.points:
                continue
            tr = self.cold(float(gj), ref)
            p = self.add(float(gj), tr, "" if tr is not None else "no equilibrium found (cold starts)")
            if p.branch != "normal":
                continue
            self.walk(p, +1, upper)  # where does this segment begin (up to the fold above)?
            end = self.walk(p, -1, self.gj_min)
            if end is not None:
                self.probe(end.gj_nm2, upper_fold=end.gj_nm2, ref=end)
            return


def _intervals(points: list, gj_min: float, gj_max: float, rel_tol: float, complete: bool) -> list:
    out = []
    tol = math.log1p(rel_tol) * (1 + 1e-9)
    for i, p in enumerate(points):
        if out and out[-1]["kind"] == p.kind:
            out[-1]["_last"] = i
            continue
        if out:
            q = points[out[-1]["_last"]]
            edge = math.sqrt(q.gj_nm2 * p.gj_nm2)
            ok = math.log(p.gj_nm2 / q.gj_nm2) <= tol
            out[-1]["gj_hi_nm2"] = edge
            out[-1]["_hi_ok"] = ok
            out.append({"kind": p.kind, "gj_lo_nm2": edge, "_lo_ok": ok, "_last": i})
        else:
            out.append({"kind": p.kind, "gj_lo_nm2": gj_min if complete else p.gj_nm2, "_lo_ok": True, "_last": i})
    if out:
        out[-1]["gj_hi_nm2"] = gj_max if complete or points[-1].gj_nm2 == gj_max else points[-1].gj_nm2
        out[-1]["_hi_ok"] = True
    res = []
    first = 0
    for iv in out:
        # windmill-brake / fold edges come from probes: bracketed to the probe grid only
        d = {"kind": iv["kind"], "gj_lo_nm2": iv["gj_lo_nm2"], "gj_hi_nm2": iv["gj_hi_nm2"],
             "resolved": bool(iv["_lo_ok"] and iv["_hi_ok"]),
             "gj_lo_point_nm2": points[first].gj_nm2, "gj_hi_point_nm2": points[iv["_last"]].gj_nm2}
        if iv["kind"] == "flutter":
            d.update(instability(points[first:iv["_last"] + 1]))
        first = iv["_last"] + 1
        res.append(d)
    return res


#: modes labelled by a variable of the trim equilibrium (not of the blade): the eigenvalue that passes
#: through zero at a fold is one of them
EQUILIBRIUM_MODES = ("rotor speed", "inflow", "descent")


def _mode_record(m: Mode) -> dict:
    return {"mode": m.label, "growth_rate_1_s": float(m.real_part_per_s), "damping_ratio": float(m.damping_ratio),
            "frequency_hz": float(m.frequency_hz),
            "participation": {k: round(float(v), 3) for k, v in m.participation.items()}}


def instability(points: list) -> dict:
    """What is unstable in a run of unstable points of one interval (issue 21 §1): at the point of
    largest real part, that mode's ``peak_growth_rate_1_s`` [1/s], ``damping_ratio`` [-] (negative:
    growing), ``frequency_hz`` [Hz], ``mode`` label and ``participation`` (rotor speed, teeter,
    flap, torsion, lag, inflow, descent); ``oscillatory``: the unstable oscillating mode
    (frequency >= ``MIN_FLUTTER_HZ``) of most negative damping ratio over the interval's points
    (None if none); ``oscillatory_blade``: the same among the modes not labelled by an equilibrium
    variable (:data:`EQUILIBRIUM_MODES`); ``monotonic_growth_rate_1_s``: the largest real part of an unstable mode that
    does not oscillate (None if none); ``n_points``."""
    pts = [p for p in points if getattr(p, "modes", None)]
    out = {"peak_growth_rate_1_s": None, "damping_ratio": None, "frequency_hz": None, "mode": None,
           "participation": {}, "oscillatory": None, "oscillatory_blade": None, "monotonic_growth_rate_1_s": None, "n_points": len(points)}
    if not pts:
        return out
    peak = max(pts, key=lambda p: p.max_real_part_per_s).critical
    rec = _mode_record(peak)
    out.update({"peak_growth_rate_1_s": rec["growth_rate_1_s"], "damping_ratio": rec["damping_ratio"],
                "frequency_hz": rec["frequency_hz"], "mode": rec["mode"], "participation": rec["participation"]})
    unstable = [m for p in pts for m in p.modes if m.real_part_per_s >= UNSTABLE_REAL_PART and m.label != "aero lag"]
    osc = [m for m in unstable if m.frequency_hz >= MIN_FLUTTER_HZ]
    if osc:
        out["oscillatory"] = _mode_record(min(osc, key=lambda m: m.damping_ratio))
    blade = [m for m in osc if m.label not in EQUILIBRIUM_MODES]
    out["oscillatory_blade"] = _mode_record(min(blade, key=lambda m: m.damping_ratio)) if blade else None
    mono = [m.real_part_per_s for m in unstable if m.frequency_hz < MIN_FLUTTER_HZ]
    if mono:
        out["monotonic_growth_rate_1_s"] = float(max(mono))
    return out


def summarise(points: list, gj_min: float, gj_max: float, rel_tol: float, complete: bool = True):
    """(intervals, critical GJ) of a column's points (see :class:`ColumnWalk`)."""
    pts = sorted(points, key=lambda p: p.gj_nm2)
    if not pts:
        return [], None
    intervals = _intervals(pts, gj_min, gj_max, rel_tol, complete)
    if pts[-1].kind != "stable":
        return intervals, math.inf
    i = len(pts) - 1
    while i > 0 and pts[i - 1].kind == "stable":
        i -= 1
    return intervals, (None if i == 0 else pts[i].gj_nm2)


def walk_column(rotor: Rotor, flight: FlightCondition, settings: SolverSettings, cg: float,
                gj_min_nm2: float, gj_max_nm2: float, *, rel_tol: float = 0.02,
                on_point: Optional[Callable[[BranchPoint], None]] = None,
                cancel: Optional[threading.Event] = None, max_step: float = MAX_STEP,
                n_probe: int = 7, modes: str = FLOQUET_SCHEME) -> ColumnWalk:
    """Walk the CG column ``cg`` [chord fraction] of ``rotor`` (which already carries the EA) from
    ``gj_max_nm2`` down to ``gj_min_nm2`` [N m^2/rad] along its trim branch (module docstring).
    ``on_point(point)`` is called with every :class:`BranchPoint` as it is found (walk order);
    ``cancel``: a ``threading.Event`` checked between points (a cancelled walk returns what it
    has, ``cancelled=True``); ``max_step``: largest GJ ratio of one step; ``n_probe``: coarse
    grid of the cold-start probes below a fold; ``modes``: the analysis at each point
    (``stability.analyse``'s scheme): :data:`FLOQUET_SCHEME`, the least damped modes (the map), or
    ``"forward"``, every mode (the dashboard's root locus draws them all)."""
    if not 0 < gj_min_nm2 < gj_max_nm2:
        raise ValueError(f"gj_min_nm2 = {gj_min_nm2!r}, gj_max_nm2 = {gj_max_nm2!r}: need 0 < gj_min < gj_max")
    if not 0 < rel_tol < 1:
        raise ValueError(f"rel_tol = {rel_tol!r} is not allowed: must be in (0, 1)")
    t0 = time.perf_counter()
    w = _Walker(rotor, flight, settings, cg, gj_min_nm2, gj_max_nm2, rel_tol, on_point, cancel, max_step,
                max(int(n_probe), 2), modes)
    cancelled, fold = False, None
    try:
        fold = w.run()
    except _Cancelled:
        cancelled = True
    pts = sorted(w.points.values(), key=lambda p: p.gj_nm2)
    intervals, crit = summarise(pts, gj_min_nm2, gj_max_nm2, rel_tol, complete=not cancelled)
    return ColumnWalk(float(cg), float(gj_min_nm2), float(gj_max_nm2), rel_tol, pts, intervals, crit, fold,
                      cancelled, w.n_trims, time.perf_counter() - t0)
