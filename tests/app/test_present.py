"""Presentation mode (issue 23 §2): a link flag and a toggle; taller plots and larger fonts, the
status row steps aside for a header with Run, Stop, a large GJ input and the verdict."""
from __future__ import annotations

import holoviews as hv

from app.live import NORMAL_HEIGHT, PRESENT_HEIGHT
from app.controls import apply_query


def test_the_toggle_switches_the_page(dash):
    hv.extension("bokeh")
    page = dash.__panel__()  # builds the header and the main area
    assert not dash.controls.present and dash.top.visible
    assert dash.live_bar is None and len(page.header[0]) == 1  # the live bar is made when first shown
    assert all(f.height == NORMAL_HEIGHT for f in dash.live.figures_made)
    dash.controls.present = True
    assert not dash.top.visible
    assert all(f.height == PRESENT_HEIGHT and f.title.text_font_size == "18px" for f in dash.live.figures_made)
    header_bar = page.header[0][1]
    assert header_bar.visible
    dash.controls.present = False
    assert dash.top.visible and not header_bar.visible


def test_the_link_flag(dash):
    hv.extension("bokeh")
    assert apply_query(dash.controls, {"present": "true"}) == []
    assert dash.controls.present
    assert apply_query(dash.controls, {"present": "maybe"}) == ["link parameter present = 'maybe' was ignored: "
                                                                "not true or false"]
    page = dash.__panel__()
    assert page.collapsed_sidebar and not dash.top.visible
