"""``amra validate --quick``: runs in-process once (module fixture) and checks the report files."""
import json
import re

import pytest

from amra_core.cli import main

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def quick_report(tmp_path_factory):
    out = tmp_path_factory.mktemp("validate")
    rc = main(["validate", "--quick", "--quiet", "--out", str(out)])
    return rc, out


def test_exit_code_and_files(quick_report):
    rc, out = quick_report
    assert rc == 0
    assert (out / "report.html").is_file()
    assert (out / "results.json").is_file()


def test_html_is_self_contained(quick_report):
    _, out = quick_report
    text = (out / "report.html").read_text(encoding="utf-8")
    assert text.startswith("<!DOCTYPE html>")
    # every src= is an embedded data URI; no external links of any kind
    srcs = re.findall(r'src\s*=\s*["\']([^"\']*)', text, flags=re.I)
    assert srcs, "no figures embedded"
    assert all(s.startswith("data:image/png;base64,") for s in srcs), [s[:40] for s in srcs]
    assert not re.search(r'(src|href)\s*=\s*["\']\s*(https?:)?//', text, flags=re.I)
    assert "<link" not in text.lower() and "<script" not in text.lower()


def test_every_case_has_reference_value_status(quick_report):
    _, out = quick_report
    doc = json.loads((out / "results.json").read_text(encoding="utf-8"))
    cases = doc["cases"]
    assert len(cases) >= 40
    ids = [c["id"] for c in cases]
    assert len(set(ids)) == len(ids)
    for c in cases:
        for key in ("id", "section", "title", "reference", "reference_source", "value", "unit", "tolerance",
                    "status", "note"):
            assert key in c, (c["id"], key)
        assert c["reference"] not in (None, ""), c["id"]
        assert c["value"] not in (None, ""), c["id"]
        assert c["status"] in ("pass", "fail", "info", "error", "skipped"), c
    assert {c["section"] for c in cases} == {"structure", "aero", "autorotation", "system"}
    assert doc["meta"]["mode"] == "quick"


def test_structure_cases_pass(quick_report):
    _, out = quick_report
    doc = json.loads((out / "results.json").read_text(encoding="utf-8"))
    structure = [c for c in doc["cases"] if c["section"] == "structure"]
    assert len(structure) >= 20
    bad = [(c["id"], c["value"], c["note"]) for c in structure if c["status"] != "pass"]
    assert not bad, bad


def test_no_errors_and_paper_cases_present(quick_report):
    _, out = quick_report
    doc = json.loads((out / "results.json").read_text(encoding="utf-8"))
    errors = [(c["id"], c["note"]) for c in doc["cases"] if c["status"] == "error"]
    assert not errors, errors
    ids = {c["id"] for c in doc["cases"]}
    for fig in ("fig10", "fig11", "fig12", "fig13"):
        assert f"system.paper-case.{fig}" in ids
    assert {"system.table1.A.rigid", "system.table1.B.fem-coupled", "aero.theodorsen.magnitude",
            "autorotation.descent-rate.rigid", "autorotation.torque-regions.present"} <= ids
    # the equivalent rigid blade beside the FEM: cyclic flap, static twist, fold GJ with both springs
    eq = {c["id"]: c for c in doc["cases"] if c["id"].startswith("system.equivalence.")}
    assert set(eq) == {"system.equivalence.cyclic-flap", "system.equivalence.static-twist",
                       "system.equivalence.fold-gj"}
    assert all(c["status"] == "pass" for c in eq.values()), eq
    folds = eq["system.equivalence.fold-gj"]["details"]["fold_gj_nm2"]
    assert set(folds) == {"rigid, frequency spring", "rigid, static spring", "fem-coupled"}


def test_bad_arguments_exit_2():
    with pytest.raises(SystemExit) as exc:
        main(["validate", "--bogus"])
    assert exc.value.code == 2


def test_a_raising_case_is_recorded_as_error(tmp_path, monkeypatch):
    """One case raising must not stop the report: it becomes status 'error' with the message."""
    from amra_core.validation import aero, run_validation

    def boom(k):
        raise RuntimeError("deliberate failure")

    monkeypatch.setattr(aero, "theodorsen_model", boom)
    res = run_validation(tmp_path, quick=True, sections=("aero",))
    by_id = {c.id: c for c in res.cases}
    assert by_id["aero.theodorsen.magnitude"].status == "error"
    assert "deliberate failure" in by_id["aero.theodorsen.magnitude"].note
    assert by_id["aero.table-points.naca0012_critzos"].status == "pass"
    doc = json.loads((tmp_path / "results.json").read_text(encoding="utf-8"))
    assert any(c["status"] == "error" for c in doc["cases"])
    assert (tmp_path / "report.html").is_file()


def test_report_lists_fold_and_flutter_per_column_with_every_interval_strength(quick_report):
    """Issue 21: the validation report gives fold and strong-flutter GJ per column and the strength of
    every flutter interval; the fold GJ rises from CG 0.36 aft."""
    _, out = quick_report
    doc = json.loads((out / "results.json").read_text(encoding="utf-8"))
    by_id = {c["id"]: c for c in doc["cases"]}
    ff = by_id["system.boundary.fold-flutter.rigid.axial"]
    assert "fold" in ff["value"] and "flutter" in ff["value"] and "critical" in ff["value"]
    cols = ff["details"]["columns"]
    assert cols and all({"fold_gj", "flutter_gj", "critical_gj"} <= set(c) for c in cols)
    iv = by_id["system.boundary.intervals.rigid.axial"]
    flutter = [i for c in iv["details"]["columns"] for i in c["intervals"] if i["kind"] == "flutter"]
    assert all(i["strength"] in ("weak", "strong") for i in flutter)
    assert by_id["system.boundary.fold-rises-aft.rigid.axial"]["status"] == "pass"
