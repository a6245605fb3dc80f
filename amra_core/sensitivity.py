"""Sensitivity of the stability boundary to every estimated rotor value (issue 21 item 6).

Several rotor values are not measured but estimated (the preset files say which and why): blade
incidence, aircraft mass, hub teeter and polar inertias, torsional inertia, radius, chord,
structural damping and root cut-out. :func:`sensitivity` perturbs each by ``±step`` (relative,
10 % by default) and walks the same CG column again with the map's own column walk
(:func:`amra_core.column.walk_column`, no second solver), so a user sees which conclusions rest
on guesses: the change of the **fold GJ** (no steady autorotation below) and of the **flutter GJ**
(top of the highest unstable interval on the walk), and per boundary a **band**, the lowest and
highest value over the baseline and every perturbation.

How a perturbation is applied (everything else of the rotor kept):

* ``radius``: the tip radius; stations keep their relative place between the root cut-out and the
  tip (the blade is stretched, its mass and stiffness per length kept);
* ``root_cutout``: the root cut-out; stations likewise between the new root and the tip;
* ``chord``: every station's chord (the chordwise EA/CG/AC fractions kept, so the CG offset
  scales with it; the torsional inertia is its own estimate and is kept);
* ``torsional_inertia``: every station's torsional inertia per length;
* the scalar values (incidence, aircraft mass, hub inertias, structural damping) themselves.

A perturbation that makes the rotor invalid (e.g. a chord above a quarter of the radius) gives a
row with its message and no numbers. An estimate of zero has no relative perturbation (the row
says so).
"""
from __future__ import annotations

import dataclasses
import math
import threading
import time
from dataclasses import dataclass
from typing import Callable, Optional

from .column import ColumnWalk, walk_column
from .flight import FlightCondition, SolverSettings
from .rotor import Rotor, RotorError


@dataclass(frozen=True)
class Boundaries:
    """The two boundaries of one column [N m^2/rad]: ``fold_gj_nm2`` (the trim branch through
    the stiffest blade ends below it; None: no fold inside the GJ range) and ``flutter_gj_nm2``
    (top of the highest flutter interval; None: none in the range; inf: unstable at the top of
    the range)."""

    fold_gj_nm2: Optional[float]
    flutter_gj_nm2: Optional[float]

    def to_dict(self) -> dict:
        """JSON form: ``flutter_at_gj_max`` says that a null ``flutter_gj_nm2`` is infinite."""
        f = self.flutter_gj_nm2
        return {"fold_gj_nm2": self.fold_gj_nm2, "flutter_gj_nm2": f,
                "flutter_at_gj_max": f is not None and not math.isfinite(f)}


def column_boundaries(walk: ColumnWalk) -> Boundaries:
    """Fold GJ and strong-flutter GJ of a column walk, as the map defines them
    (:func:`amra_core.boundary.intervals.classify`: weak windows and the fold's own approach do not
    count). The strength follows the damping ratio alone here: the map's 20 s run per interval
    would cost 18 times per column. ``inf`` when a strong interval reaches the top of the range."""
    from .boundary.intervals import classify
    c = classify(walk.intervals, walk.gj_max_nm2)
    fold = c["fold_gj"] if c["fold_gj"] is not None else walk.fold_gj_nm2
    flutter = c["flutter_gj"]
    for iv in c["intervals"]:
        if (iv["kind"] == "flutter" and iv.get("strength") == "strong" and not iv.get("fold_approach")
                and iv["gj_hi_nm2"] >= walk.gj_max_nm2 * (1 - 1e-12)):
            flutter = math.inf
    return Boundaries(fold, flutter)


def _stretch(stations, old_r0, old_tip, new_r0, new_tip):
    scale = (new_tip - new_r0) / (old_tip - old_r0)
    r = tuple(new_r0 + (x - old_r0) * scale for x in stations.r_m)
    r = r[:-1] + (new_tip,)  # exactly at the tip (validation compares with 1e-9)
    return dataclasses.replace(stations, r_m=(new_r0,) + r[1:])


