"""In the page at 1280x720: the GJ slider's readout runs its JavaScript rule (written out, "1500",
never "1.50e+3") and an out-of-range GJ in presentation mode says so legibly on the dark header
without making the header taller (tests/app/test_view_fixes.py checks the Python side)."""
from __future__ import annotations

import math
import re

import pytest
from playwright.sync_api import expect

from app.inputs import gj_readout
from helpers import open_dashboard, shot, wait_for

pytestmark = pytest.mark.browser
SLIDER_TITLE = "GJ (log scale) [N m²/rad]: "

#: the computed style of an element (in any shadow root) whose class list has ``cls``
JS_STYLE = """([cls, pseudo]) => {
  const find = (root) => {
    for (const el of root.querySelectorAll('*')) {
      if (el.classList && el.classList.contains(cls) && el.getBoundingClientRect().width > 0) return el;
      if (el.shadowRoot) { const f = find(el.shadowRoot); if (f) return f; }
    }
    return null;
  };
  const el = find(document);
  if (!el) return null;
  const cs = getComputedStyle(el, pseudo), r = el.getBoundingClientRect();
  return {color: cs.color, background: cs.backgroundColor, fontSize: cs.fontSize, arrow: cs.borderBottomColor,
          top: r.top, bottom: r.bottom, right: r.right};
}"""


def _rgb(css: str) -> tuple:
    return tuple(int(v) for v in re.findall(r"\d+", css)[:3])


def _contrast(a: tuple, b: tuple) -> float:
    def lum(rgb):
        lin = [c / 255 / 12.92 if c / 255 <= 0.03928 else ((c / 255 + 0.055) / 1.055) ** 2.4 for c in rgb]
        return 0.2126 * lin[0] + 0.7152 * lin[1] + 0.0722 * lin[2]
    hi, lo = sorted((lum(a), lum(b)), reverse=True)
    return (hi + 0.05) / (lo + 0.05)


def test_the_gj_slider_reads_gj_written_out(watched_page, dashboard_url):
    page = watched_page
    page.set_viewport_size({"width": 1280, "height": 720})
    open_dashboard(page, dashboard_url + "?preset=nominal")
    title = page.locator(".amra-gj-slider .bk-slider-title").first
    expect(title).to_have_text(SLIDER_TITLE + "1500")  # the default GJ, on every page
    exact = page.locator(".amra-gj input").first
    for gj_nm2 in (612.0, 30.0, 12.34, 10000.0, 10.0):
        exact.fill(f"{gj_nm2:g}")
        exact.press("Enter")
        expect(title).to_have_text(SLIDER_TITLE + gj_readout(math.log10(gj_nm2)), timeout=30_000)
        assert "e+" not in title.inner_text()
    assert page.amra_errors == []


def test_an_out_of_range_gj_on_the_presentation_header_is_legible(watched_page, dashboard_url):
    """Needs app/app.py's _live_bar to pass ``on_dark=True`` to checked_input."""
    page = watched_page
    page.set_viewport_size({"width": 1280, "height": 720})
    page.goto(dashboard_url + "?preset=nominal&present=true")
    gj = page.locator(".amra-present-gj input")
    expect(gj).to_be_visible(timeout=120_000)
    page.wait_for_timeout(1000)
    header_height_px = page.locator("#header").bounding_box()["height"]
    tab = page.get_by_text("Boundary map", exact=True).first
    tab_top_px = tab.bounding_box()["y"]
    assert tab_top_px < 720  # the views' tabs show at the bottom of a projector's screen
    gj.fill("5")
    gj.press("Enter")
    message = page.get_by_text("GJ [N m²/rad] = 5 is out of range: allowed 10 to 10000").first
    expect(message).to_be_visible(timeout=30_000)
    page.wait_for_timeout(500)
    shot(page, "vf-present-bad-gj-1280x720")
    assert page.locator("#header").bounding_box()["height"] == pytest.approx(header_height_px, abs=1)
    msg = wait_for(lambda: page.evaluate(JS_STYLE, ["amra-msg", None]), 30, what="the message's style")
    assert float(msg["fontSize"].removesuffix("px")) >= 14, msg
    assert _contrast(_rgb(msg["color"]), _rgb(msg["background"])) >= 4.5, msg
    assert msg["right"] <= 1280, msg
    # the input's own text is legible on the dark header (a text input: no spinner arrows to check)
    assert _contrast(_rgb(page.evaluate("e => getComputedStyle(e).color", gj.element_handle())),
                     _rgb(page.evaluate("e => getComputedStyle(e).backgroundColor", gj.element_handle()))) >= 4.5
    assert tab.bounding_box()["y"] == pytest.approx(tab_top_px, abs=1)  # and stay there


def test_an_emptied_gj_input_shows_the_kept_value_not_nan(watched_page, dashboard_url):
    """Cleared and entered, the box read "NaN" beside its message. Letters and a decimal comma are
    refused with a message too (a number input had dropped them as the keys were pressed: "1,5"
    became GJ 15, "abc" nothing, without a word)."""
    page = watched_page
    open_dashboard(page, dashboard_url + "?preset=nominal")
    exact = page.locator(".amra-gj input").first
    for typed, words in (("", "not a number (empty)"), ("1,5", "(write decimals with a point: 1.5)"),
                         ("abc", "'abc' is not a number")):
        exact.fill(typed)
        exact.press("Enter")
        expect(page.get_by_text(words).first).to_be_visible(timeout=30_000)
        expect(exact).to_have_value("1500", timeout=30_000)
    exact.fill("700")
    exact.press("Enter")
    expect(page.get_by_text("is not a number")).to_have_count(0, timeout=30_000)
    expect(exact).to_have_value("700")
    assert page.amra_errors == []


def test_the_modes_tab_draws_a_forward_flight_locus_that_comes_late(watched_page, dashboard_url):
    """fem-coupled at mu 0.3: the tab is drawn before its locus arrives (seconds later); the
    colour-mapped points then threw "invalid color array" on every update."""
    page = watched_page
    open_dashboard(page, dashboard_url + "?mu=0.3&fidelity=fem-coupled")
    page.locator(".bk-tab", has_text="Modes & root locus").first.click()
    # the locus's own summary (not the "computing ..." line before it): it takes seconds, more on a busy machine
    expect(page.get_by_text("no trim (fold) below about").first).to_be_visible(timeout=300_000)
    page.wait_for_timeout(3000)  # the plots' updates after the locus
    assert page.amra_errors == [], f"console errors: {page.amra_errors}"
