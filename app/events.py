"""What a session tells its views: one frozen dataclass per kind of news.

The run thread, the analysis pool and the map job produce these; :class:`app.session.Session`
hands each to the views that subscribed to its type, on the session's event loop. Units are SI
unless a name says otherwise.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True)
class Notice:
    """A message for the page (``level``: error, warning or info)."""
    text: str
    level: str = "error"


@dataclass(frozen=True)
class RunStatus:
    """What the run is doing, as a line of text (``state``: trimming, running, idle)."""
    run_id: int
    state: str
    text: str


@dataclass(frozen=True)
class Started:
    """A run's trim is done; it streams from now on."""
    run_id: int
    start_note: str
    omega_ref_rad_s: float


@dataclass(frozen=True)
class Rows:
    """New full-resolution history rows (columns ``HISTORY_COLUMNS``), computed with ``gj_nm2``."""
    run_id: int
    rows: np.ndarray
    gj_nm2: float
    t_s: float


@dataclass(frozen=True)
class Applied:
    """A live change (GJ [N m²/rad], EA and CG [chord fractions]) took effect at ``t_s``."""
    run_id: int
    values: dict
    t_s: float


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
class ModeFrames:
    result: dict  #: app.compute.mode_frames


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


@dataclass(frozen=True)
class Modes:
    result: dict  #: app.compute.modes_result


@dataclass(frozen=True)
class Locus:
    result: dict  #: app.compute.locus_result


@dataclass(frozen=True)
class Fan:
    result: dict  #: app.compute.fan_data


@dataclass(frozen=True)
class Ladder:
    result: dict  #: app.compute.run_ladder


@dataclass(frozen=True)
class Sensitivity:
    """The boundaries' sensitivity to every estimate at one CG column
    (:meth:`amra_core.sensitivity.SensitivityResult.to_dict`)."""
    result: dict
