"""Stability at a glance: the trimmed state's modes (table) and the root locus over GJ.

The table lists the eigenvalues (axial) or Floquet exponents (forward) of the current case, from
``amra_core.stability.analyse``; the root locus plots the modes of :func:`app.compute.locus_result` along GJ
for the current CG, coloured by GJ, the current GJ marked, and beside it the largest real part
against GJ, so the flutter crossing (real part through zero) or the fold (the trim branch ends)
is visible before any run.
"""
from __future__ import annotations

import math

import holoviews as hv
import numpy as np
import pandas as pd
import panel as pn
from holoviews.streams import Pipe, Stream

from ..compute import LOCUS_GJ_RANGE
from ..events import Locus, ModeFrames, Modes
from . import Dim
from .rotor import ModeAnimation
from .status import units_as_shown

MODE_COLUMNS = ["mode", "frequency [Hz]", "damping ratio [-]", "real part [1/s]", "stable"]
GJ_DIM = Dim("gj_nm2", label="GJ", unit="N m²/rad")
RE_DIM = Dim("re", label="Real part σ", unit="1/s")
F_DIM = Dim("f_hz", label="Frequency", unit="Hz")
#: GJ ticks [N m²/rad] of the log axis (Bokeh's own put 2000 and 2500 on top of each other)
GJ_TICKS = [50, 100, 200, 500, 1000, 3000]
LOG_GJ_DIM = Dim("log_gj", label="log10 GJ", unit="N m²/rad")
CurrentGJ = Stream.define("CurrentGJ", gj=1500.0)


def modes_frame(modes, shown: bool = True) -> pd.DataFrame:
    """The mode table (aero-lag modes left out): label, frequency [Hz], damping ratio, real part [1/s];
    rounded as the page shows it, or (``shown=False``) at full precision, for the export (its file had
    a frequency of 0.003 Hz: the README promises 8 significant digits)."""
    r = (lambda x, n: round(x, n)) if shown else (lambda x, n: float(x))
    rows = [(m.label, r(m.frequency_hz, 3), r(m.damping_ratio, 4), r(m.real_part_per_s, 4),
             "yes" if m.real_part_per_s < 1e-3 else "NO") for m in modes if m.label != "aero lag"]
    return pd.DataFrame(rows, columns=MODE_COLUMNS)


def gj_colours(gj_nm2: np.ndarray) -> list:
    """Viridis colours of GJ [N m²/rad] on a log scale over the locus's range (purple: soft, yellow: stiff)."""
    from bokeh.palettes import Viridis256
    lo, hi = (math.log10(g) for g in LOCUS_GJ_RANGE)
    x = np.clip((np.log10(np.asarray(gj_nm2, dtype=float)) - lo) / (hi - lo), 0.0, 1.0)
    return [Viridis256[int(round(v * 255))] for v in x]


def locus_frame(points) -> pd.DataFrame:
    rows = [(p.gj_nm2, math.log10(p.gj_nm2), m.real_part_per_s, m.frequency_hz, m.label)
            for p in points for m in p.modes]
    return pd.DataFrame(rows, columns=["gj_nm2", "log_gj", "re", "f_hz", "label"])


def critical_frame(points) -> pd.DataFrame:
    rows = [(p.gj_nm2, p.max_real_part_per_s if p.trimmed else np.nan) for p in sorted(points, key=lambda p: p.gj_nm2)]
    return pd.DataFrame(rows, columns=["gj_nm2", "re"])


