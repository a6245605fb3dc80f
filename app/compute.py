"""What the process pools compute (no Panel/HoloViews imports here): the one-shot analyses of a
case (modes, root locus, fan plot, fidelity ladder, mode shapes, sensitivity) and the kernels'
warm-up.

Trim and the eigen-analysis are largely Python/SciPy and hold the GIL; in the server's own
process they would starve the sessions' event loop, so :class:`app.server.pool.LatestTasks` sends
these functions to a process pool. Every argument and result is picklable.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Optional

import numpy as np

from amra_core.model import compile_model
from amra_core.scenario import run_scenario
from amra_core.shapes import FIDELITIES
from amra_core.simulation import COL, Simulation
from amra_core.stability import analyse

LOCUS_GJ_RANGE = (50.0, 3000.0)  #: GJ range of the root locus [N m^2/rad]
FAN_OMEGA_MAX = 60.0  #: top of the fan plot's speed axis [rad/s]
LADDER_POINTS = 2000  #: points kept per ladder curve
LOCUS_REL_TOL = 0.05  #: bracket of the fold and of flutter crossings along the locus [-]


def warm() -> float:
    """Compile (or load from Numba's cache) what a session uses: trim, a short run with a live
    change at every fidelity, the stability analysis and the fan plot; returns the time taken [s]."""
    t0 = time.perf_counter()
    from amra_core.flight import FlightCondition, SolverSettings
    from amra_core.modes import fan_plot
    from amra_core.rotor_io import load_preset
    from amra_core.simulation import Case

    rotor = load_preset("paper-boundary")
    for fid in ("rigid", "fem-torsion", "fem-coupled"):
        settings = SolverSettings(fidelity=fid)
        sim = Simulation(Case(rotor, FlightCondition(), settings, t_end_s=0.1))
        sim.advance(span_s=0.05)
        sim.set_parameters(gj_nm2=1400.0)
        sim.advance(span_s=0.05)
        sim.verdict()
        sim.spanwise_last_revolution()
        analyse(compile_model(rotor, FlightCondition(), settings))
    fan_plot(rotor, [0.0, 30.0], fidelity="rigid")
    return time.perf_counter() - t0


def warm_worker() -> bool:
    """Import and touch the kernels in a fresh worker process."""
    warm()
    return True


@dataclass(frozen=True)
class LocusPoint:
    """The modes of the trim at one GJ [N m²/rad]; ``trimmed`` False where no autorotation exists
    (then ``modes`` is empty)."""

    gj_nm2: float
    trimmed: bool
    modes: tuple  #: stability.Mode, aero-lag modes left out
    max_real_part_per_s: Optional[float]
    stable: bool


def modes_result(rotor, flight, settings) -> dict:
    """The mode table of the trimmed state (``modes``) and a one-line summary (``text``)."""
    with np.errstate(all="ignore"):
        res = analyse(compile_model(rotor, flight, settings))
    if not res.trim.ok:
        return {"modes": [], "text": f"**No trim** for this case, so no modes: {res.trim.reason}"}
    kind = "eigenvalues (axial flight)" if res.method == "eigenvalues" else "Floquet exponents (forward flight)"
    crit = res.critical
    verdict = "**stable**" if res.stable else f"**unstable**: {crit.label} mode, σ = {crit.real_part_per_s:+.3g} 1/s"
    return {"modes": res.modes, "omega_rad_s": float(res.trim.omega_rad_s), "method": res.method,
            "stable": bool(res.stable), "descent_rate_m_s": float(res.trim.descent_rate_m_s),
            "text": f"Modes of the trim ({kind}) at Ω = {res.trim.omega_rad_s:.2f} rad/s: {verdict}"}


def locus_result(rotor, flight, settings, cg: float) -> dict:
    """Locus points along GJ at chordwise CG ``cg`` [chord fraction] and a summary line: the trim
    continued down the column with the modes at each step (``amra_core.column.walk_column``), the
    fold and flutter crossings bracketed."""
    from amra_core.column import walk_column
    with np.errstate(all="ignore"):
        cw = walk_column(rotor, flight, settings, cg, LOCUS_GJ_RANGE[0], LOCUS_GJ_RANGE[1], rel_tol=LOCUS_REL_TOL,
                         modes="forward")  # every mode: the locus draws them all
    pts = []
    for p in cw.points:
        trimmed = p.branch == "normal" and p.trim is not None
        modes = tuple(m for m in (p.modes or ()) if m.label != "aero lag") if trimmed else ()
        re = p.max_real_part_per_s if trimmed and math.isfinite(p.max_real_part_per_s) else None
        pts.append(LocusPoint(float(p.gj_nm2), trimmed, modes, re, bool(p.stable)))
    return {"points": pts, "text": locus_text(pts)}


def locus_text(pts: list) -> str:
    """The locus's summary: where the branch followed down from the stiff end stops (the fold, as
    the map puts it), trims found again below it, and the unstable ones. It took the lowest trim of
    all: an isolated set of violently unstable trims at GJ 50-79 read as the fold (fem-coupled, CG
    40 %), against the map's 700."""
    text = f"Root locus: {len(pts)} GJ values from {LOCUS_GJ_RANGE[1]:g} down to {LOCUS_GJ_RANGE[0]:g} N m²/rad"
    down = sorted(pts, key=lambda p: -p.gj_nm2)
    top = next((i for i, p in enumerate(down) if not p.trimmed), len(down))  # the branch from the top
    if top < len(down):
        if top:  # with the bracket: the locus walks to 5 %, the map and the preset cards to 2 % (Fig. 10's
            # card says "≈ 414" where the locus said only "about 424")
            fold = down[top - 1].gj_nm2
            text += (f"; no trim (fold) below about {fold:.4g} N m²/rad (it lies between the locus's grid "
                     f"points {down[top].gj_nm2:.4g} and {fold:.4g})")
        else:  # ("below about nan" before)
            text += f"; no trim at the stiff end, GJ {down[0].gj_nm2:.4g} N m²/rad"
        again = [p for p in down[top:] if p.trimmed]
        if again:
            worst = max((p.max_real_part_per_s for p in again if p.max_real_part_per_s is not None), default=None)
            lo, hi = min(p.gj_nm2 for p in again), max(p.gj_nm2 for p in again)
            text += (f"; trims again at GJ {lo:.4g}" + (f"-{hi:.4g}" if hi > lo else "") +
                     " N m²/rad, cut off from the branch" + (f" (σ up to {worst:+.3g} 1/s)" if worst is not None else ""))
    # the unstable stretches of the branch, each from its lowest to its highest point (one "GJ <= 667.8"
    # read as unstable all the way down, over the stable 416-623 of fem-coupled CG 40 %)
    runs, run = [], []
    for p in down[:top]:
        if not p.stable:
            run.append(p.gj_nm2)
        elif run:
            runs.append(run); run = []
    if run:
        runs.append(run)
    if runs:
        spans = [f"{r[-1]:.4g}-{r[0]:.4g}" if len(r) > 1 else f"{r[0]:.4g}" for r in reversed(runs)]
        text += f"; unstable trims on the branch at GJ {', '.join(spans)} N m²/rad (the locus's grid points)"
    return text


