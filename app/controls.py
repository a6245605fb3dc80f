"""The case the user is exploring: the single source of truth for every control of a session, and
the ways values reach it besides its widgets (classroom presets, a shared link, a rotor file).

One :class:`Controls` per session. ``doc=`` strings (with units) become the widgets' tooltips;
bounds are enforced by param, so a value from a widget, a preset or the URL is validated the same
way. Run, Stop, Reset and the fidelity ladder are ``param.Event``s (the buttons are views of them).
:meth:`Controls.case` builds the frozen :class:`amra_core.simulation.Case`; the core's own
validation (``SettingsError``, ``RotorError``) then names anything the bounds cannot express.
"""
from __future__ import annotations

import json
import math
import urllib.parse
from dataclasses import dataclass
from types import MappingProxyType
from typing import Optional

import param

from amra_core.flight import AERO_MODELS, INFLOW_MODELS, FlightCondition, SolverSettings
from amra_core.paper_cases import NOMINAL_GJ_NM2, PAPER_CASES
from amra_core.rotor import Rotor, RotorError
from amra_core.rotor_io import decode_rotor_bytes, load_preset, preset_names, rotor_from_toml
from amra_core.scenario import LiveChange, Scenario
from amra_core.shapes import FIDELITIES
from amra_core.simulation import Case

UPLOADED = "uploaded file"
LIVE_PARAMETERS = ("gj_nm2", "ea_pct", "cg_pct")  #: changed mid-run without restarting
#: each live control's key in :meth:`Controls.live_values` (the units of Simulation.set_parameters)
LIVE_VALUE_OF = {"gj_nm2": "gj_nm2", "ea_pct": "x_ea", "cg_pct": "x_cg"}
GJ_BOUNDS = (10.0, 10000.0)


# ---------------------------------------------------------------------------------------- presets
@dataclass(frozen=True)
class Preset:
    """A classroom preset: control values and the card text shown under the selector."""
    label: str
    explanation: str
    values: tuple  #: ((control name, value), ...)
    #: Table 1: (measured teeter amplitude [rad], the original AMRA's [rad]) to show beside the run's
    teeter_reference_rad: tuple | None = None

    def as_dict(self) -> dict:
        return dict(self.values)


_BASE = (("airspeed_m_s", 0.0), ("omega_hold_rad_s", 0.0), ("aero", "theodorsen"), ("inflow", "uniform"),
         ("soften_at_s", 0.0))


def _p(label, explanation, teeter_reference_rad=None, **values):
    return Preset(label, explanation, tuple((dict(_BASE) | values).items()), teeter_reference_rad)


def _paper(key: str) -> Preset:
    """Figs 10-13 tell the paper's story (:mod:`amra_core.paper_cases`): the paper-boundary blade
    starts in steady autorotation at its nominal GJ and is softened to the figure's GJ at t = 2 s."""
    pc = PAPER_CASES[key]
    text = f"**The paper:** {pc.paper_reports}.\n\n**This model:** {pc.model_gives}"
    return _p(pc.label, text, rotor="paper-boundary", gj_nm2=pc.gj_nm2, ea_pct=32.0, cg_pct=40.0, mu=pc.mu,
              fidelity=pc.fidelity, run_s=pc.run_s, soften_at_s=pc.soften_at_s)


#: run length of the Table 1 presets [s]: a stable verdict needs 4.8 s of fit in the run's last two
#: thirds (:data:`amra_core.verdict.STABLE_MIN_FIT_S`), so a 5 s run ended "undetermined"
TABLE1_RUN_S = 8.0


def _table1(case: str, speed_m_s: float, omega: float, measured: float, amra: float) -> Preset:
    """Table 1 holds the rotor speed at the measured mean in level flight and compares the teeter
    amplitude with the flight measurement and the original AMRA."""
    text = (f"Paper Table 1 case {case}: McCutcheon rotor (GJ, EA, CG at their span means), rotor speed held "
            f"at {omega:g} rad/s, level flight at {speed_m_s:g} m/s. **Teeter amplitude:** measured in flight "
            f"{measured:g} rad, original AMRA {amra:g} rad; this model's is shown when the run ends. With the "
            f"rotor speed held, the verdict only says whether the kick dies out.")
    return _p(f"Table 1 {case}: G-UNIV, {speed_m_s:g} m/s, Ω {omega:g} rad/s", text, (measured, amra),
              rotor="mccutcheon", gj_nm2=1471.0, ea_pct=31.4, cg_pct=33.0, mu=0.0, airspeed_m_s=speed_m_s,
              omega_hold_rad_s=omega, fidelity="rigid", run_s=TABLE1_RUN_S)


