"""Done-when check of issue 21: at EA 0.32, rigid and fem-coupled, axial and mu 0.1, the fold GJ (no
normal autorotation below) rises with the CG from 0.36 to 0.50 (model-notes §8: the fold is set by
static twist, the total pitch reaching the root's stall). The fold is the map's ``fold_gj``
(:func:`amra_core.boundary.intervals.classify` of the column walk's intervals)."""
from __future__ import annotations

import pytest

from amra_core.boundary.intervals import classify
from amra_core.column import walk_column
from amra_core.flight import FlightCondition, SolverSettings
from amra_core.rotor_io import load_preset

CGS = (0.36, 0.43, 0.50)
#: the walks start at 2500 N m^2/rad (above every fold here: 1300 at most, fem-coupled axial CG 0.50)
GJ_MAX = 2500.0


def fold_gj(fidelity: str, mu: float, cg: float) -> float:
    rotor = load_preset("paper-boundary").with_overrides(x_ea=0.32, x_cg=cg)
    fl = FlightCondition(mu=mu) if mu > 0 else FlightCondition()
    w = walk_column(rotor, fl, SolverSettings(fidelity=fidelity), cg, 100.0, GJ_MAX, n_probe=2)
    return classify(w.intervals, GJ_MAX)["fold_gj"]


@pytest.mark.slow
@pytest.mark.parametrize("fidelity, mu", [("rigid", 0.0), ("rigid", 0.1), ("fem-coupled", 0.0),
                                          ("fem-coupled", 0.1)])
def test_fold_gj_rises_with_cg_from_036_to_050(fidelity, mu):
    folds = [fold_gj(fidelity, mu, cg) for cg in CGS]
    print(f"\n{fidelity}, mu {mu}: fold GJ " + ", ".join(f"CG {c:.2f}: {g}" for c, g in zip(CGS, folds)))
    assert all(g is not None and g < GJ_MAX for g in folds), folds
    assert all(b > a for a, b in zip(folds, folds[1:])), folds
