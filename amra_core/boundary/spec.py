"""What a boundary map computes (:class:`MapSpec`), its validation and its case keys.

A case key is the sha256 of every parameter that determines a cell plus the solver fingerprint
(the package version and the content of the solver sources), so a result store never serves a
cell computed by another solver.
"""
from __future__ import annotations

import functools
import hashlib
import json
import math
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Union

import numpy as np

from .. import __version__
from ..flight import AERO_MODELS, FlightCondition, SolverSettings
from ..rotor import Rotor
from ..shapes import FIDELITIES, TORSION_SPRINGS
from ..verdict import VERDICTS as RUN_VERDICTS
from .intervals import WEAK_AMPLITUDE_DEG, WEAK_DAMPING

#: a map cell's verdict: a run's verdict word (one vocabulary, :data:`amra_core.verdict.VERDICTS`), or
#: ``failed`` (a numerical failure or a crashed worker: no physics verdict)
VERDICTS = tuple(v for v in RUN_VERDICTS if v not in ("numerical-failure", "undetermined")) + ("undetermined", "failed")
METHODS = ("eigen", "time")
DEFAULT_CG = tuple(round(float(x), 6) for x in np.linspace(0.20, 0.50, 16))

#: solver sources whose content enters the case key (with ``__version__``), so stored cells are
#: never served for a changed solver
_SOLVER_SOURCES = ("airfoil", "airfoil_kernel", "atan2_kernel", "blade_symmetry", "column", "continuation",
                   "equilibrium", "flight", "floquet", "jit", "kernel_guard", "kernels", "layout", "model", "periodic_trim",
                   "rigid_equivalence", "rotor", "shapes", "shooting", "simulation", "sincos_kernel", "stability",
                   "structure", "trim", "trim_kernels", "verdict",
                   "boundary/intervals", "boundary/tasks", "boundary/result")
#: modules a map computation imports that do not change its answers (orchestration, keys, pools)
ORCHESTRATION_SOURCES = ("boundary", "boundary/runner", "boundary/spec", "executor")


class MapSpecError(ValueError):
    """A map parameter is out of range; the message names it and the allowed range."""


@functools.lru_cache(maxsize=1)
def solver_fingerprint() -> str:
    """``<version>+<sha256 of the solver sources, 12 hex>``: part of every case key."""
    h = hashlib.sha256()
    here = Path(__file__).resolve().parents[1]
    for name in _SOLVER_SOURCES:
        p = here / f"{name}.py"
        if p.is_file():
            h.update(name.encode())
            h.update(p.read_bytes())
    return f"{__version__}+{h.hexdigest()[:12]}"


def _gj_round(x: float) -> float:
    """GJ values to 10 significant digits, so keys do not depend on the last bit of a log grid."""
    return float(f"{x:.10g}")


def _num(name, v, lo, hi, lo_open=False):
    if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) or not math.isfinite(v):
        raise MapSpecError(f"{name} = {v!r} is not allowed: must be a finite number in "
                           f"{'(' if lo_open else '['}{lo}, {hi}]")
    if v < lo or v > hi or (lo_open and v == lo):
        raise MapSpecError(f"{name} = {v!r} is out of range: allowed {'(' if lo_open else '['}{lo}, {hi}]")
    return float(v)


