"""Fold, flutter and critical GJ of a column from its intervals (issue 21 §2), on synthetic
intervals whose answer is known by construction (:func:`amra_core.boundary.intervals.classify`)."""
from __future__ import annotations

import math

from amra_core.boundary.intervals import WEAK_AMPLITUDE_DEG, WEAK_DAMPING, classify, strength_of


def iv(kind, lo, hi, zeta=None, mode="torsion", mono=None, run=None):
    d = {"kind": kind, "gj_lo_nm2": lo, "gj_hi_nm2": hi, "resolved": True, "gj_lo_point_nm2": lo * 1.005,
         "gj_hi_point_nm2": hi * 0.995}
    if kind == "flutter":
        osc = None if zeta is None else {"mode": mode, "damping_ratio": zeta, "growth_rate_1_s": 1.0,
                                         "frequency_hz": 12.0, "participation": {}}
        d.update({"peak_growth_rate_1_s": 1.0, "damping_ratio": zeta if zeta is not None else -1.0,
                  "frequency_hz": 12.0, "mode": mode, "oscillatory": osc,
                  "oscillatory_blade": osc if mode not in ("inflow", "rotor speed", "descent") else None,
                  "monotonic_growth_rate_1_s": mono})
        if run is not None:
            d.update({"run_outcome": run[0], "run_verdict": "flutter",
                      "run_amplitude": {"twist_deg": run[1], "teeter_deg": run[1], "omega_rad_s": 0.0}})
    return d


def test_strength_needs_a_small_damping_ratio_and_a_small_run():
    assert strength_of(iv("flutter", 600, 660, zeta=-0.012)) == "weak"
    assert strength_of(iv("flutter", 600, 660, zeta=-0.012, run=("bounded-oscillation", 0.38))) == "weak"
    assert strength_of(iv("flutter", 600, 660, zeta=-0.006, run=("bounded-oscillation", 10.0))) == "strong"
    assert strength_of(iv("flutter", 600, 660, zeta=-0.012, run=("rotor-speed-collapse", 0.1))) == "strong"
    assert strength_of(iv("flutter", 600, 660, zeta=-1.2 * WEAK_DAMPING)) == "strong"
    assert strength_of(iv("flutter", 600, 660, zeta=-0.001, mono=0.5)) == "strong"  # a monotonic growth
    assert strength_of(iv("flutter", 600, 660, zeta=-0.012), weak_damping=0.0) == "strong"
    assert strength_of(iv("flutter", 600, 660, zeta=-0.012, run=("bounded-oscillation", 0.38)),
                       weak_amplitude_deg=0.3) == "strong"
    assert WEAK_AMPLITUDE_DEG == 1.0


def test_weak_window_does_not_move_the_critical_gj():
    """Rigid axial CG 0.40: fold at 416, a weak window 628-662 above: critical = fold."""
    c = classify([iv("windmill-brake", 30, 350), iv("fold", 350, 412), iv("stable", 412, 628),
                  iv("flutter", 628, 662, zeta=-0.012, run=("bounded-oscillation", 0.38)), iv("stable", 662, 3000)],
                 3000)
    assert c["fold_gj"] == 412 * 1.005 and c["flutter_gj"] is None and c["critical_gj"] == c["fold_gj"]
    assert c["kind"] == "fold" and [x.get("strength") for x in c["intervals"]][3] == "weak"


def test_strong_window_above_the_fold_sets_the_critical_gj():
    c = classify([iv("fold", 30, 270), iv("stable", 270, 438), iv("flutter", 438, 485, zeta=-0.08),
                  iv("stable", 485, 3000)], 3000)
    assert c["flutter_gj"] == 485 * 1.005 and c["critical_gj"] == c["flutter_gj"] and c["kind"] == "flutter"
    assert c["fold_gj"] == 270 * 1.005


def test_the_fold_approach_is_merged_into_the_fold():
    """Rigid axial CG 0.36: 270-281 directly above the branch end, an inflow mode growing and a weak
    teeter oscillation: the fold's own approach; a strong blade mode there would not be."""
    ivs = [iv("windmill-brake", 30, 193), iv("fold", 193, 270),
           iv("flutter", 270, 281, zeta=-0.0855, mode="inflow", mono=0.12), iv("stable", 281, 3000)]
    c = classify(ivs, 3000)
    assert c["intervals"][2]["fold_approach"] and c["flutter_gj"] is None
    assert c["fold_gj"] == 281 * 1.005 and c["branch_end_gj"] == 270 * 1.005
    ivs[2] = iv("flutter", 270, 281, zeta=-0.1, mode="flap")
    c = classify(ivs, 3000)
    assert not c["intervals"][2]["fold_approach"] and c["flutter_gj"] == 281 * 1.005
    # a weakly damped blade mode whose run grows large is not the fold's approach either
    ivs[2] = iv("flutter", 270, 281, zeta=-0.016, mode="torsion", run=("bounded-oscillation", 7.0))
    c = classify(ivs, 3000)
    assert not c["intervals"][2]["fold_approach"] and c["intervals"][2]["strength"] == "strong"


def test_overspeed_stretch_is_no_normal_autorotation_and_unstable_top_is_inf():
    c = classify([iv("overspeed", 30, 205), iv("flutter", 205, 1043, zeta=-0.05), iv("stable", 1043, 3000)], 3000)
    assert c["fold_gj"] == 205 * 1.005 and c["flutter_gj"] == 1043 * 1.005
    c = classify([iv("stable", 30, 2000), iv("flutter", 2000, 3000, zeta=-0.1)], 3000)
    assert math.isinf(c["critical_gj"])
