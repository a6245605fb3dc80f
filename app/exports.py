"""CSV exports that stand alone (time histories, mode table, map) as ``FileDownload`` buttons; plots
are saved as PNG with each plot's Bokeh save tool.

Every file is named after its case (``amra-fig10-rigid-gj100-cg40-history.csv``) and starts with
``#`` lines giving the case's parameters in the page's units and the solver version
(:mod:`amra_core.export`); numbers have 8 significant digits.
"""
from __future__ import annotations

import io
from typing import Callable

import numpy as np
import pandas as pd
import panel as pn

from amra_core.export import case_meta, file_name, table_csv
from amra_core.simulation import HISTORY_COLUMNS


def history_csv(sim, history: np.ndarray | None = None, verdict: str | None = None) -> io.StringIO:
    """The full-resolution history of ``sim`` (a Simulation; ``history`` overrides its rows):
    columns :data:`HISTORY_COLUMNS` (SI units in the names), the case and its changes above."""
    h = history if history is not None else (sim.history if sim is not None else np.zeros((0, len(HISTORY_COLUMNS))))
    meta = case_meta(sim.case, [what for _, _, what in sim.changes], verdict) if sim is not None else {}
    return io.StringIO(table_csv(HISTORY_COLUMNS, h, meta))


def frame_csv(frame: pd.DataFrame, meta: dict) -> io.StringIO:
    """A table (columns with units in their names) with the case in ``#`` lines above."""
    return io.StringIO(table_csv(list(frame.columns), frame.itertuples(index=False), meta))


def controls_meta(c) -> dict:
    """The case of the controls, in the page's units."""
    return {"preset": c.preset, "rotor": c.rotor, "gj_nm2": float(c.gj_nm2), "ea_pct_chord": float(c.ea_pct),
            "cg_pct_chord": float(c.cg_pct), "mu": float(c.mu), "airspeed_m_s": float(c.airspeed_m_s),
            "fidelity": c.fidelity, "aero": c.aero, "inflow": c.inflow}


def names_for(c) -> dict:
    """File names of the three exports for the controls' case."""
    case = c.preset if c.preset != "custom" else c.rotor
    common = dict(case=case, fidelity=c.fidelity, gj_nm2=float(c.gj_nm2), cg_pct=float(c.cg_pct), mu=float(c.mu))
    return {"history": file_name("history", **common), "modes": file_name("modes", **common),
            "map": file_name("map", case=case, fidelity=c.fidelity, mu=float(c.mu))}


def download(label: str, filename: str, callback: Callable[[], io.StringIO], css: str) -> pn.widgets.FileDownload:
    return pn.widgets.FileDownload(callback=callback, filename=filename, label=label, button_type="default",
                                   sizing_mode="stretch_width", css_classes=[css])


class ExportBar:
    """The three download buttons; :meth:`rename` names them after a case."""

    def __init__(self, history: Callable, modes: Callable, cells: Callable):
        self.buttons = {"history": download("Time histories (CSV)", "amra-history.csv", history, "amra-export-history"),
                        "modes": download("Mode table (CSV)", "amra-modes.csv", modes, "amra-export-modes"),
                        "map": download("Boundary map (CSV)", "amra-map.csv", cells, "amra-export-map")}

    def rename(self, names: dict) -> None:
        for key, name in names.items():
            self.buttons[key].filename = name

    def panel(self) -> pn.Column:
        return pn.Column(pn.pane.Markdown("**Exports** (CSV with the case in its header; each plot's toolbar has "
                                          "a PNG save button)"), *self.buttons.values(), sizing_mode="stretch_width")
