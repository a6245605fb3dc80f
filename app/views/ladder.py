"""The fidelity ladder (the paper's central comparison): the same case at rigid, fem-torsion and
fem-coupled, run side by side (unpaced, in the analysis pool: :func:`app.compute.run_ladder`) and
overlaid, with each run's verdict; and the previous run overlaid (dashed) on the one that just
finished."""
from __future__ import annotations

import holoviews as hv
import numpy as np
import pandas as pd
import panel as pn
from holoviews.streams import Pipe

from amra_core.shapes import FIDELITIES

from ..compute import ladder_curves
from ..events import Finished, Ladder
from ..live import UNITS
from . import FIDELITY_COLOURS, Dim

DIMS = {c: Dim(c, label=name, unit=unit) for c, (name, unit) in UNITS.items()}
COLOURS = {**FIDELITY_COLOURS, "previous run": "#9e9e9e", "last run": "#1f77b4"}
COMPARED = ("previous run", "last run")
#: (curve of app.compute.ladder_curves, y dimension, title) of each plot
PLOTS = (("omega", DIMS["omega_rad_s"], "Rotor speed"), ("teeter_deg", DIMS["teeter_deg"], "Teeter"),
         ("twist_deg", DIMS["twist0_deg"], "Tip twist, blade 0"))


class LadderView(pn.viewable.Viewer):
    def __init__(self, session, **params):
        super().__init__(**params)
        self.pipe = Pipe(data={})
        self.table = pn.pane.DataFrame(pd.DataFrame(), index=False, sizing_mode="stretch_width", name="ladder-table")
        self.info = pn.pane.Markdown("Press **Run fidelity ladder** to run the current case at the three "
                                     "fidelities.", name="ladder-info")
        self.compare_pipe = Pipe(data={})
        self.previous = None  #: the last finished run's history
        self.case_text = ""  #: what the ladder runs, in words (:func:`app.app.ladder_case_text`)
        session.subscribe(Ladder, lambda ev: self.show(ev.result))
        session.subscribe(Finished, self._finished)

    def _finished(self, ev: Finished) -> None:
        if len(ev.history):
            self.compare(self.previous, ev.history)
            self.previous = ev.history

    def compare(self, previous, current) -> None:
        """Overlay the previous run on the one that just finished (histories, ``HISTORY_COLUMNS``)."""
        self.compare_pipe.send({label: ladder_curves(h) for label, h in zip(COMPARED, (previous, current))
                                if h is not None and len(h)})

    def running(self, case_text: str) -> None:
        self.case_text = case_text
        self.info.object = f"Running the case ({case_text}) at rigid, fem-torsion and fem-coupled ..."

    def show(self, result: dict) -> None:
        self.info.object = f"Fidelity ladder: the current case ({self.case_text}) at the three fidelities."
        self.pipe.send(result["runs"])
        self.table.object = verdict_table(result["verdicts"])

    def _plot(self, runs, key, dim, title, labels=FIDELITIES):
        # the same layers every time, empty where a run is missing (a DynamicMap draws only the layers
        # of its first overlay)
        layers = []
        for fid in labels:
            r = runs.get(fid)
            data = (r["t"], r[key]) if r is not None else ([], [])
            layers.append(hv.Curve(data, DIMS["t_s"], dim, label=fid).opts(
                color=COLOURS[fid], line_width=2, line_dash="dashed" if fid == "previous run" else "solid",
                framewise=True))  # each new set of runs sets the axes (framewise is an element option)
        # at 1280x720 a plot is ~287 px wide: a short title (the row's heading says what is compared)
        # and the legend under the axes, one entry a line, clear of the curves
        return hv.Overlay(layers).opts(title=title, responsive=True, height=340, show_grid=True,
                                       legend_position="bottom", legend_cols=1, framewise=True,
                                       legend_opts={"margin": 0, "padding": 4, "spacing": 0})

    def __panel__(self):
        def plots(pipe, labels):
            return pn.Row(*[pn.pane.HoloViews(hv.DynamicMap(
                lambda data, p=p: self._plot(data, p[0], p[1], p[2], labels), streams=[pipe]),
                sizing_mode="stretch_width", linked_axes=False) for p in PLOTS])  # each row its own runs
        return pn.Column(
            pn.pane.Markdown("### Previous run vs last run (overlaid when a run finishes)"),
            plots(self.compare_pipe, COMPARED),
            pn.pane.Markdown("### Fidelity ladder: the same case at the three fidelities"),
            self.info, self.table, plots(self.pipe, FIDELITIES), sizing_mode="stretch_width")


def _num(x, unit: str = "") -> str:
    return "—" if x is None or not np.isfinite(x) else f"{x:.3g}{unit}"


def verdict_table(rows) -> pd.DataFrame:
    """The ladder's verdicts, numbers to 3 significant digits, "—" where there is none."""
    return pd.DataFrame([(fid, verdict, _num(g), _num(f), _num(c), text) for fid, verdict, g, f, c, text in rows],
                        columns=["fidelity", "verdict", "growth rate [1/s]", "frequency [Hz]", "collapse time [s]",
                                 "explanation"])
