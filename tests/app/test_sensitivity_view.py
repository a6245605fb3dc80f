"""The map tab's sensitivity study (issue 21 §6): the button walks the current CG column again with
every estimate ±10 % in the analysis pool; the answer is a table, a band per boundary on the map at
that CG (lowest to highest over the baseline and every change) and a CSV that reads back."""
from __future__ import annotations

import io

import pandas as pd
import pytest

from amra_core.sensitivity import ESTIMATE_NAMES
from app.views.sensitivity import HEADERS, TABLE_COLUMNS
from test_dashboard import pump_until


def test_sensitivity_study_draws_bands_and_exports_its_table(dash, wait):
    dash.refresh_analyses()  # the map follows the case
    dash.sensitivity.start()
    assert dash.sensitivity.busy.visible and "computing" in dash.sensitivity.info.value
    pump_until(dash, lambda: dash.sensitivity.result is not None, wait, 900, "the sensitivity study")
    r = dash.sensitivity.result
    assert r["cg"] == pytest.approx(0.40) and r["fidelity"] == "rigid" and r["step"] == pytest.approx(0.10)
    assert len(r["rows"]) == 2 * len(ESTIMATE_NAMES)
    base = r["baseline"]["fold_gj_nm2"]
    lo, hi = r["fold_band_nm2"]
    folds = [row["fold_gj_nm2"] for row in r["rows"] if row["fold_gj_nm2"] is not None]
    assert lo == min(folds + [base]) and hi == max(folds + [base]) and lo < base < hi  # some estimate moves it
    bands = dash.map.sens_source.data
    fold_at = list(bands["lo"]).index(lo)
    assert bands["hi"][fold_at] == hi and bands["cg_pct"][fold_at] == pytest.approx(40.0 - 0.6)
    assert "fold GJ" in bands["text"][fold_at] and not dash.sensitivity.busy.visible
    shown = dash.sensitivity.table.object
    assert list(shown.columns) == list(HEADERS)
    assert not shown.isin(["None", "nan", "NaN"]).any().any()  # a missing value is said, not printed as None
    assert (shown["Fold GJ [N m²/rad]"] == [f"{w:.0f}" for w in (row["fold_gj_nm2"] for row in r["rows"])]).all()
    assert f"fold GJ {base:.0f}" in dash.sensitivity.info.value
    back = pd.read_csv(io.StringIO(dash.sensitivity.csv().getvalue()), comment="#")
    assert list(back.columns) == list(TABLE_COLUMNS) and len(back) == len(r["rows"])
    want = [row["fold_gj_nm2"] for row in r["rows"]]
    assert back["fold_gj_nm2"].tolist() == pytest.approx([float("nan") if w is None else w for w in want],
                                                         rel=1e-7, nan_ok=True)
    assert dash.sensitivity.download.filename == "amra-sensitivity-rigid-cg40.csv"
    # another case: the bands belonged to the old one and go
    dash.controls.fidelity = "fem-torsion"
    dash.refresh_analyses()
    assert len(dash.map.sens_source.data["lo"]) == 0


def test_an_invalid_case_is_named_not_studied(dash):
    dash.controls.omega_hold_rad_s = 0.5  # in the widget's bounds, refused by the core
    dash.sensitivity.start()
    assert dash.messages and "cannot study the sensitivity of this case" in dash.messages[-1][1]
    assert dash.sensitivity.result is None and not dash.sensitivity.busy.visible


def test_a_change_that_rounds_to_zero_reads_plus_zero():
    """A boundary that moved by -0.3 N m²/rad read "-0" in the table."""
    from app.views.sensitivity import display_frame
    row = {"label": "hub polar inertia", "change": -0.1, "value": 1.0, "unit": "kg m²", "fold_gj_nm2": 414.0,
           "d_fold_gj_nm2": -0.3, "flutter_gj_nm2": None, "d_flutter_gj_nm2": None, "note": ""}
    table = display_frame({"rows": [row]})
    assert "-0" not in table.to_string().replace("-10", "") and "+0" in table.to_string()


def test_the_summary_says_a_band_without_a_baseline_boundary_comes_from_the_changes():
    """"strong-flutter GJ none in range, band 591 to 680 N m²/rad" read as a contradiction."""
    from app.views.sensitivity import summary_html
    result = {"cg": 0.4, "fidelity": "rigid", "mu": 0.0, "step": 0.1, "wall_time_s": 4.2,
              "baseline": {"fold_gj_nm2": 416.0, "flutter_gj_nm2": None, "flutter_at_gj_max": False},
              "fold_band_nm2": (398.0, 431.0), "flutter_band_nm2": (591.0, 680.0)}
    text = summary_html(result)
    assert "fold GJ 416, 398 to 431 N m²/rad over the baseline and every ±10 % change" in text
    assert ("strong-flutter GJ none in range at the baseline, 591 to 680 N m²/rad under some of the ±10 % "
            "changes") in text