def fan_data(rotor, fidelity: str, n_modes: int = 8) -> dict:
    """Tracked in-vacuo mode frequencies [Hz] against rotor speed [rad/s] (``amra_core.modes.fan_plot``)."""
    from amra_core.modes import fan_plot
    fp = fan_plot(rotor, np.linspace(0.0, FAN_OMEGA_MAX, 31), fidelity=fidelity, n_modes=n_modes)
    return {"omega": fp["omega_rad_s"], "modes": [(m["label"], m["frequency_hz"]) for m in fp["modes"]]}


def ladder_curves(history: np.ndarray) -> dict:
    """``{t, omega, teeter_deg, twist_deg}`` of a history (rows evenly thinned to :data:`LADDER_POINTS`)."""
    h = history[np.linspace(0, len(history) - 1, min(LADDER_POINTS, len(history))).astype(int)]
    return {"t": h[:, COL["t_s"]], "omega": h[:, COL["omega_rad_s"]],
            "teeter_deg": np.degrees(h[:, COL["teeter_rad"]]),
            "twist_deg": np.degrees(h[:, COL["tip_twist_0_rad"]])}


def run_ladder(scenarios: dict) -> dict:
    """``{fidelity: Scenario}`` -> ``{"runs": {fidelity: ladder_curves}, "verdicts": rows}``: each run
    unpaced to its end, its scripted changes (a softening) included, with its verdict."""
    runs, rows = {}, []
    for fid in FIDELITIES:
        scenario = scenarios.get(fid)
        if scenario is None:
            continue
        try:
            with np.errstate(all="ignore"):
                sim = run_scenario(scenario, chunk_s=0.5)
                v = sim.verdict()
        except Exception as exc:  # noqa: BLE001 - one failed rung does not stop the ladder
            rows.append((fid, "failed", None, None, None, str(exc)))
            continue
        runs[fid] = ladder_curves(sim.history)
        rows.append((fid, v.verdict, v.growth_rate_per_s, v.frequency_hz, v.collapse_time_s, v.explanation))
    return {"runs": runs, "verdicts": rows}