def _set_radius(rotor: Rotor, f: float) -> Rotor:
    R = rotor.radius_m * f
    pm = rotor.point_mass
    if pm is not None:
        pm = dataclasses.replace(pm, r_m=rotor.root_cutout_m + (pm.r_m - rotor.root_cutout_m)
                                 * (R - rotor.root_cutout_m) / rotor.blade_length_m)
    return dataclasses.replace(rotor, radius_m=R, point_mass=pm,
                               stations=_stretch(rotor.stations, rotor.root_cutout_m, rotor.radius_m,
                                                 rotor.root_cutout_m, R))


def _set_root_cutout(rotor: Rotor, f: float) -> Rotor:
    r0 = rotor.root_cutout_m * f
    pm = rotor.point_mass
    if pm is not None:
        pm = dataclasses.replace(pm, r_m=r0 + (pm.r_m - rotor.root_cutout_m) * (rotor.radius_m - r0)
                                 / rotor.blade_length_m)
    return dataclasses.replace(rotor, root_cutout_m=r0, point_mass=pm,
                               stations=_stretch(rotor.stations, rotor.root_cutout_m, rotor.radius_m, r0,
                                                 rotor.radius_m))


def _scale_stations(name: str):
    def apply(rotor: Rotor, f: float) -> Rotor:
        st = rotor.stations
        return dataclasses.replace(rotor, stations=dataclasses.replace(st, **{name: tuple(v * f for v in
                                                                                          getattr(st, name))}))
    return apply


def _scale_field(name: str):
    def apply(rotor: Rotor, f: float) -> Rotor:
        return dataclasses.replace(rotor, **{name: getattr(rotor, name) * f})
    return apply


@dataclass(frozen=True)
class Estimate:
    """One estimated rotor value: ``name`` (CLI/JSON key), ``label``, ``unit``, ``value(rotor)``
    (its nominal value in that unit, a span mean for station values) and ``apply(rotor, factor)``."""

    name: str
    label: str
    unit: str
    value: Callable
    apply: Callable


ESTIMATES = (
    Estimate("incidence", "blade incidence", "deg", lambda r: math.degrees(r.incidence_rad),
             _scale_field("incidence_rad")),
    Estimate("vehicle_mass", "aircraft mass", "kg", lambda r: r.vehicle_mass_kg, _scale_field("vehicle_mass_kg")),
    Estimate("hub_teeter_inertia", "hub teeter inertia", "kg m^2", lambda r: r.hub_teeter_inertia_kg_m2,
             _scale_field("hub_teeter_inertia_kg_m2")),
    Estimate("hub_polar_inertia", "hub polar inertia", "kg m^2", lambda r: r.hub_polar_inertia_kg_m2,
             _scale_field("hub_polar_inertia_kg_m2")),
    Estimate("torsional_inertia", "torsional inertia (span mean)", "kg m^2/m",
             lambda r: r.stations.mean("torsional_inertia_kg_m"), _scale_stations("torsional_inertia_kg_m")),
    Estimate("radius", "radius", "m", lambda r: r.radius_m, _set_radius),
    Estimate("chord", "chord (span mean)", "m", lambda r: r.stations.mean("chord_m"), _scale_stations("chord_m")),
    Estimate("structural_damping", "structural damping ratio", "-", lambda r: r.structural_damping_ratio,
             _scale_field("structural_damping_ratio")),
    Estimate("root_cutout", "root cut-out", "m", lambda r: r.root_cutout_m, _set_root_cutout),
)
ESTIMATE_NAMES = tuple(e.name for e in ESTIMATES)


@dataclass(frozen=True)
class SensitivityRow:
    """One perturbation: ``parameter`` (an :data:`ESTIMATE_NAMES` entry) changed by ``change``
    (relative, e.g. +0.1) from ``base_value`` to ``value`` [``unit``]; the column's boundaries
    [N m^2/rad] and their changes from the baseline (None where either is None or not finite);
    ``note``: why there are no numbers, if there are none."""

    parameter: str
    label: str
    unit: str
    change: float
    base_value: float
    value: float
    fold_gj_nm2: Optional[float]
    flutter_gj_nm2: Optional[float]
    d_fold_gj_nm2: Optional[float]
    d_flutter_gj_nm2: Optional[float]
    note: str = ""


