"""One-shot analyses of a case, run in a worker process (no Panel/HoloViews imports here).

Trim and the eigen-analysis are largely Python/SciPy and hold the GIL; in the server's own
process they would starve the sessions' event loop, so :class:`app.background.LatestTasks` sends
these functions to a process pool. Every argument and result is picklable (frozen dataclasses,
numpy arrays, plain dicts).
"""
from __future__ import annotations

import math

import numpy as np

from amra_core.model import compile_model
from amra_core.shapes import FIDELITIES
from amra_core.simulation import COL, Simulation
from amra_core.stability import analyse

from .locus import walk

LOCUS_GJ_RANGE = (50.0, 3000.0)  #: GJ range of the root locus [N m^2/rad]
FAN_OMEGA_MAX = 60.0  #: top of the fan plot's speed axis [rad/s]
LADDER_POINTS = 2000  #: points kept per ladder curve


def warm_worker() -> bool:
    """Import and touch the kernels in a fresh worker process."""
    from .warmup import warm
    warm()
    return True


def modes_result(rotor, flight, settings) -> dict:
    """The mode table of the trimmed state (``modes``) and a one-line summary (``text``)."""
    with np.errstate(all="ignore"):
        res = analyse(compile_model(rotor, flight, settings))
    if not res.trim.ok:
        return {"modes": [], "text": f"**No trim** for this case, so no modes: {res.trim.reason}"}
    kind = "eigenvalues (axial flight)" if res.method == "eigenvalues" else "Floquet exponents (forward flight)"
    crit = res.critical
    verdict = "**stable**" if res.stable else f"**unstable**: {crit.label} mode, σ = {crit.real_part_per_s:+.3g} 1/s"
    return {"modes": res.modes, "text": f"Modes of the trim ({kind}) at Ω = {res.trim.omega_rad_s:.2f} rad/s: "
                                        f"{verdict}"}


def locus_result(rotor, flight, settings, cg: float) -> dict:
    """Locus points along GJ at chordwise CG ``cg`` [chord fraction] and a summary line."""
    with np.errstate(all="ignore"):
        pts = walk(rotor, flight, settings, cg, *LOCUS_GJ_RANGE)
    trimmed = [p for p in pts if p.trimmed]
    text = f"Root locus: {len(pts)} GJ values from {LOCUS_GJ_RANGE[1]:g} down to {LOCUS_GJ_RANGE[0]:g} N m²/rad"
    if len(trimmed) < len(pts):
        low = min((p.gj_nm2 for p in trimmed), default=math.nan)
        text += f"; no trim (fold) below about {low:.4g} N m²/rad"
    unstable = [p.gj_nm2 for p in trimmed if not p.stable]
    if unstable:
        text += f"; unstable trims at GJ ≤ {max(unstable):.4g} N m²/rad"
    return {"points": pts, "text": text}


def fan_data(rotor, fidelity: str, n_modes: int = 8) -> dict:
    """Tracked in-vacuo mode frequencies [Hz] against rotor speed [rad/s] (``amra_core.modes.fan_plot``)."""
    from amra_core.modes import fan_plot
    fp = fan_plot(rotor, np.linspace(0.0, FAN_OMEGA_MAX, 31), fidelity=fidelity, n_modes=n_modes)
    return {"omega": fp["omega_rad_s"], "modes": [(m["label"], m["frequency_hz"]) for m in fp["modes"]]}


def run_ladder(cases: dict) -> dict:
    """``{fidelity: Case}`` -> ``{"runs": {fidelity: {t, omega, teeter_deg, twist_deg}}, "verdicts": rows}``:
    each case run unpaced to its end, with its verdict."""
    runs, rows = {}, []
    for fid in FIDELITIES:
        case = cases.get(fid)
        if case is None:
            continue
        try:
            with np.errstate(all="ignore"):
                sim = Simulation(case).run(chunk_s=0.5)
                v = sim.verdict()
        except Exception as exc:  # noqa: BLE001 - one failed rung does not stop the ladder
            rows.append((fid, "failed", None, None, None, str(exc)))
            continue
        h = sim.history
        idx = np.linspace(0, len(h) - 1, min(LADDER_POINTS, len(h))).astype(int)
        h = h[idx]
        runs[fid] = {"t": h[:, COL["t_s"]], "omega": h[:, COL["omega_rad_s"]],
                     "teeter_deg": np.degrees(h[:, COL["teeter_rad"]]),
                     "twist_deg": np.degrees(h[:, COL["tip_twist_0_rad"]])}
        rows.append((fid, v.verdict, v.growth_rate_per_s, v.frequency_hz, v.collapse_time_s, v.explanation))
    return {"runs": runs, "verdicts": rows}
