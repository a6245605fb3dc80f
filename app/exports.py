"""CSV exports (time histories, mode table, map) as ``FileDownload`` buttons; plots are saved as PNG
with each plot's Bokeh save tool."""
from __future__ import annotations

import io
from typing import Callable

import numpy as np
import panel as pn

from amra_core.simulation import HISTORY_COLUMNS


def history_csv(history: np.ndarray | None) -> io.StringIO:
    """The full-resolution history of a run: columns :data:`HISTORY_COLUMNS` (SI units in the names)."""
    out = io.StringIO()
    h = np.zeros((0, len(HISTORY_COLUMNS))) if history is None else history
    np.savetxt(out, h, delimiter=",", header=",".join(HISTORY_COLUMNS), comments="")
    out.seek(0)
    return out


def download(label: str, filename: str, callback: Callable[[], io.StringIO]) -> pn.widgets.FileDownload:
    return pn.widgets.FileDownload(callback=callback, filename=filename, label=label, button_type="default",
                                   sizing_mode="stretch_width")


def export_bar(history: Callable, modes: Callable, cells: Callable) -> pn.Column:
    return pn.Column(
        pn.pane.Markdown("**Exports** (CSV; each plot's toolbar has a PNG save button)"),
        download("Time histories (CSV)", "amra-history.csv", history),
        download("Mode table (CSV)", "amra-modes.csv", modes),
        download("Boundary map (CSV)", "amra-map.csv", cells),
        sizing_mode="stretch_width")
