"""Classroom presets: the seed paper's cases (Figs 10-13, Table 1) and the nominal blade.

Each preset is a set of control values (see :class:`app.controls.Controls`) with a card text
shown under the selector. Figs 10-13 tell the paper's story (:mod:`amra_core.paper_cases`): the
paper-boundary blade (EA 32 %, CG 40 % chord) starts in steady autorotation at its nominal GJ and
is softened to the figure's GJ at t = 2 s (``soften_at_s``), as a live change does; in this model
no steady autorotation exists at the figures' GJ at all. The paper does not give the forward speed
of Figs 12-13; μ = 0.1 is assumed. Table 1 holds the rotor speed at the measured mean in level
flight and compares the teeter amplitude with the flight measurement and the original AMRA.
"""
from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType

from amra_core.paper_cases import PAPER_CASES


@dataclass(frozen=True)
class Preset:
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
    merged = dict(_BASE) | values
    return Preset(label, explanation, tuple(merged.items()), teeter_reference_rad)


def _paper(key: str) -> Preset:
    pc = PAPER_CASES[key]
    text = f"**The paper:** {pc.paper_reports}.\n\n**This model:** {pc.model_gives}"
    return _p(pc.label, text, rotor="paper-boundary", gj_nm2=pc.gj_nm2, ea_pct=32.0, cg_pct=40.0, mu=pc.mu,
              fidelity=pc.fidelity, run_s=pc.run_s, soften_at_s=pc.soften_at_s)


def _table1(case: str, speed_m_s: float, omega: float, measured: float, amra: float) -> Preset:
    text = (f"Paper Table 1 case {case}: McCutcheon rotor (GJ, EA, CG at their span means), rotor speed held "
            f"at {omega:g} rad/s, level flight at {speed_m_s:g} m/s. **Teeter amplitude:** measured in flight "
            f"{measured:g} rad, original AMRA {amra:g} rad; this model's is shown when the run ends. With the "
            f"rotor speed held, the verdict only says whether the kick dies out.")
    return _p(f"Table 1 {case}: G-UNIV, {speed_m_s:g} m/s, Ω {omega:g} rad/s", text, (measured, amra),
              rotor="mccutcheon", gj_nm2=1471.0, ea_pct=31.4, cg_pct=33.0, mu=0.0, airspeed_m_s=speed_m_s,
              omega_hold_rad_s=omega, fidelity="rigid", run_s=5.0)


PRESETS = MappingProxyType({
    "custom": Preset("Custom (keep the current values)", "Your own case: set the controls below.", ()),
    "nominal": _p("Nominal blade, axial", "Paper-boundary blade at its nominal GJ 1500 N m²/rad: stable steady "
                  "autorotation; the kick decays.", rotor="paper-boundary", gj_nm2=1500.0, ea_pct=32.0,
                  cg_pct=40.0, mu=0.0, fidelity="rigid", run_s=10.0),
    **{key: _paper(key) for key in ("fig10", "fig11", "fig12", "fig13")},
    "table1a": _table1("A", 14.0, 38.0, 0.031, 0.026),
    "table1b": _table1("B", 27.0, 41.0, 0.058, 0.056),
})
