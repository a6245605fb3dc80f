"""Every axis of every view writes its unit the same way, in brackets ("Frequency [Hz]"), as the
live plots, the map and the controls do; HoloViews' default "(Hz)" had crept into four views."""
from __future__ import annotations

import re

import panel as pn
from bokeh.document import Document
from bokeh.models import Axis

#: an axis label ending in a parenthesised unit
PAREN_UNIT = re.compile(r"\((s|Hz|deg|rad|rad/s|1/s|m|m/s|N m²/rad)\)\s*$")


def _axis_labels(viewable) -> list:
    root = pn.panel(viewable).get_root(Document())
    return [a.axis_label for a in root.select({"type": Axis}) if a.axis_label]


def test_the_views_axes_write_units_in_brackets(dash):
    labels = []
    for view in (dash.modes, dash.fan, dash.ladder, dash.disc, dash.rotor_view, dash.live.figures()[0]):
        labels += _axis_labels(view)
    assert len(labels) >= 12, labels
    assert not [lb for lb in labels if PAREN_UNIT.search(lb)], labels
    assert {"Time [s]", "Frequency [Hz]", "Rotor speed Ω [rad/s]"} <= set(labels), labels
