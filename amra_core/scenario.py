"""Scripted runs: a case plus live parameter changes at stated times.

A :class:`Scenario` is what a teacher does with the sliders, written down: start from the steady
autorotation of one blade, then at ``t_s`` change GJ (or EA, CG) as a live change does
(:meth:`amra_core.simulation.Simulation.set_parameters`), and watch what follows. The paper's
Figs 10-13 are told this way (:mod:`amra_core.paper_cases`): in this model no steady autorotation
exists at the figures' GJ, so a run *at* that GJ can only start from the end of the trim branch;
softening the nominal blade mid-run shows the instability and the rotor-speed decay unfold instead.

:func:`run_scenario` marches a scenario to its end (the CLI); a streaming consumer (the dashboard)
steps the :class:`~amra_core.simulation.Simulation` itself and asks :meth:`Scenario.due` which
changes fall inside each chunk, so both apply the same changes at the same times.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Optional

from .flight import SettingsError
from .simulation import T_END_MAX_S, Case, Simulation, TERMINAL_STATUSES


@dataclass(frozen=True)
class LiveChange:
    """At ``t_s`` [s] of simulated time, set the blade's uniform GJ ``gj_nm2`` [N m^2/rad] and/or
    its EA ``x_ea`` and CG ``x_cg`` [fractions of chord from the leading edge]."""

    t_s: float
    gj_nm2: Optional[float] = None
    x_ea: Optional[float] = None
    x_cg: Optional[float] = None

    def __post_init__(self):
        t = self.t_s
        if isinstance(t, bool) or not isinstance(t, (int, float)) or not math.isfinite(t) or not 0 < t < T_END_MAX_S:
            raise SettingsError(f"change time t_s = {t!r} is not allowed: must be a number of seconds in "
                                f"(0, {T_END_MAX_S:g})")
        if self.gj_nm2 is None and self.x_ea is None and self.x_cg is None:
            raise SettingsError("a live change needs at least one of gj_nm2, x_ea, x_cg")

    def describe(self) -> str:
        parts = [f"GJ {self.gj_nm2:.4g} N m²/rad"] if self.gj_nm2 is not None else []
        parts += [f"{n} {100 * v:.1f} % chord" for n, v in (("EA", self.x_ea), ("CG", self.x_cg)) if v is not None]
        return f"at t = {self.t_s:g} s: {', '.join(parts)}"


#: two times [s] closer than this are one instant (times summed over chunks differ in the last bits)
TIME_TOLERANCE_S = 1e-9


@dataclass(frozen=True)
class Scenario:
    """A :class:`~amra_core.simulation.Case` (the starting blade, flight and run length
    ``case.t_end_s`` [s]) and the live changes applied during the run, in time order, each before
    the run's end."""

    case: Case
    changes: tuple = ()

    def __post_init__(self):
        if not isinstance(self.case, Case):
            raise SettingsError(f"case = {self.case!r} is not allowed: must be a Case")
        if not isinstance(self.changes, tuple) or not all(isinstance(c, LiveChange) for c in self.changes):
            raise SettingsError("changes must be a tuple of LiveChange")
        times = [c.t_s for c in self.changes]
        if times != sorted(times) or len(set(times)) != len(times):
            raise SettingsError(f"change times {times} are not allowed: must be distinct and in increasing order")
        if times and times[-1] >= self.case.t_end_s:
            raise SettingsError(f"change time {times[-1]:g} s is not allowed: must come before the run's end "
                                f"({self.case.t_end_s:g} s)")

    def due(self, t_from_s: float, t_to_s: float) -> tuple:
        """The changes with ``t_from_s < t_s <= t_to_s``: those a chunk ending at ``t_to_s`` crossed.
        Both ends are read within :data:`TIME_TOLERANCE_S`, so the chunk that ends on a change (at
        1.9999999999999998 s for 2 s, times summed over chunks) applies it and the next chunk, which
        starts there, does not apply it again (Fig. 12 at playback 10x was softened at 2.0 and again
        at 2.6 s, and its verdict was judged from 2.6 s)."""
        return tuple(c for c in self.changes if t_from_s + TIME_TOLERANCE_S < c.t_s <= t_to_s + TIME_TOLERANCE_S)

    def next_change_s(self, t_s: float) -> Optional[float]:
        """Time [s] of the first change after ``t_s``, or None."""
        return next((c.t_s for c in self.changes if c.t_s > t_s + TIME_TOLERANCE_S), None)


def apply_change(sim: Simulation, change: LiveChange) -> None:
    """Apply one scripted change to a running simulation, exactly as a live slider change does."""
    sim.set_parameters(gj_nm2=change.gj_nm2, x_ea=change.x_ea, x_cg=change.x_cg)


def run_scenario(scenario: Scenario, chunk_s: float = 0.5,
                 progress: Optional[Callable[[float, float], None]] = None) -> Simulation:
    """March ``scenario`` from its case's trim to ``case.t_end_s``, applying each change when the
    run reaches its time (chunks end exactly there). A run that ends early (rotor stopped, numerical
    failure) skips the changes it did not reach."""
    sim = Simulation(scenario.case)
    t_end = scenario.case.t_end_s
    for change in scenario.changes:
        sim.run(t_end_s=change.t_s, chunk_s=chunk_s, progress=progress and (lambda t, _: progress(t, t_end)))
        if sim.status in TERMINAL_STATUSES:
            return sim
        apply_change(sim, change)
    sim.run(t_end_s=t_end, chunk_s=chunk_s, progress=progress)
    return sim