MODE_FRAMES = 24  #: frames of a mode animation (one cycle)
MODE_FLAP_DRAWN = 0.25  #: largest tip flap of a mode as drawn [fraction of the radius]
MODE_TWIST_DRAWN_RAD = math.radians(20.0)  #: largest twist of a mode as drawn [rad]


def mode_frames(rotor, flight, settings, real_part_per_s: float, frequency_hz: float, label: str = "") -> dict:
    """Frames of the trim's mode nearest ``real_part_per_s + i 2 pi frequency_hz`` for
    :class:`app.views.rotor.ModeAnimation`: flap (teeter with it) and twist each scaled to be
    visible (a mode's size is arbitrary), with its true flap-per-twist mix in the ``text``."""
    from amra_core.pose import mode_animation, rotor_pose
    from amra_core.trim import trim
    with np.errstate(all="ignore"):
        tr = trim(compile_model(rotor, flight, settings))
    if not tr.ok:
        return {"error": f"no trimmed autorotation for this case, so no modes ({tr.reason})"}
    a = mode_animation(tr.model, tr.state, real_part_per_s, frequency_hz, n_frames=MODE_FRAMES)
    flap_to_m = MODE_FLAP_DRAWN * rotor.radius_m  # a.flap peaks at 1
    t_max = float(np.abs(a.twist).max())
    twist = a.twist * (MODE_TWIST_DRAWN_RAD / t_max) if t_max > 0 else a.twist
    cyclic = float(np.abs(a.flap[:, 0] + a.flap[:, 1]).max()) < float(np.abs(a.flap[:, 0] - a.flap[:, 1]).max())
    kind = "cyclic (the blades move oppositely: the hub teeters)" if cyclic else "collective (both blades alike)"
    mix = (f"{a.flap_per_twist_m_rad * math.radians(1.0) * 100:.3g} cm of tip flap per degree of tip twist"
           if math.isfinite(a.flap_per_twist_m_rad) else "flap only")
    text = (f"**{label or 'mode'}**, {abs(a.eigenvalue.imag) / (2 * math.pi):.3g} Hz, real part "
            f"{a.eigenvalue.real:+.3g} 1/s: {kind}. Drawn with flap and twist each scaled to be visible; "
            f"the mode's true mix is {mix}.")
    pose = rotor_pose(tr.model, tr.state)
    return {"r_m": pose.r_m.tolist(), "flap": (a.flap * flap_to_m).tolist(), "twist": twist.tolist(),
            "teeter": (a.teeter * flap_to_m).tolist(), "text": text, "chord_m": pose.chord_m, "x_ea": pose.x_ea,
            "radius_m": pose.radius_m}


def sensitivity_study(rotor, flight, settings, cg: float, gj_range: tuple, rel_tol: float, n_probe: int) -> dict:
    """The fold and flutter GJ of CG column ``cg`` [chord fraction] with every estimated rotor value
    changed by -10 % and +10 % (:func:`amra_core.sensitivity.sensitivity`, the map's own column
    walk over ``gj_range`` [N m^2/rad] at the map's ``rel_tol`` and probe grid), as its JSON dict."""
    from amra_core.sensitivity import sensitivity
    with np.errstate(all="ignore"):
        return sensitivity(rotor, cg, settings=settings, flight=flight, gj_min_nm2=gj_range[0],
                           gj_max_nm2=gj_range[1], rel_tol=rel_tol, n_probe=n_probe).to_dict()