class ModesView(pn.viewable.Viewer):
    def __init__(self, session, **params):
        super().__init__(**params)
        self.frame = self.full_frame = modes_frame([])
        self.about: dict = {}  #: the trim and method of the table (set with it)
        self.table = pn.pane.DataFrame(self.frame, index=False, sizing_mode="stretch_width", max_height=320,
                                       name="mode-table")
        self.info = pn.pane.Markdown("Modes of the trim: computing ...", name="modes-info")
        self.locus_info = pn.pane.Markdown("Root locus: computing ...", name="locus-info")
        self.points_pipe = Pipe(data=[])  #: the locus points (app.compute.locus_result)
        self.current = CurrentGJ()
        #: pick a mode to watch its shape; ``on_pick(real_part_per_s, frequency_hz, label)`` computes it
        self.pick = pn.widgets.Select(label="Watch a mode's shape", options={"(choose a mode)": None},
                                      sizing_mode="stretch_width", css_classes=["amra-mode-pick"])
        self.animation = ModeAnimation()
        self.on_pick = None
        self.pick.param.watch(self._picked, "value")
        session.subscribe(ModeFrames, lambda ev: self.animation.load(ev.result))
        session.subscribe(Modes, lambda ev: self.show_modes(ev.result))
        session.subscribe(Locus, lambda ev: self.show_locus(ev.result["points"], ev.result["text"]))

    # -- updates (event loop)
    def show_modes(self, result: dict) -> None:
        modes = result.get("modes", [])
        #: what the table is of, for its export (the page says it above the table)
        self.about = {"trim_omega_rad_s": result.get("omega_rad_s"), "trim_descent_rate_m_s": result.get("descent_rate_m_s"),
                      "method": result.get("method", "none (no trim)"), "stable": result.get("stable")}
        self.frame = modes_frame(modes)
        self.full_frame = modes_frame(modes, shown=False)  #: what the export writes
        self.table.object = self.frame
        self.info.object = units_as_shown(result.get("text", ""))
        # no trim, no modes: the select said "(choose a mode)" over nothing (Fig. 10 at GJ 100)
        options = {"(choose a mode)" if modes else "(no modes: this case has no trim)": None}
        if not modes:
            self.animation.info.object = "No modes to watch: this case has no trimmed autorotation."
        elif self.animation.info.object.startswith("No modes"):
            self.animation.info.object = "Pick a mode to watch its shape."
        for m in modes:
            if m.label != "aero lag":
                key = f"{m.label}, {m.frequency_hz:.3g} Hz, σ {m.real_part_per_s:+.3g} 1/s"
                digits = 4
                while key in options and digits < 12:  # two close rows were one option: one could not be picked
                    key = f"{m.label}, {m.frequency_hz:.{digits}g} Hz, σ {m.real_part_per_s:+.{digits}g} 1/s"
                    digits += 1
                options[key] = (m.real_part_per_s, m.frequency_hz, m.label)
        self.pick.options = options

    def _picked(self, event) -> None:
        if event.new is not None and self.on_pick is not None:
            self.animation.info.object = "Computing the mode's shape ..."
            self.on_pick(*event.new)

    @property
    def points(self) -> list:
        return self.points_pipe.data

    def show_locus(self, points, text: str) -> None:
        self.points_pipe.send(points)
        self.locus_info.object = text

    def set_gj(self, gj: float) -> None:
        self.current.event(gj=float(gj))

    # -- plots
    def _locus(self, data, gj):
        data = locus_frame(data)
        # each point's colour computed here, on one GJ scale for every case (the locus's range): a
        # colour-mapped column failed in the browser for fem-coupled forward flight ("invalid color
        # array" on every update, both plots left empty)
        data = data.assign(colour=gj_colours(data["gj_nm2"].to_numpy()))
        pts = hv.Points(data, [RE_DIM, F_DIM], [LOG_GJ_DIM, "label", GJ_DIM, "colour"]).opts(
            color="colour", size=7, tools=["hover"], framewise=True)
        near = data.iloc[0:0]
        if len(data):
            g = data["gj_nm2"].unique()
            near = data[data["gj_nm2"] == g[np.argmin(np.abs(np.log(g) - math.log(gj)))]]
        # its GJ in the hover and the legend's words: at Fig. 10's GJ 100 (no trim) it circled the modes of
        # GJ 424, which read as the current case's
        cur = hv.Points(near, [RE_DIM, F_DIM], ["label", GJ_DIM], label="nearest sampled GJ with a trim").opts(
            marker="circle", size=13, fill_alpha=0, line_color="red", line_width=2)
        return (pts * cur * hv.VLine(0.0).opts(color="black", line_dash="dashed")).opts(
            title="Root locus over GJ, current CG (colour: GJ, purple 50 to yellow 3000 N m²/rad)", responsive=True,
            height=300, show_grid=True, legend_position="top_left", framewise=True)

    def _critical(self, data, gj):
        data = critical_frame(data)
        # framewise: the axes follow each new locus (rendered before the first one arrived, as a slow
        # fem-coupled forward-flight locus does, the plots kept their empty 0..1 ranges and looked empty)
        curve = hv.Curve(data, [GJ_DIM], [RE_DIM], label="largest real part").opts(logx=True, framewise=True)
        dots = hv.Scatter(data, [GJ_DIM], [RE_DIM]).opts(size=6, logx=True, framewise=True)
        return (curve * dots * hv.HLine(0.0).opts(color="black", line_dash="dashed")
                * hv.VLine(gj).opts(color="red")).opts(
            title="Least-damped mode vs GJ (gaps: no trim)", responsive=True, height=300, show_grid=True,
            logx=True, legend_position="top_left", xticks=GJ_TICKS, framewise=True)

    def __panel__(self):
        locus = hv.DynamicMap(self._locus, streams=[self.points_pipe, self.current])
        crit = hv.DynamicMap(self._critical, streams=[self.points_pipe, self.current])
        return pn.Column(
            pn.Row(pn.Column(self.info, self.table, sizing_mode="stretch_width"),
                   pn.pane.HoloViews(crit, sizing_mode="stretch_width", linked_axes=False), sizing_mode="stretch_width"),
            pn.Card(self.pick, self.animation, title="Watch a mode", sizing_mode="stretch_width"),
            # each plot its own σ range: linked by their shared dimension, the least-damped plot spanned
            # the locus's -50 .. 0 1/s and its zero crossing (data -0.56 .. +0.97) could not be read
            self.locus_info, pn.pane.HoloViews(locus, sizing_mode="stretch_width", linked_axes=False),
            sizing_mode="stretch_width")
