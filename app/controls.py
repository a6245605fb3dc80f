"""The case the user is exploring: the single source of truth for every control of a session.

One :class:`Controls` per session. ``doc=`` strings (with units) become the widgets' tooltips;
bounds are enforced by param, so a value from a widget, a preset or the URL is validated the same
way. Run, Stop, Reset and the fidelity ladder are ``param.Event``s (the buttons are views of them).
GJ is one parameter, shown twice: a log-scale slider (:func:`gj_slider`) and the exact input.
:meth:`Controls.case` builds the frozen :class:`amra_core.simulation.Case`; the core's own
validation (``SettingsError``, ``RotorError``) then names anything the bounds cannot express.
"""
from __future__ import annotations

import math

import panel as pn
import param
from bokeh.models import CustomJSTickFormatter

from amra_core.flight import AERO_MODELS, INFLOW_MODELS, FlightCondition, SolverSettings
from amra_core.paper_cases import NOMINAL_GJ_NM2
from amra_core.scenario import LiveChange, Scenario
from amra_core.rotor import Rotor
from amra_core.rotor_io import load_preset, preset_names
from amra_core.shapes import FIDELITIES
from amra_core.simulation import Case

from .presets import PRESETS

UPLOADED = "uploaded file"
LIVE_PARAMETERS = ("gj_nm2", "ea_pct", "cg_pct")  #: changed mid-run without restarting
GJ_BOUNDS = (10.0, 10000.0)


