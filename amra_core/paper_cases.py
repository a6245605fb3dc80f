"""The seed paper's instability cases (Figs 10-13) as scenarios that tell the paper's story.

The paper (Trchalík, Gillies & Thomson 2008, §5) shows for EA 32 % and CG 40 % chord that "reduction
of rotor speed from a steady value to zero takes only few seconds" while the "speed of descent
increases to unacceptable value". In this model no steady autorotation exists at the figures' GJ at
all: the trim branch ends in a fold (model-notes §7) at a higher GJ, given per case below as
``model_fold_gj_nm2`` (checked against the trim by ``tests/core/test_scenario.py``). A run started
*at* the figure's GJ can only begin from that fold's state, already slowed down. So each case starts
from the nominal blade (GJ 1500 N m²/rad), trimmed in steady autorotation, and softens it to the
figure's GJ at ``soften_at_s`` as a live change does: the instability and the rotor-speed collapse
then unfold as in the paper's figures.

Forward flight: the paper does not state the speed of Figs 12-13; μ = 0.1 is assumed (as the
dashboard's presets and ``tests/core/test_system.py`` do).
"""
from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType

from .flight import FlightCondition, SolverSettings
from .rotor_io import load_preset
from .scenario import LiveChange, Scenario
from .simulation import Case

NOMINAL_GJ_NM2 = 1500.0  #: the paper-boundary blade's nominal torsional stiffness [N m^2/rad]
EA_FRACTION = 0.32  #: elastic axis of Figs 10-14 [fraction of chord]
CG_FRACTION = 0.40  #: centre of gravity of Figs 10-13 [fraction of chord]


@dataclass(frozen=True)
class PaperCase:
    """One of the paper's figures as a scenario: ``fidelity`` and advance ratio ``mu`` of the
    figure, its torsional stiffness ``gj_nm2`` [N m^2/rad] reached at ``soften_at_s`` [s] from
    the nominal blade, a run of ``run_s`` [s]; the texts say what the paper reports and what this
    model gives, and why they differ."""

    key: str
    figure: str
    fidelity: str
    mu: float
    gj_nm2: float
    model_fold_gj_nm2: float  #: the GJ [N m^2/rad] where this model's steady autorotation ends
    paper_reports: str
    soften_at_s: float = 2.0
    run_s: float = 12.0

    @property
    def label(self) -> str:
        flight = "axial" if self.mu == 0 else f"forward (μ {self.mu:g})"
        return f"{self.figure}: {self.fidelity}, {flight}, GJ {self.gj_nm2:g}"

    @property
    def model_gives(self) -> str:
        return (f"This model has no steady autorotation below GJ ≈ {self.model_fold_gj_nm2:.0f} N m²/rad at "
                f"this CG (the fold: nose-up elastic twist raises the blade pitch until the root stalls), so "
                f"the case starts from the nominal blade (GJ {NOMINAL_GJ_NM2:g}) in steady autorotation and "
                f"is softened to GJ {self.gj_nm2:g} at t = {self.soften_at_s:g} s. The rotor speed then "
                f"collapses within seconds while the descent rate climbs, as in the paper's figure; later it "
                f"settles at a low rotor speed with a descent rate far beyond normal autorotation (the "
                f"windmill-brake state), where the paper's figure goes on towards zero.")

    def scenario(self, run_s: float | None = None) -> Scenario:
        rotor = load_preset("paper-boundary").with_overrides(gj_nm2=NOMINAL_GJ_NM2, x_ea=EA_FRACTION,
                                                             x_cg=CG_FRACTION)
        flight = FlightCondition(mu=self.mu) if self.mu else FlightCondition()
        case = Case(rotor, flight, SolverSettings(fidelity=self.fidelity), t_end_s=run_s or self.run_s)
        return Scenario(case, (LiveChange(self.soften_at_s, gj_nm2=self.gj_nm2),))


_AXIAL = ("reduction of rotor speed from a steady value to zero takes only few seconds; the speed of "
          "descent increases to an unacceptable value (paper §5, {fig})")
_FORWARD = ("as in axial flight: the rotor speed decays within seconds and the descent speed rises; the "
            "paper finds the rotor unstable whenever the CG lies aft of the EA (paper §5, {fig})")

PAPER_CASES = MappingProxyType({
    "fig10": PaperCase("fig10", "Fig. 10", "rigid", 0.0, 100.0, 414.0, _AXIAL.format(fig="Fig. 10")),
    "fig11": PaperCase("fig11", "Fig. 11", "fem-coupled", 0.0, 400.0, 670.0, _AXIAL.format(fig="Fig. 11")),
    "fig12": PaperCase("fig12", "Fig. 12", "rigid", 0.1, 300.0, 557.0, _FORWARD.format(fig="Fig. 12")),
    "fig13": PaperCase("fig13", "Fig. 13", "fem-coupled", 0.1, 600.0, 925.0, _FORWARD.format(fig="Fig. 13")),
})
