"""Classroom view: the fan (Southwell/Campbell) plot of the tracked in-vacuo modes against rotor
speed (paper Figs 6-7), per-rev lines dashed, the current rotor speed marked. From
``amra_core.modes.fan_plot``; the marker moves once a second during a run."""
from __future__ import annotations

import holoviews as hv
import numpy as np
import panel as pn
from holoviews.streams import Pipe, Stream

from ..compute import FAN_OMEGA_MAX as OMEGA_MAX
from ..events import Fan, Modes, RunStatus
from . import Dim

OMEGA_DIM = Dim("omega_rad_s", label="Rotor speed Ω", unit="rad/s")
F_DIM = Dim("frequency_hz", label="Natural frequency", unit="Hz")

Omega = Stream.define("Omega", omega=0.0)


class FanView(pn.viewable.Viewer):
    def __init__(self, session, **params):
        super().__init__(**params)
        self.pipe = Pipe(data={})
        self.omega = Omega()
        session.subscribe(Fan, lambda ev: self.pipe.send(ev.result))
        session.subscribe(RunStatus, lambda ev: self._move(ev.omega_rad_s))  # once a second while a run runs
        # before any run, the current case's trim (the marker sat at 0 rad/s until a run)
        session.subscribe(Modes, lambda ev: self._move(ev.result.get("omega_rad_s")))

    def _move(self, omega_rad_s) -> None:
        if omega_rad_s is not None and abs(omega_rad_s - self.omega.omega) > 0.05:
            self.omega.event(omega=omega_rad_s)  # each move re-renders the plot

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