class Controls(param.Parameterized):
    """Every value that determines a run, a stability analysis and a boundary map."""

    # -- the case
    preset = param.Selector(objects=list(PRESETS), default="custom", label="Preset",
                            doc="A paper case (Figs 10-13, Table 1) or the nominal blade; sets the controls below.")
    rotor = param.Selector(objects=[*preset_names(), UPLOADED], default="paper-boundary", label="Rotor",
                           doc="Shipped rotor description, or the rotor file you uploaded.")
    gj_nm2 = param.Number(1500.0, bounds=GJ_BOUNDS, label="GJ [N m²/rad]",
                          doc="Torsional stiffness GJ, uniform along the span [N m²/rad]. Applied live during a run.")
    ea_pct = param.Number(32.0, bounds=(10.0, 60.0), step=0.5, label="EA [% chord]",
                          doc="Elastic axis, chordwise position from the leading edge [% chord]. Applied live.")
    cg_pct = param.Number(40.0, bounds=(10.0, 70.0), step=0.5, label="CG [% chord]",
                          doc="Sectional centre of gravity, chordwise from the leading edge [% chord]. Applied live.")
    mu = param.Number(0.0, bounds=(0.0, 0.5), step=0.01, label="Advance ratio μ [-]",
                      doc="Advance ratio μ = V cos(α) / (Ω R) of the trim [-]; 0 = axial (vertical) descent.")
    airspeed_m_s = param.Number(0.0, bounds=(0.0, 80.0), step=0.5, label="Airspeed [m/s] (0: use μ)",
                                doc="Horizontal airspeed [m/s]; 0 means the advance ratio μ sets the flight.")
    omega_hold_rad_s = param.Number(0.0, bounds=(0.0, 200.0), step=0.5, label="Held rotor speed [rad/s] (0: free)",
                                    doc="Hold the rotor speed at this value [rad/s] (paper Table 1); 0 lets the "
                                        "torque balance set it.")
    fidelity = param.Selector(objects=list(FIDELITIES), default="rigid", label="Fidelity",
                              doc="Blade model: rigid (torsion spring), fem-torsion or fem-coupled (flap-torsion FEM).")
    aero = param.Selector(objects=list(AERO_MODELS), default="theodorsen", label="Aerodynamics",
                          doc="Unsteady Theodorsen/Wagner lift, or quasi-steady.")
    inflow = param.Selector(objects=list(INFLOW_MODELS), default="uniform", label="Inflow",
                            doc="Uniform Pitt-Peters inflow, or with first-harmonic (three-state) inflow.")
    # -- the run
    run_s = param.Number(10.0, bounds=(0.5, 120.0), step=0.5, label="Run length [s]",
                         doc="Simulated time of a run [s] (capped by the server's AMRA_MAX_RUN_S).")
    soften_at_s = param.Number(0.0, bounds=(0.0, 600.0), step=0.5, label="Soften at [s] (0: from the start)",
                               doc=f"When above 0, the run starts from the nominal blade (GJ {NOMINAL_GJ_NM2:g} N m²/rad) "
                                   "in steady autorotation and the GJ above is applied at this time [s], as a live "
                                   "change (the paper's Figs 10-13 are told this way). Must be shorter than the run.")
    speed = param.Number(1.0, bounds=(0.1, 50.0), step=0.1, label="Playback [sim s per s]",
                         doc="Playback speed [simulated s per wall-clock s] while streaming (the solver is faster).")
    # -- the map
    map_columns = param.Integer(9, bounds=(2, 31), label="Map CG columns",
                                doc="Number of CG columns of the boundary map (20-50 % chord).")
    map_coarse = param.Integer(7, bounds=(3, 20), label="Map coarse GJ values",
                               doc="GJ values of the map's coarse grid (30-3000 N m²/rad, log spaced) before bisection.")

    # -- the page
    present = param.Boolean(False, label="Presentation mode",
                            doc="For a projector: Run, Stop and a large GJ input in the header, larger fonts, live "
                                "plots that fill a 1280x720 screen, the sidebar collapsed (link flag present=true).")

    # -- actions
    run = param.Event(label="▶ Run", doc="Start a run of the current case (replaces this session's run).")
    stop = param.Event(label="■ Stop", doc="Stop the run; the plots and verdict stay.")
    reset = param.Event(label="↺ Reset", doc="Stop the run and clear the plots, verdict and messages.")
    ladder = param.Event(label="Run fidelity ladder", doc="Run the case at the three fidelities side by side.")

    def __init__(self, max_run_s: float = 120.0, **params):
        super().__init__(**params)
        self.param.run_s.bounds = (0.5, float(max_run_s))
        if self.run_s > max_run_s:
            self.run_s = float(max_run_s)
        self._applying_preset = False
        if params.get("preset", "custom") != "custom":  # watchers do not fire on construction
            self._apply_preset()
            explicit = {k: v for k, v in params.items() if k != "preset"}
            with param.parameterized.discard_events(self):
                self.param.update(**explicit)

    @param.depends("preset", watch=True)
    def _apply_preset(self):
        values = PRESETS[self.preset].as_dict()
        if "run_s" in values:
            values["run_s"] = min(values["run_s"], self.param.run_s.bounds[1])
        if values:
            self._applying_preset = True
            try:
                self.param.update(**values)
            finally:
                self._applying_preset = False

    @param.depends(*[p for p in ("rotor", "gj_nm2", "ea_pct", "cg_pct", "mu", "airspeed_m_s", "omega_hold_rad_s",
                                 "fidelity", "aero", "inflow", "soften_at_s")], watch=True)
    def _left_preset(self):
        if not self._applying_preset and self.preset != "custom":
            values = PRESETS[self.preset].as_dict()
            if any(getattr(self, k) != v for k, v in values.items() if k in self.param):
                with param.parameterized.discard_events(self):
                    self.preset = "custom"

    # -- mapping to the solver
    def base_rotor(self, uploaded: Rotor | None = None) -> Rotor:
        if self.rotor == UPLOADED:
            if uploaded is None:
                raise ValueError("rotor = 'uploaded file' is not allowed: no rotor file has been uploaded "
                                 "(choose a shipped rotor or upload a TOML file)")
            return uploaded
        return load_preset(self.rotor)

    def rotor_obj(self, uploaded: Rotor | None = None) -> Rotor:
        return self.base_rotor(uploaded).with_overrides(gj_nm2=self.gj_nm2, x_ea=self.ea_pct / 100.0,
                                                        x_cg=self.cg_pct / 100.0)

    def flight(self) -> FlightCondition:
        hold = self.omega_hold_rad_s or None
        if self.airspeed_m_s > 0:
            return FlightCondition(airspeed_m_s=self.airspeed_m_s, omega_hold_rad_s=hold)
        return FlightCondition(mu=self.mu or None, omega_hold_rad_s=hold)

    def settings(self, fidelity: str | None = None) -> SolverSettings:
        return SolverSettings(fidelity=fidelity or self.fidelity, aero=self.aero, inflow=self.inflow)

    def case(self, uploaded: Rotor | None = None, fidelity: str | None = None) -> Case:
        """The solver case for the current values (raises ValueError naming a bad value)."""
        return Case(self.rotor_obj(uploaded), self.flight(), self.settings(fidelity), t_end_s=float(self.run_s))

    def scenario(self, uploaded: Rotor | None = None) -> Scenario:
        """The run to start: the case, and with ``soften_at_s`` the nominal blade softened to GJ then."""
        case = self.case(uploaded)
        if not self.soften_at_s:
            return Scenario(case)
        if not self.soften_at_s < self.run_s:
            raise ValueError(f"soften at = {self.soften_at_s:g} s is not allowed: must be shorter than the run "
                             f"length ({self.run_s:g} s), or 0 for no softening")
        stiff = Case(case.rotor.with_overrides(gj_nm2=NOMINAL_GJ_NM2), case.flight, case.settings, case.t_end_s)
        return Scenario(stiff, (LiveChange(float(self.soften_at_s), gj_nm2=float(self.gj_nm2)),))

    def live_values(self) -> dict:
        """The mid-run changeable values in the units of ``Simulation.set_parameters``."""
        return {"gj_nm2": float(self.gj_nm2), "x_ea": self.ea_pct / 100.0, "x_cg": self.cg_pct / 100.0}

    def values(self) -> dict:
        return {k: getattr(self, k) for k in self.param if k not in ("name", "run", "stop", "reset", "ladder")}


def gj_slider(controls: Controls) -> pn.widgets.FloatSlider:
    """GJ on a log10 scale, labelled in N m²/rad. A release sets ``controls.gj_nm2``; a change of
    ``gj_nm2`` from anywhere moves the handle. No echo: a handle moved from the server changes
    ``value`` only, and only the browser's release changes ``value_throttled``."""
    lo, hi = (math.log10(b) for b in GJ_BOUNDS)
    s = pn.widgets.FloatSlider(name="GJ (log scale) [N m²/rad]", start=lo, end=hi, step=0.005,
                               value=math.log10(controls.gj_nm2), sizing_mode="stretch_width",
                               format=CustomJSTickFormatter(code="return (10 ** tick).toPrecision(3)"),
                               css_classes=["amra-gj-slider"])

    def released(event):
        controls.gj_nm2 = min(max(float(f"{10 ** event.new:.4g}"), GJ_BOUNDS[0]), GJ_BOUNDS[1])
    s.param.watch(released, "value_throttled")
    controls.param.watch(lambda e: setattr(s, "value", math.log10(e.new)), "gj_nm2")
    return s
