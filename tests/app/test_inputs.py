"""Every bad value gets a visible message next to its control, naming the allowed range, and the
session keeps working (issue 23 §5); tooltips state unit and range."""
from __future__ import annotations

import html

import pytest

from app.controls import Controls
from app.inputs import checked_input, tooltip


@pytest.mark.parametrize("name, bad, fragment", [
    ("gj_nm2", "0", "GJ [N m²/rad] = 0 is out of range: allowed 10 to 10000"),
    ("gj_nm2", "1e9", "GJ [N m²/rad] = 1e+09 is out of range: allowed 10 to 10000"),
    ("gj_nm2", "", "GJ [N m²/rad]: not a number (empty); allowed 10 to 10000"),
    ("gj_nm2", "nan", "is not a finite number"),
    # what a number input dropped as keys were pressed, without a word ("1,5" became 15, "abc" nothing)
    ("gj_nm2", "1,5", "GJ [N m²/rad]: '1,5' is not a number (write decimals with a point: 1.5); allowed 10 to 10000"),
    ("gj_nm2", "12abc", "GJ [N m²/rad]: '12abc' is not a number; allowed 10 to 10000"),
    ("run_s", "ten", "Run length [s]: 'ten' is not a number; allowed 0.5 to 120"),
    ("run_s", "-5", "Run length [s] = -5 is out of range: allowed 0.5 to 120"),
    ("run_s", "1000", "Run length [s] = 1000 is out of range"),
    ("speed", "0", "Playback [sim s per s] = 0 is out of range: allowed 0.1 to 50"),
    ("map_columns", "9.5", "Map CG columns = 9.5 is not a whole number; allowed 2 to 31"),
    ("map_columns", "inf", "Map CG columns: inf is not a finite number"),
    ("map_columns", "nan", "Map CG columns: nan is not a finite number"),
])
def test_a_bad_value_is_named_and_the_control_keeps_its_value(name, bad, fragment):
    c = Controls()
    before = getattr(c, name)
    box = checked_input(c, name)
    (widget,) = box.objects  # no message line until there is a message (one model less per input)
    widget.value = bad
    assert getattr(c, name) == before
    widget, message = box.objects
    assert message.visible and html.escape(fragment) in message.object, message.object
    good = {"gj_nm2": "250", "run_s": "4", "speed": "2.5", "map_columns": "12"}[name]
    widget.value = good  # the next good value applies and clears the message
    assert getattr(c, name) == float(good) and not message.visible
    assert type(getattr(c, name)) is type(before)  # an Integer parameter gets an int


def test_an_input_that_is_not_a_number_shows_the_kept_value_and_says_why():
    """Cleared, the box showed "NaN" beside its message; letters and a decimal comma are refused the
    same way, the box showing the value kept (a number out of range stays shown, with its message)."""
    c = Controls()
    box = checked_input(c, "gj_nm2")
    for typed in ("", "abc", "1,5"):
        box.objects[0].value = typed
        widget, message = box.objects
        assert widget.value == "1500" and c.gj_nm2 == 1500.0  # the kept value, not NaN
        assert message.visible and "not a number" in message.object
    widget.value = "700"
    assert c.gj_nm2 == 700.0 and not message.visible
    widget.value = "5"
    assert widget.value == "5" and c.gj_nm2 == 700.0 and message.visible


def test_a_value_set_elsewhere_shows_in_the_input_without_a_message():
    c = Controls()
    box = checked_input(c, "gj_nm2")
    box.objects[0].value = "0"
    widget, message = box.objects
    assert message.visible
    c.gj_nm2 = 412.5  # e.g. the log slider or a map click
    assert widget.value == "412.5" and not message.visible and c.gj_nm2 == 412.5


def test_the_soften_time_must_lie_inside_the_run():
    c = Controls(preset="fig10")
    c.soften_at_s = 30.0
    with pytest.raises(ValueError, match="soften at = 30 s is not allowed: must be shorter than the run length"):
        c.scenario()


@pytest.mark.parametrize("name", ["gj_nm2", "ea_pct", "cg_pct", "mu", "run_s", "speed", "soften_at_s"])
def test_tooltips_state_unit_and_range(name):
    text = tooltip(Controls.param[name])
    assert "[" in text and "Allowed:" in text


def test_help_explains_every_verdict_and_links_the_sources():
    from amra_core.verdict import VERDICTS
    from app.views.help import PAPER_URL, REPORT_URL, help_markdown
    text = help_markdown(Controls())
    for v in VERDICTS:
        assert f"**{v}" in text or f"/ {v}**" in text, v
    assert "Why a growth rate can be negative" in text
    assert PAPER_URL in text and REPORT_URL in text
    assert "GJ [N m²/rad]" in text and "Allowed: 10 to 10000" in text


def test_help_tables_render_as_tables():
    """The verdicts, the map classes and the controls are three tables, every row a table row, no
    pipe left as text (a blank line between a table's header and its rows printed them as text)."""
    from markdown_it import MarkdownIt

    from app.views.help import MAP_CLASSES, VERDICTS, help_markdown
    html = MarkdownIt("commonmark").enable("table").render(help_markdown(Controls()))
    assert html.count("<table>") == 3
    assert html.count("<tr>") == 3 + len(VERDICTS) + len(MAP_CLASSES) + 10  # headers, verdicts, classes, controls
    assert "|" not in html.replace("<td>", "").split("<h3>Why")[0], "a table's pipes printed as text"
