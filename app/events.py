"""What a session tells its views: one frozen dataclass per kind of news (SI units unless a name
says otherwise). The run thread, the analysis pool and the map job produce them;
:class:`app.session.Session` hands each to the views that subscribed to its type."""
from __future__ import annotations

from dataclasses import dataclass, make_dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True)
class Notice:
    """A message for the page (``level``: error, warning or info)."""
    text: str
    level: str = "error"


@dataclass(frozen=True)
class RunStatus:
    """What the run is doing (``state``: trimming, running, idle) as a line of text; while it runs
    once a second, and when it ends, with its rotor speed."""
    run_id: int
    state: str
    text: str
    omega_rad_s: float | None = None


@dataclass(frozen=True)
class Started:
    """A run's trim is done; it streams from now on."""
    run_id: int
    start_note: str


@dataclass(frozen=True)
class Rows:
    """New full-resolution history rows (columns ``HISTORY_COLUMNS``), computed with ``gj_nm2``."""
    run_id: int
    rows: np.ndarray
    gj_nm2: float
    t_s: float


@dataclass(frozen=True)
class Applied:
    """A live or scripted change (GJ [N m²/rad], EA and CG [chord fractions]) took effect at ``t_s``."""
    run_id: int
    values: dict
    t_s: float

    def text(self, sep: str = " ", unit: bool = False) -> str:
        """The new values, e.g. ``GJ 700 EA 30%`` (``unit``: with GJ's unit)."""
        return live_values_text(self.values, sep, unit)


def live_values_text(values: dict, sep: str = " ", unit: bool = False) -> str:
    """GJ [N m²/rad], EA and CG [chord fractions] of a live change as text, e.g. ``GJ 700 EA 30 %``
    (``unit``: with GJ's unit); the values absent are left out."""
    v = values
    parts = [f"GJ {v['gj_nm2']:.4g}" + (" N m²/rad" if unit else "")] if v.get("gj_nm2") is not None else []
    parts += [f"{n} {100 * v[k]:.3g} %" for n, k in (("EA", "x_ea"), ("CG", "x_cg")) if v.get(k) is not None]
    return sep.join(parts)


@dataclass(frozen=True)
class VerdictNews:
    """The verdict so far (``final`` False) or at the end of the run."""
    run_id: int
    verdict: Any  #: amra_core.verdict.Verdict
    final: bool
    status: str
    start_note: str


@dataclass(frozen=True)
class Pose:
    """Both blades' shape at ``t_s`` (``amra_core.pose.RotorPose``), for the live rotor drawing."""
    run_id: int
    pose: Any
    t_s: float


@dataclass(frozen=True)
class Disc:
    """Spanwise distributions over the last revolution (``Simulation.spanwise_last_revolution``)."""
    run_id: int
    data: dict


@dataclass(frozen=True)
class Finished:
    """The run ended (completed, stopped or failed); ``history`` is its full-resolution history."""
    run_id: int
    history: np.ndarray
    status: str
    stopped: bool
    t_s: float


def _result(name: str, function: str):
    return make_dataclass(name, [("result", dict)], frozen=True,
                          namespace={"__doc__": f"The result of :func:`app.compute.{function}`.",
                                     "__module__": __name__})


# the analyses' results from the process pool, one type per analysis
Modes = _result("Modes", "modes_result")
Locus = _result("Locus", "locus_result")
Fan = _result("Fan", "fan_data")
Ladder = _result("Ladder", "run_ladder")
ModeFrames = _result("ModeFrames", "mode_frames")
Sensitivity = _result("Sensitivity", "sensitivity_study")
