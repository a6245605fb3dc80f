"""Classroom view: the fan (Southwell/Campbell) plot of the tracked in-vacuo modes against rotor
speed (paper Figs 6-7), per-rev lines dashed, the current rotor speed marked. From
``amra_core.modes.fan_plot``."""
from __future__ import annotations

import holoviews as hv
import numpy as np
import panel as pn
from holoviews.streams import Pipe, Stream

from amra_core.simulation import COL

from ..compute import FAN_OMEGA_MAX as OMEGA_MAX
from ..events import Fan, Rows
from ..throttle import Throttle

OMEGA_DIM = hv.Dimension("omega_rad_s", label="Rotor speed Ω", unit="rad/s")
F_DIM = hv.Dimension("frequency_hz", label="Natural frequency", unit="Hz")

MARK_PERIOD_S = 1.0  #: wall-clock period of the current-speed marker's moves [s]

Omega = Stream.define("Omega", omega=0.0)


class FanView(pn.viewable.Viewer):
    def __init__(self, session, doc=None, **params):
        super().__init__(**params)
        self.pipe = Pipe(data={})
        self.omega = Omega()
        self._omega_now = 0.0
        self.marker = Throttle(self._move, MARK_PERIOD_S, doc)  # each move re-renders the plot
        session.subscribe(Fan, lambda ev: self.pipe.send(ev.result))
        session.subscribe(Rows, self._rows)

    def _rows(self, ev: Rows) -> None:
        if len(ev.rows):
            self._omega_now = float(ev.rows[-1, COL["omega_rad_s"]])
            self.marker.kick()

    def _move(self) -> None:
        if abs(self._omega_now - self.omega.omega) > 0.05:
            self.omega.event(omega=self._omega_now)

    def _plot(self, data):
        layers = []
        om = np.linspace(0, OMEGA_MAX, 2)
        for k in range(1, 7):
            layers.append(hv.Curve((om, k * om / (2 * np.pi)), OMEGA_DIM, F_DIM).opts(
                color="#bbbbbb", line_dash="dashed", line_width=1))
        for label, f in data.get("modes", []):
            layers.append(hv.Curve((data["omega"], f), OMEGA_DIM, F_DIM, label=label).opts(line_width=2))
        return hv.Overlay(layers)

    def __panel__(self):
        fan = hv.DynamicMap(self._plot, streams=[self.pipe])
        mark = hv.DynamicMap(lambda omega: hv.VLine(omega).opts(color="red", line_width=2), streams=[self.omega])
        plot = (fan * mark).opts(hv.opts.Overlay(title="Fan plot: in-vacuo modes vs rotor speed (dashed: 1-6 per rev; "
                                                       "red: current Ω)", responsive=True, height=380, show_grid=True,
                                                 legend_position="right", ylim=(0, 40), xlim=(0, OMEGA_MAX)))
        return pn.pane.HoloViews(plot, sizing_mode="stretch_width")
