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


def test_the_live_plots_y_labels_fit_their_height(dash):
    """At 13 px a label of more than 18 characters is taller than a 220 px live plot's frame: "Rotor
    speed Ω [rad/s]" (21) showed as "otor speed Ω [rad/s]" ("Descent rate [m/s]", 18, fits)."""
    from app.live import NORMAL_HEIGHT
    labels = []
    for fig in dash.live.figures():
        assert fig.height == NORMAL_HEIGHT == 220
        labels += [ax.axis_label for ax in fig.left if ax.axis_label]
    assert len(labels) == 4 and "Ω [rad/s]" in labels, labels
    assert max(len(lb) for lb in labels) <= 18, labels