PRESETS = MappingProxyType({
    "custom": Preset("Custom (keep the current values)", "Your own case: set the controls below.", ()),
    "nominal": _p("Nominal blade, axial", "Paper-boundary blade at its nominal GJ 1500 N m²/rad: stable steady "
                  "autorotation; the kick decays.", rotor="paper-boundary", gj_nm2=1500.0, ea_pct=32.0,
                  cg_pct=40.0, mu=0.0, fidelity="rigid", run_s=10.0),
    **{key: _paper(key) for key in ("fig10", "fig11", "fig12", "fig13")},  # Figs 12-13: μ = 0.1 assumed
    "table1a": _table1("A", 14.0, 38.0, 0.031, 0.026),
    "table1b": _table1("B", 27.0, 41.0, 0.058, 0.056),
})


# ---------------------------------------------------------------------------------------- controls
class Controls(param.Parameterized):
    """Every value that determines a run, a stability analysis and a boundary map."""

    # -- the case
    preset = param.Selector(objects={p.label: key for key, p in PRESETS.items()}, default="custom", label="Preset",
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
            with param.parameterized.discard_events(self):
                self.param.update(**{k: v for k, v in params.items() if k != "preset"})

    @property
    def applying_preset(self) -> bool:
        """True while a chosen preset sets its values (their watchers run inside)."""
        return self._applying_preset

    @param.depends("preset", watch=True)
    def _apply_preset(self):
        values = PRESETS[self.preset].as_dict()
        if "run_s" in values:
            values["run_s"] = min(values["run_s"], self.param.run_s.bounds[1])
        self._applying_preset = True
        try:
            self.param.update(**values)
        finally:
            self._applying_preset = False

    @param.depends("rotor", "gj_nm2", "ea_pct", "cg_pct", "mu", "airspeed_m_s", "omega_hold_rad_s", "fidelity",
                   "aero", "inflow", "soften_at_s", watch=True)
    def _left_preset(self):
        """An edit away from a preset's values makes the case custom, with the selector and its card
        told (set without events, the selector kept showing "Fig. 10" and its text, and choosing
        Fig. 10 again changed nothing)."""
        if not self._applying_preset and self.preset != "custom":
            if any(getattr(self, k) != v for k, v in PRESETS[self.preset].as_dict().items()):
                self.preset = "custom"  # the custom preset sets no values

    # -- mapping to the solver
    def rotor_obj(self, uploaded: Rotor | None = None) -> Rotor:
        """The rotor (shipped or ``uploaded``) with the controls' uniform GJ, EA and CG."""
        if self.rotor == UPLOADED and uploaded is None:
            raise ValueError("rotor = 'uploaded file' is not allowed: no rotor file has been uploaded "
                             "(choose a shipped rotor or upload a TOML file)")
        base = uploaded if self.rotor == UPLOADED else load_preset(self.rotor)
        return base.with_overrides(gj_nm2=self.gj_nm2, x_ea=self.ea_pct / 100.0, x_cg=self.cg_pct / 100.0)

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

    def scenario(self, uploaded: Rotor | None = None, fidelity: str | None = None) -> Scenario:
        """The run to start: the case, and with ``soften_at_s`` the nominal blade softened to GJ then."""
        case = self.case(uploaded, fidelity)
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


# ---------------------------------------------------------------------------------------- links
#: control name -> URL key: every control is in the URL, so a case can be shared as a link
URL_KEYS = {"preset": "preset", "rotor": "rotor", "gj_nm2": "gj", "ea_pct": "ea", "cg_pct": "cg", "mu": "mu",
            "airspeed_m_s": "v", "omega_hold_rad_s": "omega_hold", "fidelity": "fidelity", "aero": "aero",
            "inflow": "inflow", "run_s": "run_s", "soften_at_s": "soften_at", "speed": "speed",
            "present": "present", "map_columns": "map_columns", "map_coarse": "map_coarse"}
_BY_KEY = {v: k for k, v in URL_KEYS.items()}


def allowed(p: param.Parameter) -> str:
    """The values ``p`` allows: ``"10 to 10000"``, the choices, ``"true or false"`` ('' if any)."""
    if isinstance(p, param.Number) and p.bounds:
        return f"{p.bounds[0]:g} to {p.bounds[1]:g}"
    if isinstance(p, param.Selector):
        return ", ".join(map(str, p.objects))
    return "true or false" if isinstance(p, param.Boolean) else ""


def _coerce(p: param.Parameter, name: str, raw):
    if isinstance(p, param.Boolean):
        text = str(raw).strip().lower()
        if text in ("1", "true", "yes", "on"):
            return True
        if text in ("0", "false", "no", "off"):
            return False
        raise ValueError(f"{name} = {raw!r} is not allowed: must be true or false")
    if isinstance(p, param.Integer):
        if isinstance(raw, float) and raw.is_integer():
            raw = int(raw)
        if isinstance(raw, str):
            if not raw.strip().lstrip("+-").isascii() or not raw.strip().lstrip("+-").isdigit():
                raise ValueError(f"{name} = {raw!r} is not allowed: must be an integer")
            raw = int(raw)
    elif isinstance(p, param.Number):
        if isinstance(raw, str):
            raw = float(raw)
        if isinstance(raw, (int, float)) and not isinstance(raw, bool) and not math.isfinite(raw):
            raise ValueError(f"{name} = {raw!r} is not allowed: must be a finite number")
    elif isinstance(p, param.Selector) and not isinstance(raw, str):
        raw = str(raw)
    return raw


def apply_query(controls: Controls, query: dict) -> list:
    """Apply a link's values (raw strings, or values parsed as ``Location.query_params`` parses them),
    the preset first so explicit values win, each validated as a widget's is; return a message for
    each one rejected (the control keeps its value)."""
    # a key the page does not know was dropped without a word (?ea_pct=30 opened at EA 32); the
    # server's own (bokeh-...) and Panel's template theme are not the link's
    errors = [f"link parameter {key} = {query[key]!r} was ignored: not a parameter of this page (its "
              f"parameters: {', '.join(URL_KEYS.values())})"
              for key in sorted(query) if key not in _BY_KEY and not key.startswith("bokeh-") and key != "theme"]
    for key in sorted((k for k in query if k in _BY_KEY), key=lambda k: k != "preset"):
        name, raw = _BY_KEY[key], query[key]
        p = controls.param[name]
        try:
            value = _coerce(p, key, raw)
            if name == "rotor" and value == UPLOADED:
                raise ValueError("an uploaded rotor cannot be shared by link (upload the file again)")
            controls.param.update({name: value})
        except Exception as exc:  # noqa: BLE001 - every bad value becomes a message
            rng = "" if isinstance(p, param.Boolean) else allowed(p)  # (a boolean's reason says it)
            rng = f" (allowed{'' if isinstance(p, param.Number) else ':'} {rng})" if rng else ""
            why = _why_not(p, raw)
            if why is None:  # the value's own reason (an uploaded rotor in a link)
                why, rng = str(exc).split("\n")[0][:200], ""
            errors.append(f"link parameter {key} = {raw!r} was ignored: {why}{rng}")
    return errors


def _why_not(p: param.Parameter, raw) -> Optional[str]:
    """Why a link's value for ``p`` was refused, in the inputs' words (param's own message named
    internals: "Number parameter 'Controls.run_s' must be at most 120.0, not 1000000000.0."); None
    when the value is of the right kind and in range (then the refusal has its own reason)."""
    if isinstance(p, param.Boolean):
        return "not true or false"
    if isinstance(p, param.Selector) and str(raw) not in [str(v) for v in p.get_range().values()]:
        return "not one of the choices"
    if isinstance(p, param.Number):
        try:
            x = float(raw)
        except (TypeError, ValueError):
            return "not a number"
        if not math.isfinite(x):
            return "not a finite number"
        if isinstance(p, param.Integer) and not x.is_integer():
            return "not an integer"
        lo, hi = p.bounds or (None, None)
        if (lo is not None and x < lo) or (hi is not None and x > hi):
            return "out of range"
    return None


def query_string(controls: Controls) -> str:
    """The URL query for the current values (what a shared link carries)."""
    def text(v):  # as Location.sync writes them: booleans true/false, not Python's True/False
        return str(v).lower() if isinstance(v, bool) else v
    return urllib.parse.urlencode({key: text(getattr(controls, name)) for name, key in URL_KEYS.items()})


def parse_link_query(query: str) -> dict:
    """A URL query string (with or without the leading '?') as ``{key: raw string}``."""
    return dict(urllib.parse.parse_qsl(query.lstrip("?"), keep_blank_values=True))


def apply_session_query(controls: Controls, notify) -> None:
    """At session creation: apply the link's values, so the first paint already shows the case."""
    import panel as pn
    args = pn.state.session_args or {}
    raw = {k: v[-1].decode("utf-8", "replace") if isinstance(v[-1], bytes) else str(v[-1])
           for k, v in args.items() if v}
    report_link_errors(apply_query(controls, raw), notify)


def report_link_errors(msgs: list, notify) -> None:
    """One message for a link's refused values, naming every one (the alert shows the last three
    messages: a link with seven bad values showed three, the rest only in passing toasts)."""
    if len(msgs) == 1:
        notify(msgs[0])
    elif msgs:
        notify(f"{len(msgs)} values of this link were ignored:\n\n" + "\n".join(f"- {m}" for m in msgs))


def sync_url(controls: Controls, location=None) -> None:
    """After the page has loaded: mirror every control in the URL (``pn.state.location.sync``, or
    ``location``'s)."""
    import panel as pn
    loc = pn.state.location if location is None else location
    if loc is None:
        return
    # every value but the preset both ways: Location.sync applies the link's values in one batch,
    # after which the preset's watcher would overwrite the edits (?preset=nominal&gj=100 opened at
    # GJ 1500); a link's preset was applied first by apply_session_query (whose messages name any
    # bad value, so none are repeated here)
    loc.sync(controls, {k: v for k, v in URL_KEYS.items() if k != "preset"}, on_error=lambda bad: None)

    # the preset one way only, so a copied link reopens as the preset it shows (the URL kept the
    # opening link's preset=fig10 after Fig. 12 was chosen, and the link opened as a custom case).
    # With every synced value as it is now, serialised as Location writes them: an edit that leaves a
    # preset changes the preset inside the edit's own watchers, before Location has written the
    # edited value, and a query holding the old value was read back (a GJ typed over the nominal
    # preset's went back to 1500)
    def write_preset(*_):
        loc.update_query(preset=controls.preset, **url_values(controls))
    controls.param.watch(write_preset, "preset")
    write_preset()


def url_values(controls: Controls) -> dict:
    """Every synced control's URL value as ``Location.sync`` writes it (the parameter's own
    serialisation, JSON text unless already a string)."""
    out = {}
    for name, key in URL_KEYS.items():
        if name != "preset":
            v = controls.param[name].serialize(getattr(controls, name))
            out[key] = v if isinstance(v, str) else json.dumps(v)
    return out


# ---------------------------------------------------------------------------------------- rotor files
MAX_BYTES = 256 * 1024  #: a rotor description is a few kB; anything near this is not one


class UploadError(ValueError):
    """The upload is not a usable rotor file; the message says why, naming the file."""


def parse_rotor_upload(data: bytes | None, filename: str = "upload") -> Rotor:
    """A :class:`Rotor` from the bytes of a TOML rotor file (``assets/rotors/*.toml``), parsed from
    memory with a size cap, by the core's own reader of rotor files
    (:func:`amra_core.rotor_io.rotor_from_toml`: its prescan refuses what would make the parser
    recurse or grow without bound)."""
    name = filename or "upload"
    if not data:
        raise UploadError(f"rotor file {name!r} is empty")
    if len(data) > MAX_BYTES:
        raise UploadError(f"rotor file {name!r} is {len(data) / 1024:.0f} kB: too large "
                          f"(a rotor description is a few kB; the limit is {MAX_BYTES // 1024} kB)")
    try:
        return rotor_from_toml(decode_rotor_bytes(data, name), name)
    except RotorError as exc:
        raise UploadError(str(exc)) from None
