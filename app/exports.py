"""CSV exports that stand alone (time histories, mode table, map) as ``FileDownload`` buttons; plots
are saved as PNG with each plot's Bokeh save tool.

Every file is named after its case (``amra-fig10-rigid-gj100-cg40-history.csv``) and starts with
``#`` lines giving the case's parameters in the page's units and the solver version
(:mod:`amra_core.export`); numbers have 8 significant digits.
"""
from __future__ import annotations

import io

import numpy as np
import pandas as pd
import panel as pn

from amra_core.export import file_name, run_meta, table_csv
from amra_core.simulation import HISTORY_COLUMNS

LABELS = {"history": "Time histories (CSV)", "modes": "Mode table (CSV)", "map": "Boundary map (CSV)"}


def history_csv(sim, history: np.ndarray | None = None, verdict=None, run_state: str | None = None) -> io.StringIO:
    """The full-resolution history of ``sim`` (a Simulation; ``history`` overrides its rows):
    columns :data:`HISTORY_COLUMNS` (SI units in the names), the case, its changes, its start, how
    far it got (``run_state``, see :func:`amra_core.export.run_meta`) and its ``verdict`` (a Verdict)
    above. Without a run: the header row and a line saying so."""
    h = history if history is not None else (sim.history if sim is not None else np.zeros((0, len(HISTORY_COLUMNS))))
    meta = run_meta(sim, verdict, run_state) if sim is not None else {"run_state": "no run (none yet, or reset)"}
    return io.StringIO(table_csv(HISTORY_COLUMNS, h, meta))


def modes_csv(frame: pd.DataFrame, c, about: dict | None = None) -> io.StringIO:
    """The mode table (columns with units in their names) with the case of the controls ``c`` above,
    and ``about`` the table: its trim's rotor speed and descent rate, eigenvalues or Floquet, stable."""
    meta = {"preset": c.preset, "rotor": c.rotor, "gj_nm2": float(c.gj_nm2), "ea_pct_chord": float(c.ea_pct),
            "cg_pct_chord": float(c.cg_pct), "mu": float(c.mu), "airspeed_m_s": float(c.airspeed_m_s),
            "fidelity": c.fidelity, "aero": c.aero, "inflow": c.inflow}
    meta |= {k: ("" if v is None else v) for k, v in (about or {}).items()}
    return io.StringIO(table_csv(list(frame.columns), frame.itertuples(index=False), meta))


def names_for(c) -> dict:
    """File names of the three exports for the controls' case."""
    case = c.preset if c.preset != "custom" else c.rotor
    common = dict(case=case, fidelity=c.fidelity, gj_nm2=float(c.gj_nm2), cg_pct=float(c.cg_pct), mu=float(c.mu))
    return {"history": file_name("history", **common), "modes": file_name("modes", **common),
            # a map is one per EA and aero model as well (two EAs downloaded under one name)
            "map": file_name("map", case=case, fidelity=c.fidelity, aero=c.aero, ea_pct=float(c.ea_pct), mu=float(c.mu))}


class ExportBar:
    """The three download buttons (``callbacks``: history, modes, map); :meth:`rename` names them."""

    def __init__(self, **callbacks):
        self.buttons = {k: pn.widgets.FileDownload(callback=callbacks[k], filename=f"amra-{k}.csv", label=label,
                                                   button_type="default", sizing_mode="stretch_width",
                                                   css_classes=[f"amra-export-{k}"])
                        for k, label in LABELS.items()}

    def rename(self, names: dict) -> None:
        for key, name in names.items():
            self.buttons[key].filename = name

    def panel(self) -> pn.Column:
        return pn.Column(pn.pane.Markdown("**Exports** (CSV with the case in its header; each plot's toolbar has "
                                          "a PNG save button)"), *self.buttons.values(), sizing_mode="stretch_width")