@dataclass(frozen=True)
class SensitivityResult:
    """Result of :func:`sensitivity`: the case, the ``baseline`` boundaries, one row per
    perturbation, and per boundary the ``band`` (lowest, highest) over the baseline and every
    perturbation [N m^2/rad] (None entries, i.e. no boundary in the range, are left out; a
    band is None when no value is left)."""

    rotor: str
    fidelity: str
    rigid_spring: str
    aero: str
    mu: float
    airspeed_m_s: float
    ea: Optional[float]
    cg: float
    step: float
    gj_min_nm2: float
    gj_max_nm2: float
    rel_tol: float
    baseline: Boundaries
    rows: tuple
    fold_band_nm2: Optional[tuple]
    flutter_band_nm2: Optional[tuple]
    wall_time_s: float

    def to_dict(self) -> dict:
        d = {k: getattr(self, k) for k in ("rotor", "fidelity", "rigid_spring", "aero", "mu", "airspeed_m_s", "ea", "cg", "step",
                                            "gj_min_nm2", "gj_max_nm2", "rel_tol", "wall_time_s")}
        d["baseline"] = self.baseline.to_dict()
        d["fold_band_nm2"] = None if self.fold_band_nm2 is None else list(self.fold_band_nm2)
        d["flutter_band_nm2"] = None if self.flutter_band_nm2 is None else list(self.flutter_band_nm2)
        d["rows"] = [{**dataclasses.asdict(r), "flutter_at_gj_max": r.flutter_gj_nm2 is not None
                      and not math.isfinite(r.flutter_gj_nm2)} for r in self.rows]
        return d


def _delta(a, b):
    if a is None or b is None or not (math.isfinite(a) and math.isfinite(b)):
        return None
    return a - b


def _band(values):
    vals = [v for v in values if v is not None]
    return (min(vals), max(vals)) if vals else None


def _walk(args):
    """One column walk (module level: picklable for worker processes)."""
    rotor, flight, settings, cg, gj_min, gj_max, rel_tol, n_probe = args
    return column_boundaries(walk_column(rotor, flight, settings, cg, gj_min, gj_max, rel_tol=rel_tol,
                                         n_probe=n_probe))


