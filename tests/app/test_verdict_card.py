"""The verdict card says what a missing number means (a stable run's drift has no frequency)."""
from __future__ import annotations

from amra_core.verdict import Verdict
from app.views.status import verdict_html


def test_a_run_without_a_resolved_oscillation_says_so():
    html = verdict_html(Verdict("stable", -0.55, None, None, explanation="the perturbation decays"), True)
    assert "none resolved" in html and "0.1 Hz" not in html
    # beside a forward-flight run's visible 1/rev teeter, the card says that motion is the trim's own;
    # it claims no "drift from the trim", false beside a collapse far from any trim (Fig. 10) and
    # beside a stable run's decay: what it says is what the frequency analysis found
    assert "none resolved: the largest deviation is a one-way change (1/rev is the trim's own)" in html
    assert "drift" not in html
    # and in few words: at 138 characters the card's row was six lines tall at 1280 x 720
    from app.views.status import _frequency
    assert len(_frequency(Verdict("stable", -0.55, None, None))) <= 90


def test_a_resolved_frequency_is_shown_with_its_unit():
    html = verdict_html(Verdict("flutter", 0.4, 12.04, None, explanation="growing oscillation"), True)
    assert "12 Hz" in html


def test_no_data_yet_is_a_dash_not_a_claim():
    html = verdict_html(Verdict("undetermined", None, None, None, explanation="no data yet"), False)
    assert "none resolved" not in html and "—" in html


def test_a_negative_growth_rate_on_an_unstable_verdict_is_not_read_as_a_decay():
    """fig 12 reads divergence with -0.94 1/s: the rotor speed collapses under a decaying oscillation."""
    html = verdict_html(Verdict("divergence", -0.94, None, 3.1, explanation="rotor speed collapsed"), True)
    assert "-0.94 1/s (the oscillation on top decays; the divergence is the instability)" in html
    stable = verdict_html(Verdict("stable", -0.55, 12.0, None, explanation="the perturbation decays"), True)
    assert "-0.55 1/s</b>" in stable and "instability" not in stable


def test_the_case_line_breaks_between_fields_never_inside_one():
    """The card's case line wrapped "μ" onto one line and its "0" onto the next."""
    from app.app import case_label
    from app.controls import Controls
    c = Controls()
    line = case_label(c, c.scenario())
    fields = line.split(" · ")
    assert fields[-1] == "μ\u00a00" and f"CG\u00a0{c.cg_pct:g}\u00a0%" in fields
    assert all(" " not in f for f in fields[1:])  # breakable only at the separators (and in the rotor's name)


def test_the_solvers_units_are_written_as_the_page_writes_them():
    html = verdict_html(Verdict("divergence", 0.1, None, 3.0, explanation="since the change to GJ 300 N m^2/rad"), True)
    assert "GJ 300 N m²/rad" in html and "m^2" not in html


def test_the_presentation_badge_names_the_gj_its_verdict_was_found_at(dash):
    """In presentation mode the card is hidden: a class read "stable (final)" beside the header's GJ
    input as the verdict of the GJ 300 typed after a run at GJ 1500. The badge names the run's GJ,
    from its start (the nominal blade before a softening) to its last scripted or live change."""
    from app.events import Applied
    dash.controls.preset = "fig10"
    assert dash.start_run()
    dash.session.stop()
    status = dash.status
    assert status.gj_nm2 == 1500.0  # Fig. 10 starts from the nominal blade
    final = Verdict("stable", -0.55, None, None, explanation="the perturbation decays")
    status.show(final, True)
    assert "(final)<br>at GJ 1500 N m²/rad" in status.badge.value
    status._applied(Applied(dash.session.run_id, {"gj_nm2": 100.0, "scripted": True}, 2.0))
    status.show(Verdict("divergence", 0.1, None, 3.4, explanation="collapse"), True)
    assert "(final)<br>at GJ 100 N m²/rad · Ω collapsed at 3.4 s" in status.badge.value
    dash.controls.gj_nm2 = 300.0  # typed after the run: the badge still names the run's GJ
    assert "GJ 100 N m²/rad" in status.badge.value and "300" not in status.badge.value


def test_a_runaway_outcome_says_what_ran_away():
    """ "Outcome runaway" on a rotor slowing after a live change read as a rotor running away
    upwards; the card says what the outcome means."""
    html = verdict_html(Verdict("flutter", 0.3, 8.2, None, explanation="growing oscillation", outcome="runaway"), True)
    assert "still growing or leaving its start at the end of the run (runaway)" in html
    assert "bounded oscillation" in verdict_html(Verdict("flutter", 0.0, 8.2, None, explanation="limit cycle",
                                                         outcome="bounded-oscillation"), True)


def test_the_card_and_the_map_name_their_growth_rates_apart():
    """A map cell at +0.971 1/s (eigenvalue) ran as a limit cycle with "Growth rate 0.0186 1/s" on the
    card: one label for two numbers 50 times apart. Each is named for what it is."""
    html = verdict_html(Verdict("flutter", 0.0186, 10.1, None, explanation="limit cycle", outcome="bounded-oscillation"),
                        True)
    assert "Growth rate (run's fit)" in html
    # the map's hover says "growth rate (eigenvalue)" (tests/app/test_view_fixes.py), the Help tab why
    from app.controls import Controls
    from app.views.help import help_pane
    assert "Two growth rates" in help_pane(Controls()).object


def test_the_cards_case_names_every_live_change_of_the_run():
    """After GJ 300, CG 43 % and EA 30 % the card named only the last ("live at 15.15 s: EA 30 %") over a
    collapse that GJ 300 had started at 6.85 s."""
    from types import SimpleNamespace
    from app.events import Applied, Started
    from app.views.status import StatusView
    handlers = {}
    view = StatusView(SimpleNamespace(subscribe=lambda kind, fn: handlers.setdefault(kind, fn)), lambda *a: None)
    view.case = "paper-boundary · rigid · GJ 1500 N m²/rad"
    handlers[Started](SimpleNamespace(start_note="started from the trim"))
    handlers[Applied](Applied(1, {"gj_nm2": 300.0}, 6.85))
    handlers[Applied](Applied(1, {"x_cg": 0.43}, 11.2))
    handlers[Applied](Applied(1, {"x_ea": 0.30}, 15.15))
    assert view.case == ("paper-boundary · rigid · GJ 1500 N m²/rad · live: GJ 300 N m²/rad at 6.85 s; "
                         "CG 43 % at 11.20 s; EA 30 % at 15.15 s")
    handlers[Started](SimpleNamespace(start_note="started from the trim"))  # a new run starts without them
    assert view.live_changes == []