@dataclass(frozen=True)
class MapSpec:
    """What to map.

    ``rotor``: a preset name (``paper-boundary``, ``mccutcheon``) or a :class:`Rotor`;
    ``fidelity``: ``rigid`` | ``fem-torsion`` | ``fem-coupled``; ``aero``: ``theodorsen`` |
    ``quasi-steady``; ``mu``: advance ratio [-] (0 = axial autorotation, eigenvalues; > 0 forward
    flight, Floquet); ``ea``: elastic axis [chord fraction]; ``cg_values``: CG columns [chord
    fraction], default 16 from 0.20 to 0.50; ``gj_min``, ``gj_max``: GJ range [N m^2/rad] (log
    scale); ``gj_rel_tol``: bracket width ``gj_hi/gj_lo - 1`` at which bisection stops [-];
    ``n_coarse``: GJ values of the log grid on which a column is probed by cold starts below a fold
    (and the largest walk step is at most its spacing); ``method``: ``eigen`` (linearised about trim)
    or ``time`` (the walk's points judged by time marching from their trim plus a perturbation);
    ``n_elements``: FEM elements per blade; ``weak_damping``: a flutter interval whose most unstable
    oscillating mode has a damping ratio above ``-weak_damping`` is weak (reported, never the
    critical GJ) [-], if also its run stays within ``weak_amplitude_deg`` of twist and teeter [deg]
    (:mod:`amra_core.boundary.intervals` says why 0.02 and 1 deg).
    """

    rotor: Union[str, Rotor] = "paper-boundary"
    fidelity: str = "rigid"
    aero: str = "theodorsen"
    mu: float = 0.0
    ea: float = 0.32
    cg_values: tuple = DEFAULT_CG
    gj_min: float = 30.0
    gj_max: float = 3000.0
    gj_rel_tol: float = 0.02
    n_coarse: int = 7
    method: str = "eigen"
    n_elements: int = 10
    weak_damping: float = WEAK_DAMPING
    weak_amplitude_deg: float = WEAK_AMPLITUDE_DEG
    rigid_spring: str = "frequency"  #: the rigid level's root torsion spring (SolverSettings.rigid_spring)

    def __post_init__(self):
        if not isinstance(self.rotor, (str, Rotor)):
            raise MapSpecError(f"rotor = {self.rotor!r} is not allowed: give a preset name or a Rotor")
        if self.fidelity not in FIDELITIES:
            raise MapSpecError(f"fidelity = {self.fidelity!r} is not allowed: choose one of {', '.join(FIDELITIES)}")
        if self.aero not in AERO_MODELS:
            raise MapSpecError(f"aero = {self.aero!r} is not allowed: choose one of {', '.join(AERO_MODELS)}")
        if self.method not in METHODS:
            raise MapSpecError(f"method = {self.method!r} is not allowed: choose one of {', '.join(METHODS)}")
        if self.rigid_spring not in TORSION_SPRINGS:
            raise MapSpecError(f"rigid_spring = {self.rigid_spring!r} is not allowed: choose one of "
                               f"{', '.join(TORSION_SPRINGS)}")
        _num("mu", self.mu, 0.0, 0.5)
        _num("ea", self.ea, 0.0, 1.0)
        cgs = tuple(self.cg_values) if not isinstance(self.cg_values, (str, bytes)) else None
        if not cgs:
            raise MapSpecError(f"cg_values = {self.cg_values!r} is not allowed: give at least one CG in [0, 1]")
        cgs = tuple(round(_num("cg", c, 0.0, 1.0), 6) for c in cgs)
        if len(set(cgs)) != len(cgs):
            raise MapSpecError(f"cg_values = {cgs!r} is not allowed: the CG values must be distinct")
        object.__setattr__(self, "cg_values", tuple(sorted(cgs)))
        _num("gj_min", self.gj_min, 1.0, 1e6)
        _num("gj_max", self.gj_max, 1.0, 1e6)
        if not self.gj_max > self.gj_min:
            raise MapSpecError(f"gj_max = {self.gj_max!r} is not allowed: must exceed gj_min = {self.gj_min!r}")
        _num("gj_rel_tol", self.gj_rel_tol, 1e-4, 1.0)
        if isinstance(self.n_coarse, bool) or not isinstance(self.n_coarse, int) or not 2 <= self.n_coarse <= 200:
            raise MapSpecError(f"n_coarse = {self.n_coarse!r} is not allowed: must be an integer in [2, 200]")
        _num("weak_damping", self.weak_damping, 0.0, 1.0)
        _num("weak_amplitude_deg", self.weak_amplitude_deg, 0.0, 90.0)
        if isinstance(self.n_elements, bool) or not isinstance(self.n_elements, int) or not 1 <= self.n_elements <= 60:
            raise MapSpecError(f"n_elements = {self.n_elements!r} is not allowed: must be an integer in [1, 60]")

    # -------------------------------------------------------------- derived objects
    @functools.cached_property
    def base_rotor(self) -> Rotor:
        """The rotor with the map's uniform EA (CG and GJ are set per cell)."""
        from ..rotor_io import load_preset
        r = load_preset(self.rotor) if isinstance(self.rotor, str) else self.rotor
        return r.with_overrides(x_ea=self.ea, x_cg=self.cg_values[0])  # a valid section; cells set their CG

    @property
    def flight(self) -> FlightCondition:
        return FlightCondition(mu=self.mu) if self.mu > 0 else FlightCondition()

    @property
    def settings(self) -> SolverSettings:
        return SolverSettings(fidelity=self.fidelity, aero=self.aero, n_elements=self.n_elements,
                              rigid_spring=self.rigid_spring)

    @property
    def coarse_gj(self) -> tuple:
        return tuple(_gj_round(g) for g in np.geomspace(self.gj_min, self.gj_max, self.n_coarse))

    def rotor_name(self) -> str:
        return self.rotor if isinstance(self.rotor, str) else self.rotor.name

    def grid_meta(self) -> dict:
        """The map's case for a file header, apart from EA and the CG columns (whose unit each export
        chooses): rotor, fidelity, aerodynamics, mu, the GJ grid [N m^2/rad], method, elements."""
        return {"rotor": self.rotor_name(), "fidelity": self.fidelity, "aero": self.aero, "mu": self.mu,
                "gj_range_nm2": f"{self.gj_min:g} to {self.gj_max:g}", "gj_tolerance": self.gj_rel_tol,
                "coarse_gj_values": self.n_coarse, "method": self.method, "fem_elements": self.n_elements}

    def to_dict(self) -> dict:
        d = {k: getattr(self, k) for k in self.__dataclass_fields__ if k != "rotor"}
        d["rotor"] = self.rotor_name()
        d["cg_values"] = list(self.cg_values)
        return d

    # -------------------------------------------------------------- cases
    def case_params(self, cg: float, gj: float) -> dict:
        """Every parameter that determines cell (cg, gj), plus the solver fingerprint."""
        rot = self.base_rotor.with_overrides(gj_nm2=gj, x_cg=cg).to_dict()
        rot.pop("sources", None)
        return {"kind": "map-cell", "rotor": rot, "flight": asdict(self.flight), "settings": asdict(self.settings),
                "method": self.method, "cg": cg, "gj_nm2": gj, "solver": solver_fingerprint()}

    def key(self, cg: float, gj: float) -> str:
        """Case key of cell (cg, gj): sha256 of :meth:`case_params` (24 hex)."""
        blob = json.dumps(self.case_params(cg, gj), sort_keys=True, default=float)
        return hashlib.sha256(blob.encode()).hexdigest()[:24]

    def column_params(self, cg: float) -> dict:
        """Every parameter that determines the walk of column ``cg`` (a stored column record)."""
        rot = self.base_rotor.with_overrides(x_cg=cg).to_dict()
        rot.pop("sources", None)
        return {"kind": "map-column", "rotor": rot, "flight": asdict(self.flight), "settings": asdict(self.settings),
                "method": self.method, "cg": cg, "gj_min": self.gj_min, "gj_max": self.gj_max,
                "gj_rel_tol": self.gj_rel_tol, "n_coarse": self.n_coarse, "solver": solver_fingerprint()}

    def column_key(self, cg: float) -> str:
        blob = json.dumps(self.column_params(cg), sort_keys=True, default=float)
        return "col-" + hashlib.sha256(blob.encode()).hexdigest()[:24]

    @property
    def max_step(self) -> float:
        """Largest GJ ratio of one walk step: the column walk's default, or the probe grid spacing."""
        from ..column import MAX_STEP
        return min(MAX_STEP, (self.gj_max / self.gj_min) ** (1.0 / (self.n_coarse - 1)))

    def column_task(self, cg: float) -> "ColumnTask":
        from .tasks import ColumnTask
        return ColumnTask(cg, self.base_rotor, self.flight, self.settings, self.method, self.gj_min, self.gj_max,
                          self.gj_rel_tol, self.n_coarse, self.max_step)
