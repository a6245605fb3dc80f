"""Streaming time histories: one Bokeh ``ColumnDataSource`` per session, shared by the four plots
and appended with ``source.stream(rows, rollover)`` (a ``ColumnsStreamed`` patch of the new rows).

Why not the HoloViews ``Buffer`` of the style guide (A1): every ``Buffer.send`` refreshes each
``DynamicMap`` through HoloViews' ``hold_render``, which freezes the Bokeh document and, on exit,
recomputes the references of all its models (354 in a session: 0.06-0.12 s each), and rebuilds
each element from the whole buffer. Measured in a served session on the 2-core machine
(``/tmp``-profiled pump, 2026-12-01): 0.37 s per pump, 1.8 plot updates/s in the browser. A
``stream`` call changes no references, so it needs no recompute; the pump then costs about a
millisecond. Range tracking is done in the browser (``DataRange1d``), with the time axis shared.

The columns are the plotted quantities in display units; ``gj_nm2`` is the GJ the solver used for
each row, so a mid-run change is visible in the data (and in the rotor-speed hover). The window
is the last :data:`BUFFER_ROWS` rows (120 s at 200 rows/s); the full-resolution history is kept by
the Simulation and exported as CSV. (The previous-run overlay is in :mod:`app.ladder`.)
"""
from __future__ import annotations

import math

import holoviews as hv
import numpy as np
import pandas as pd
from bokeh.models import ColumnDataSource, DataRange1d, HoverTool, Legend
from bokeh.plotting import figure

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


def _axis_label(col: str) -> str:
    d = DIMS[col]
    return f"{d.label} [{d.unit}]"


def empty_frame() -> pd.DataFrame:
    return pd.DataFrame({c: np.zeros(0) for c in COLUMNS})


def frame_from_rows(rows: np.ndarray, gj_nm2: float) -> pd.DataFrame:
    """History rows (columns of ``amra_core.simulation.HISTORY_COLUMNS``, SI) to the plotted frame."""
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
    """The session's data source and the four time-history plots built on it.

    :meth:`send` and :meth:`clear` must run on the session's event loop (the dashboard's pump)."""

    def __init__(self, length: int = BUFFER_ROWS):
        self.length = int(length)
        self.source = ColumnDataSource({c: np.zeros(0) for c in COLUMNS}, name="amra-time-histories")
        self.sent_rows = 0

    def send(self, frame: pd.DataFrame) -> None:
        if len(frame):
            self.source.stream({c: frame[c].to_numpy(dtype=float) for c in COLUMNS}, rollover=self.length)
            self.sent_rows += len(frame)

    def clear(self) -> None:
        """Empty the live plots (a new run starts)."""
        self.source.data = {c: np.zeros(0) for c in COLUMNS}
        self.sent_rows = 0

    def frame(self) -> pd.DataFrame:
        """What the plots hold now, as a frame of :data:`COLUMNS`."""
        return pd.DataFrame({c: np.asarray(self.source.data[c], dtype=float) for c in COLUMNS})

    def plots(self) -> list:
        """Rotor speed, teeter, tip twist (both blades) and descent rate against time, with the
        time axis shared (pan or zoom one, all follow)."""
        x_range = DataRange1d(only_visible=True)
        out = []
        for cols, title, colours in ((("omega_rad_s",), "Rotor speed", ("#1f77b4",)),
                                     (("teeter_deg",), "Teeter angle", ("#2ca02c",)),
                                     (("twist0_deg", "twist1_deg"), "Elastic tip twist, both blades",
                                      ("#d62728", "#ff7f0e")),
                                     (("descent_m_s",), "Descent rate", ("#9467bd",))):
            fig = figure(title=title, height=220, sizing_mode="stretch_width", x_range=x_range,
                         y_range=DataRange1d(only_visible=True), tools="pan,wheel_zoom,box_zoom,reset,save",
                         x_axis_label=_axis_label("t_s"), y_axis_label=_axis_label(cols[0]),
                         output_backend="canvas")
            items = []
            for col, colour, label in zip(cols, colours, ("blade 0", "blade 1") if len(cols) == 2 else ("current run",)):
                r = fig.line("t_s", col, source=self.source, line_width=2, color=colour)
                items.append((label, [r]))
            tips = [("t", "@t_s{0.000} s"), (DIMS[cols[0]].label, f"@{cols[0]}{{0.000}} {DIMS[cols[0]].unit}")]
            if cols[0] == "omega_rad_s":
                tips.append(("GJ", "@gj_nm2{0.0} N m²/rad"))
            fig.add_tools(HoverTool(tooltips=tips, mode="vline", renderers=[r]))
            if len(cols) == 2:
                legend = Legend(items=items, location="top_left")
                fig.add_layout(legend)
            fig.toolbar.logo = None
            out.append(fig)
        return out