def sensitivity(rotor: Rotor, cg: float, *, ea: Optional[float] = None, settings: SolverSettings = SolverSettings(),
                flight: FlightCondition = FlightCondition(), step: float = 0.10, parameters=None,
                gj_min_nm2: float = 30.0, gj_max_nm2: float = 3000.0, rel_tol: float = 0.02, n_probe: int = 7,
                workers: int = 1, progress: Optional[Callable[[int, int, str], None]] = None,
                cancel: Optional[threading.Event] = None) -> SensitivityResult:
    """The change of fold GJ and flutter GJ of CG column ``cg`` [chord fraction] when each estimate
    of ``parameters`` (default: all of :data:`ESTIMATE_NAMES`) changes by ``-step`` and ``+step``
    (relative). ``ea``: uniform elastic axis [chord fraction] (None: the rotor's own);
    ``settings``/``flight``: fidelity, aerodynamics and flight condition (``FlightCondition(mu=0.1)``
    for forward flight); ``gj_min_nm2``..``gj_max_nm2``, ``rel_tol``, ``n_probe``: the column
    walk's range, bracket tolerance and probe grid. ``workers`` > 1 walks the perturbed columns in
    that many processes. ``progress(done, total, what)`` is called as each walk ends.
    ``cancel``: a ``threading.Event`` checked between walks (raises ``RuntimeError`` when set)."""
    if not 0.0 < step < 0.5:
        raise ValueError(f"step = {step!r} is not allowed: a relative change in (0, 0.5)")
    names = ESTIMATE_NAMES if parameters is None else tuple(parameters)
    bad = [n for n in names if n not in ESTIMATE_NAMES]
    if bad or not names:
        raise ValueError(f"parameters = {list(names)!r} is not allowed: choose from {', '.join(ESTIMATE_NAMES)}")
    if not 0 < gj_min_nm2 < gj_max_nm2:
        raise ValueError(f"gj range {gj_min_nm2!r}..{gj_max_nm2!r} is not allowed: need 0 < gj_min < gj_max")
    t0 = time.perf_counter()
    base = rotor if ea is None else rotor.with_overrides(x_ea=ea)
    base.with_overrides(x_cg=cg)  # the column's section must be physical (message names the bound)
    by_name = {e.name: e for e in ESTIMATES}

    jobs, rows_meta, what = [], [], ["baseline"]
    for name in names:
        est = by_name[name]
        v0 = float(est.value(base))
        for sign in (-1.0, 1.0):
            f = 1.0 + sign * step
            meta = dict(parameter=name, label=est.label, unit=est.unit, change=sign * step, base_value=v0,
                        value=v0 * f)
            if v0 == 0.0:
                rows_meta.append((meta, None, "the estimate is 0: a relative change leaves it 0"))
                continue
            try:
                perturbed = est.apply(base, f).with_overrides(x_cg=cg)
            except RotorError as exc:
                rows_meta.append((meta, None, f"not a valid rotor: {exc}"))
                continue
            rows_meta.append((meta, len(jobs), ""))
            jobs.append((perturbed, flight, settings, cg, gj_min_nm2, gj_max_nm2, rel_tol, n_probe))
            what.append(f"{name} {sign * step:+.0%}")

    base_job = (base, flight, settings, cg, gj_min_nm2, gj_max_nm2, rel_tol, n_probe)
    results = {}

    def check_cancel():
        if cancel is not None and cancel.is_set():
            raise RuntimeError("sensitivity study cancelled")

    todo = [base_job] + jobs
    if workers > 1:
        from concurrent.futures import ProcessPoolExecutor

        from .blas_threads import use_one_blas_thread
        with ProcessPoolExecutor(max_workers=int(workers), initializer=use_one_blas_thread) as ex:
            futs = [ex.submit(_walk, j) for j in todo]
            for i, fu in enumerate(futs):
                check_cancel()
                results[i - 1] = fu.result()
                if progress is not None:
                    progress(i + 1, len(todo), what[i])
    else:
        for i, j in enumerate(todo):
            check_cancel()
            results[i - 1] = _walk(j)
            if progress is not None:
                progress(i + 1, len(todo), what[i])
    baseline = results[-1]

    rows = []
    for meta, job, note in rows_meta:
        if job is None:
            b = Boundaries(None, None) if note.startswith("not a valid") else baseline
            row = SensitivityRow(**meta, fold_gj_nm2=b.fold_gj_nm2, flutter_gj_nm2=b.flutter_gj_nm2,
                                 d_fold_gj_nm2=None if note.startswith("not a valid") else 0.0,
                                 d_flutter_gj_nm2=None if note.startswith("not a valid") else 0.0, note=note)
        else:
            b = results[job]
            row = SensitivityRow(**meta, fold_gj_nm2=b.fold_gj_nm2, flutter_gj_nm2=b.flutter_gj_nm2,
                                 d_fold_gj_nm2=_delta(b.fold_gj_nm2, baseline.fold_gj_nm2),
                                 d_flutter_gj_nm2=_delta(b.flutter_gj_nm2, baseline.flutter_gj_nm2))
        rows.append(row)
    valid = [r for r in rows if not r.note.startswith("not a valid")]
    return SensitivityResult(
        rotor=rotor.name, fidelity=settings.fidelity, rigid_spring=settings.rigid_spring, aero=settings.aero,
        mu=float(flight.mu or 0.0), airspeed_m_s=float(flight.airspeed_m_s), ea=None if ea is None else float(ea), cg=float(cg), step=float(step),
        gj_min_nm2=float(gj_min_nm2), gj_max_nm2=float(gj_max_nm2), rel_tol=float(rel_tol), baseline=baseline,
        rows=tuple(rows), fold_band_nm2=_band([baseline.fold_gj_nm2] + [r.fold_gj_nm2 for r in valid]),
        flutter_band_nm2=_band([baseline.flutter_gj_nm2] + [r.flutter_gj_nm2 for r in valid]),
        wall_time_s=time.perf_counter() - t0)
