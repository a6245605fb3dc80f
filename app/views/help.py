"""Help in the page: what each verdict and map class means, why a growth rate can be negative on an
unstable case, what the controls mean, and where the paper and the validation report are."""
from __future__ import annotations

import panel as pn

from amra_core.trim import WINDMILL_BRAKE_RATIO

from ..inputs import tooltip

PAPER_URL = "http://eprints.gla.ac.uk/4967/"
REPORT_URL = "validation/report.html"  #: served beside the app by ``amra serve``

VERDICTS = (
    ("stable", "The kick dies out: rotor speed, teeter and twist return to the steady autorotation (or its "
               "periodic motion in forward flight)."),
    ("flutter", "An oscillation of teeter, twist and rotor speed grows (or saturates into a limit cycle, "
                "reported with its amplitude). In autorotation it usually drags the rotor speed down."),
    ("divergence", "A monotonic runaway: the twist grows without oscillating, or the rotor speed falls "
                   "steadily, below half its trimmed value (it may settle there, slow and descending fast)."),
    ("overspeed", "The rotor speed runs away upwards (a nose-down twist, e.g. with the CG ahead of the "
                  "elastic axis, lowers the blade pitch and speeds the rotor up)."),
    ("fold / no-autorotation", "No torque balance exists: the nose-up elastic twist has raised the blade pitch "
                               "until the root stalls and drag wins. The rotor speed decays from the start; "
                               "on the map, the fold GJ is the stiffness below which this happens."),
    ("windmill-brake", f"An equilibrium descending faster than {WINDMILL_BRAKE_RATIO:g} times the hover induced "
                       "velocity v_h (beyond the turbulent-wake region; the map finds them at 2-6 v_h) with little "
                       "inflow: real, but the paper's failure state (descent speed 'increases to an unacceptable "
                       "value'), not autorotation."),
    ("undetermined", "Too little data to judge: the run is shorter than a few cycles of its slowest mode, or "
                     "it had not settled. Run longer; it is never counted as stable."),
    ("numerical-failure", "The state became non-finite. Reported, never hidden: try a shorter step or another "
                          "fidelity, and tell us the case."),
)

MAP_CLASSES = (
    ("fold line", "Below this GJ no steady autorotation exists (the branch of trims ends, or continues only as "
                  "an overspeeding or windmill-brake state)."),
    ("strong flutter line", "The top of the highest strong flutter interval: above it the column is stable. The "
                            "critical GJ is the larger of the fold and the strong flutter GJ."),
    ("strong flutter band", "An unstable mode on the trim branch that is not weak (shaded)."),
    ("weak window", "A flutter interval whose damping ratio is above -0.02 and whose 20 s run from the default kick "
                    "keeps the rotor speed and stays within 1° of twist and teeter (amra boundary --weak-damping, "
                    "--weak-amplitude). Real in the linear model, but marginal: drawn lighter and hatched, exported, "
                    "and it never moves the critical GJ."),
    ("overspeed", "The trim continues with a rising rotor speed past twice the hover induced velocity: the normal "
                  "branch overspeeding, not the windmill-brake root."),
)


def _table(head: str, rows) -> str:
    """A Markdown table in one block: the header, its rule and the rows on consecutive lines (a blank
    line between them would end the table and leave its pipes as text)."""
    return "\n".join([head, "|---|---|"] + [f"| **{k}** | {v} |" for k, v in rows])


def help_markdown(controls=None) -> str:
    """The help text (Markdown); with ``controls``, each control's unit and allowed range too."""
    parts = [
        "### What the verdicts mean", _table("| verdict | meaning |", VERDICTS),
        "### What the map shows", _table("| class | meaning |", MAP_CLASSES),
        "### Why a growth rate can be negative on an unstable case",
        "The growth rate is fitted to the envelope of the motion *since the last change*. A case whose "
        "rotor speed collapses (fold, divergence) can have a decaying oscillation on top of the collapse, "
        "so its oscillation's growth rate is negative while the rotor is lost: read the verdict and the "
        "collapse time, not the sign alone.",
        "### Frequencies in forward flight",
        "A forward-flight mode moves at its frequency plus and minus whole multiples of the rotor's at "
        "once (the blades meet a different airspeed each revolution). The map and the Modes tab give each "
        "mode the frequency at which its named motion (the blades' twist for a torsion mode) is largest "
        "over a revolution: the one a run of the case shows most.",
        "### Two growth rates",
        "The map and the Modes tab give the **eigenvalue's** growth rate: how fast a small disturbance of "
        "the trimmed state grows at first. The run's card gives the **run's fit**: the envelope of the "
        "simulated motion over the run's last two thirds. A flutter that saturates into a limit cycle has an "
        "eigenvalue of, say, +0.97 1/s and a run's fit near 0 1/s: both are right, about different things.",
        "### Where this comes from",
        f"The model re-implements Trchalík, Gillies & Thomson (2008), *Development of an aeroelastic stability "
        f"boundary for a rotor in autorotation* ([the paper]({PAPER_URL})). How this model compares with "
        f"analytic results, published data and the paper is in the [validation report]({REPORT_URL}).",
    ]
    if controls is not None:
        rows = [(controls.param[n].label, tooltip(controls.param[n]))
                for n in ("gj_nm2", "ea_pct", "cg_pct", "mu", "fidelity", "aero", "inflow", "run_s", "soften_at_s",
                          "speed")]
        parts += ["### The controls", _table("| control | meaning, unit and allowed range |", rows)]
    return "\n\n".join(parts)


def help_pane(controls=None) -> pn.pane.Markdown:
    return pn.pane.Markdown(help_markdown(controls), sizing_mode="stretch_width", name="help",
                            css_classes=["amra-help"])
