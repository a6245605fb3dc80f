"""Streaming time histories: one HoloViews ``Buffer`` per session, handed straight to the elements.

The buffer's columns are the plotted quantities in display units (derived columns are computed
when rows are sent, never inside the element callbacks, so Bokeh receives only the new rows,
``ColumnsStreamed``). ``gj_nm2`` is the GJ the solver used for each row, so a mid-run change is
visible in the data. (The previous-run overlay is in :mod:`app.ladder`.)
"""
from __future__ import annotations

import math
from functools import partial

import holoviews as hv
import numpy as np
import pandas as pd
from holoviews.streams import Buffer

from amra_core.simulation import COL

BUFFER_ROWS = 24_000  #: 120 s at 200 rows/s

DIMS = {
    "t_s": hv.Dimension("t_s", label="Time", unit="s"),
    "omega_rad_s": hv.Dimension("omega_rad_s", label="Rotor speed Ω", unit="rad/s"),
    "teeter_deg": hv.Dimension("teeter_deg", label="Teeter β", unit="deg"),
    "twist0_deg": hv.Dimension("twist0_deg", label="Tip twist", unit="deg"),
    "twist1_deg": hv.Dimension("twist1_deg", label="Tip twist", unit="deg"),
    "descent_m_s": hv.Dimension("descent_m_s", label="Descent rate", unit="m/s"),
    "gj_nm2": hv.Dimension("gj_nm2", label="GJ", unit="N m²/rad"),
}
COLUMNS = tuple(DIMS)


def empty_frame() -> pd.DataFrame:
    return pd.DataFrame({c: np.zeros(0) for c in COLUMNS})


def frame_from_rows(rows: np.ndarray, gj_nm2: float) -> pd.DataFrame:
    """History rows (columns of ``amra_core.simulation.HISTORY_COLUMNS``, SI) to the buffer's frame."""
    deg = 180.0 / math.pi
    return pd.DataFrame({
        "t_s": rows[:, COL["t_s"]],
        "omega_rad_s": rows[:, COL["omega_rad_s"]],
        "teeter_deg": rows[:, COL["teeter_rad"]] * deg,
        "twist0_deg": rows[:, COL["tip_twist_0_rad"]] * deg,
        "twist1_deg": rows[:, COL["tip_twist_1_rad"]] * deg,
        "descent_m_s": rows[:, COL["descent_rate_m_s"]],
        "gj_nm2": np.full(len(rows), float(gj_nm2)),
    })


class TimeHistories:
    """The session's buffer and the four time-history plots."""

    def __init__(self, length: int = BUFFER_ROWS):
        self.buffer = Buffer(empty_frame(), length=length, index=False)
        self.sent_rows = 0

    def send(self, frame: pd.DataFrame) -> None:
        if len(frame):
            self.buffer.send(frame)
            self.sent_rows += len(frame)

    def clear(self) -> None:
        """Empty the live buffer (a new run starts)."""
        self.buffer.clear()
        self.sent_rows = 0

    def _curve(self, stream, vdim: str, label: str, **opts):
        vdims = [DIMS[vdim]] + ([DIMS["gj_nm2"]] if vdim == "omega_rad_s" else [])  # GJ in the hover
        return hv.DynamicMap(partial(hv.Curve, kdims=[DIMS["t_s"]], vdims=vdims, label=label),
                             streams=[stream]).opts(**opts)

    def plots(self) -> list:
        """Rotor speed, teeter, tip twist (both blades) and descent rate against time. Each is one
        element per streamed quantity (HoloViews' per-update cost grows with the elements on the
        buffer; the previous-run comparison is in the ladder view)."""
        common = dict(responsive=True, height=220, show_grid=True, framewise=True, tools=["hover"])
        out = []
        for vdim, title, color in (("omega_rad_s", "Rotor speed", "#1f77b4"), ("teeter_deg", "Teeter angle", "#2ca02c"),
                                   ("descent_m_s", "Descent rate", "#9467bd")):
            out.append(self._curve(self.buffer, vdim, "current run", color=color, line_width=2, title=title,
                                   **common))
        tw0 = self._curve(self.buffer, "twist0_deg", "blade 0", color="#d62728", line_width=2, **common)
        tw1 = self._curve(self.buffer, "twist1_deg", "blade 1", color="#ff7f0e", line_width=2, **common)
        out.insert(2, (tw0 * tw1).opts(hv.opts.Overlay(title="Elastic tip twist, both blades",
                                                       legend_position="top_left")))
        return out
