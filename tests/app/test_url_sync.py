"""URL round trip: every control survives query_string -> parse -> apply_query; bad values are named."""
from __future__ import annotations

import math

from panel.util import parse_query

from app.controls import Controls
from app.controls import PRESETS
from app.controls import URL_KEYS, apply_query, query_string


def test_every_control_is_in_the_url():
    assert set(URL_KEYS) == set(Controls().values())


def test_round_trip_reopens_exactly_the_same_case():
    a = Controls(preset="fig13")
    a.param.update(gj_nm2=612.5, cg_pct=37.25, speed=2.5, run_s=7.5, map_columns=5, aero="quasi-steady")
    q = parse_query("?" + query_string(a))
    b = Controls()
    assert apply_query(b, q) == []
    assert b.values() == a.values()
    assert b.case() == a.case()


def test_a_link_writes_booleans_as_the_url_sync_does():
    a = Controls()
    a.present = True
    assert "present=true" in query_string(a) and "True" not in query_string(a)


def test_the_preset_is_applied_first_so_explicit_values_win():
    b = Controls()
    fig10 = PRESETS["fig10"].as_dict()
    assert fig10["gj_nm2"] != 250.0
    assert apply_query(b, {"gj": 250.0, "preset": "fig10"}) == []
    assert b.gj_nm2 == 250.0  # the link's explicit value
    assert b.fidelity == fig10["fidelity"] and b.run_s == fig10["run_s"]  # the rest from the preset


def test_bad_values_are_reported_by_name_and_ignored():
    b = Controls()
    msgs = apply_query(b, {"gj": 1e9, "cg": "abc", "mu": float("nan"), "fidelity": "beam", "map_columns": 2.5,
                           "rotor": "uploaded file", "ea": 30.0, "unknown": 1})
    joined = "\n".join(msgs)
    assert len(msgs) == 7
    for key in ("gj", "cg", "mu", "fidelity", "map_columns", "rotor", "unknown"):
        assert f"link parameter {key} =" in joined
    # a key the page does not know is named too (?ea_pct=30 opened at EA 32 without a word)
    assert "link parameter unknown = 1 was ignored: not a parameter of this page (its parameters: preset, rotor, gj," \
        in joined
    assert apply_query(Controls(), {"bokeh-session-id": "x", "theme": "dark"}) == []  # the server's and Panel's
    assert "allowed 10 to 10000" in joined and "rigid, fem-torsion, fem-coupled" in joined
    assert b.ea_pct == 30.0  # the good one is applied
    assert b.gj_nm2 == 1500.0 and b.cg_pct == 40.0 and b.mu == 0.0 and math.isfinite(b.mu)


def test_a_copied_link_reopens_as_the_preset_it_shows():
    """Opened as ?preset=fig10, then Fig. 12 chosen: the URL kept preset=fig10 beside Fig. 12's values,
    and the copied link opened as a custom case without the paper's card."""
    from panel.io.location import Location
    from app.controls import sync_url
    opened = Controls()
    assert apply_query(opened, {"preset": "fig10"}) == []
    loc = Location(search="?preset=fig10")
    sync_url(opened, loc)
    opened.preset = "fig12"
    assert loc.query_params["preset"] == "fig12"
    reopened = Controls()
    assert apply_query(reopened, {k: str(v) for k, v in loc.query_params.items()}) == []
    assert reopened.preset == "fig12" and reopened.values() == opened.values()
    opened.gj_nm2 = 333.0  # an edit leaves the preset: the link says custom, with every value
    assert loc.query_params["preset"] == "custom" and loc.query_params["gj"] == 333.0


def test_a_links_bad_values_are_named_in_the_inputs_words_in_one_message():
    """param's own text leaked ("Number parameter 'Controls.run_s' must be at most 120.0, not
    1000000000.0."), and with seven bad values the alert kept only the last three messages."""
    from app.controls import report_link_errors
    msgs = apply_query(Controls(), {"gj": "abc", "cg": "95", "mu": "-1", "fidelity": "fem", "present": "maybe",
                                    "run_s": "1e9", "map_columns": "2.5"})
    assert len(msgs) == 7
    assert not any("parameter '" in m or "Controls." in m for m in msgs), msgs
    assert "link parameter run_s = '1e9' was ignored: out of range (allowed 0.5 to 120)" in msgs
    assert "link parameter gj = 'abc' was ignored: not a number (allowed 10 to 10000)" in msgs
    assert "link parameter map_columns = '2.5' was ignored: not an integer (allowed 2 to 31)" in msgs
    shown = []
    report_link_errors(msgs, shown.append)
    assert len(shown) == 1 and shown[0].startswith("7 values of this link were ignored")
    assert all(m in shown[0] for m in msgs)


def test_an_edit_that_leaves_a_preset_keeps_the_edited_value():
    """GJ typed over the nominal preset's went back to 1500: leaving the preset wrote the preset to
    the URL inside the edit's own watchers, before Location had written the new GJ, and Location read
    the query back with the old one."""
    from panel.io.location import Location
    from app.controls import sync_url
    c, loc = Controls(preset="nominal"), Location(search="?preset=nominal")
    sync_url(c, location=loc)
    c.gj_nm2 = 700.0
    assert (c.preset, c.gj_nm2) == ("custom", 700.0)
    q = parse_query(loc.search)
    assert q["preset"] == "custom" and q["gj"] == 700.0
    c.preset = "fig12"  # and a preset chosen afterwards sets its values and the URL
    q = parse_query(loc.search)
    assert (c.gj_nm2, c.mu) == (300.0, 0.1) and (q["preset"], q["gj"], q["mu"]) == ("fig12", 300.0, 0.1)
