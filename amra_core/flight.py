"""Flight condition and solver settings: frozen, validated, hashable (cases are keyed by them)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np

from .rotor import _check_number
from .shapes import FIDELITIES, TORSION_SPRINGS

AERO_MODELS = ("quasi-steady", "theodorsen")
INFLOW_MODELS = ("uniform", "three-state")
INTEGRATORS = ("lawson", "rk4")


class SettingsError(ValueError):
    """An out-of-range or malformed setting; the message names it and its allowed range."""


def _num(name, value, lo, hi):
    try:
        return _check_number(name, value, lo, hi)
    except ValueError as exc:
        raise SettingsError(str(exc)) from None


def _integer(obj, field: str, label: str, lo: int, hi: int) -> None:
    """Check an integer setting: a bool is not a number (``True`` is not 1 element); a NumPy
    integer is stored as a Python int so the case key does not depend on the type."""
    v = getattr(obj, field)
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not lo <= v <= hi:
        raise SettingsError(f"{label} = {v!r} is not allowed: must be an integer in [{lo}, {hi}]")
    object.__setattr__(obj, field, int(v))


@dataclass(frozen=True)
class FlightCondition:
    """Air and flight path.

    ``airspeed_m_s``: horizontal airspeed [m/s] (0 = axial autorotation), or ``mu``: the advance
    ratio of the trimmed state (``V cos(alpha_s) / (Omega R)``); give at most one.
    ``omega_hold_rad_s``: hold the rotor speed at this value [rad/s] (paper Table 1) instead of
    letting the torque balance set it.
    """

    airspeed_m_s: float = 0.0
    mu: Optional[float] = None
    omega_hold_rad_s: Optional[float] = None
    density_kg_m3: float = 1.225
    speed_of_sound_m_s: float = 340.3
    gravity_m_s2: float = 9.80665

    def __post_init__(self):
        _num("airspeed_m_s", self.airspeed_m_s, 0.0, 80.0)
        if self.mu is not None:
            _num("mu", self.mu, 0.0, 0.5)
            if self.airspeed_m_s:
                raise SettingsError("mu and airspeed are both given: give one")
        if self.omega_hold_rad_s is not None:
            _num("omega_hold_rad_s", self.omega_hold_rad_s, 1.0, 200.0)
        _num("density_kg_m3", self.density_kg_m3, 0.1, 2.0)
        _num("speed_of_sound_m_s", self.speed_of_sound_m_s, 200.0, 400.0)

    @property
    def is_axial(self) -> bool:
        return not self.airspeed_m_s and not self.mu


@dataclass(frozen=True)
class SolverSettings:
    """Model fidelity and numerics.

    ``fidelity``: ``rigid`` | ``fem-torsion`` | ``fem-coupled``; ``aero``: ``theodorsen`` (Wagner,
    two states per station; default) | ``quasi-steady`` (3/4-chord angle and pitch-rate terms);
    ``inflow``: ``uniform`` (Pitt-Peters uniform inflow with the turbulent-wake curve; default) |
    ``three-state`` (adds Peters-HaQuang first-harmonic sine and cosine inflow states);
    ``n_elements``: FEM elements per blade; ``n_stations``: aerodynamic (Gauss) stations per blade;
    ``dt_s``: time step [s] (``None``: chosen from the stiffest mode, see :mod:`amra_core.model`);
    ``max_mode_hz``: FEM levels keep the structural modes below this frequency [Hz] at the
    reference rotor speed (Ritz reduction; ``None`` keeps every FEM coordinate);
    ``rigid_spring``: the ``rigid`` level's root torsion spring, ``frequency`` (``(pi/2)^2 GJ/L``,
    the first torsion frequency of the uniform cantilever; default) | ``static`` (the same
    load-weighted static twist under an ``r^2`` moment, about 1.6 x softer), see
    :mod:`amra_core.rigid_equivalence`; the FEM levels ignore it;
    ``integrator``: ``lawson`` (default: the FEM levels' modal oscillators integrated exactly, and in
    axial flight the Wagner states' decay at every level, RK4 for the rest, so the step follows the
    physics, not the stiffest retained mode; see :func:`amra_core.kernels.advance`) | ``rk4``
    (plain RK4).
    """

    fidelity: str = "rigid"
    aero: str = "theodorsen"
    inflow: str = "uniform"
    n_elements: int = 10
    n_stations: int = 12
    dt_s: Optional[float] = None
    max_mode_hz: Optional[float] = 200.0
    rigid_spring: str = "frequency"
    integrator: str = "lawson"

    def __post_init__(self):
        if self.fidelity not in FIDELITIES:
            raise SettingsError(f"fidelity = {self.fidelity!r} is not allowed: choose one of {', '.join(FIDELITIES)}")
        if self.aero not in AERO_MODELS:
            raise SettingsError(f"aero = {self.aero!r} is not allowed: choose one of {', '.join(AERO_MODELS)}")
        if self.inflow not in INFLOW_MODELS:
            raise SettingsError(f"inflow = {self.inflow!r} is not allowed: choose one of {', '.join(INFLOW_MODELS)}")
        if self.rigid_spring not in TORSION_SPRINGS:
            raise SettingsError(f"rigid_spring = {self.rigid_spring!r} is not allowed: choose one of "
                                f"{', '.join(TORSION_SPRINGS)}")
        if self.integrator not in INTEGRATORS:
            raise SettingsError(f"integrator = {self.integrator!r} is not allowed: choose one of {', '.join(INTEGRATORS)}")
        _integer(self, "n_elements", "elements", 1, 60)
        _integer(self, "n_stations", "stations", 4, 60)
        if self.dt_s is not None:
            _num("dt_s", self.dt_s, 1e-6, 0.01)
        if self.max_mode_hz is not None:
            _num("max_mode_hz", self.max_mode_hz, 50.0, 1e5)
