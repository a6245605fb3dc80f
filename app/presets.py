"""Classroom presets: the seed paper's cases (Figs 10-13, Table 1) and the nominal blades.

Each preset is a set of control values (see :class:`app.controls.Controls`) with a one-line
explanation shown under the selector. Figs 10-13 use the ``paper-boundary`` rotor (EA 32 %,
CG 40 % chord); the paper does not give the forward speed of Figs 12-13, so mu = 0.1 is used (as in
``tests/core/test_system.py``). Table 1 holds the rotor speed at the measured mean in level flight.
"""
from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType


@dataclass(frozen=True)
class Preset:
    label: str
    explanation: str
    values: tuple  #: ((control name, value), ...)

    def as_dict(self) -> dict:
        return dict(self.values)


_BASE = (("airspeed_m_s", 0.0), ("omega_hold_rad_s", 0.0), ("aero", "theodorsen"), ("inflow", "uniform"))


def _p(label, explanation, **values):
    merged = dict(_BASE) | values
    return Preset(label, explanation, tuple(merged.items()))


PRESETS = MappingProxyType({
    "custom": Preset("Custom (keep the current values)", "Your own case: set the controls below.", ()),
    "nominal": _p("Nominal blade, axial", "Paper-boundary blade at its nominal GJ 1500 N m²/rad: stable steady "
                  "autorotation; the kick decays.", rotor="paper-boundary", gj_nm2=1500.0, ea_pct=32.0,
                  cg_pct=40.0, mu=0.0, fidelity="rigid", run_s=10.0),
    "fig10": _p("Fig. 10: rigid, axial, GJ 100", "Paper Fig. 10: a soft blade (GJ 100 N m²/rad) twists nose-up "
                "until drag wins; no autorotation exists and the rotor speed runs down.", rotor="paper-boundary",
                gj_nm2=100.0, ea_pct=32.0, cg_pct=40.0, mu=0.0, fidelity="rigid", run_s=10.0),
    "fig11": _p("Fig. 11: FEM coupled, axial, GJ 400", "Paper Fig. 11: the flexible (FEM flap-torsion) blade at "
                "GJ 400 N m²/rad loses its autorotation: rotor speed falls, descent rate rises.",
                rotor="paper-boundary", gj_nm2=400.0, ea_pct=32.0, cg_pct=40.0, mu=0.0, fidelity="fem-coupled",
                run_s=10.0),
    "fig12": _p("Fig. 12: rigid, forward (μ 0.1), GJ 300", "Paper Fig. 12 in forward flight (μ = 0.1 assumed): the "
                "rigid-blade model at GJ 300 N m²/rad is unstable.", rotor="paper-boundary", gj_nm2=300.0,
                ea_pct=32.0, cg_pct=40.0, mu=0.1, fidelity="rigid", run_s=10.0),
    "fig13": _p("Fig. 13: FEM coupled, forward (μ 0.1), GJ 600", "Paper Fig. 13 in forward flight (μ = 0.1 "
                "assumed): the FEM blade at GJ 600 N m²/rad is already unstable: flexibility lowers the "
                "boundary's safety margin.", rotor="paper-boundary", gj_nm2=600.0, ea_pct=32.0, cg_pct=40.0,
                mu=0.1, fidelity="fem-coupled", run_s=10.0),
    "table1a": _p("Table 1 A: G-UNIV, 14 m/s, Ω 38 rad/s", "Paper Table 1 case A: McCutcheon rotor (GJ, EA, CG "
                  "at their span means), rotor speed held at 38 rad/s, level flight at 14 m/s; measured teeter "
                  "0.031 rad.", rotor="mccutcheon", gj_nm2=1471.0, ea_pct=31.4, cg_pct=33.0, mu=0.0, airspeed_m_s=14.0, omega_hold_rad_s=38.0,
                  fidelity="rigid", run_s=5.0),
    "table1b": _p("Table 1 B: G-UNIV, 27 m/s, Ω 41 rad/s", "Paper Table 1 case B: as A at 27 m/s and 41 rad/s; "
                  "measured teeter 0.058 rad (larger at the higher speed).", rotor="mccutcheon", gj_nm2=1471.0,
                  ea_pct=31.4, cg_pct=33.0, mu=0.0, airspeed_m_s=27.0, omega_hold_rad_s=41.0, fidelity="rigid",
                  run_s=5.0),
})
