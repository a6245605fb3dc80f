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

Flow control (:meth:`TimeHistories.enable_flow_control`, on in a served session): the browser
confirms the streamed batches once it has drawn them (a ``streaming`` callback counts them, waits
for the next animation frame, then writes the count to the ``tags`` of a small unplotted source, which syncs back),
and at most :data:`WINDOW_BATCHES` batches are sent unconfirmed; rows that arrive meanwhile are
sent together. Without it a client slower than
the stream (a loaded machine, eight browsers on two cores) fell ever further behind: at eight
sessions the newest point reached the screen 50 s after it was computed, and a slider release
took as long to show. With it each client gets as many updates as it can draw, and a new value
is at most two drawings behind. A client that does not confirm within :data:`ACK_TIMEOUT_S` (a
hidden tab draws nothing) is sent the next batch anyway.

A page whose drawing is slow (over :data:`FAST_DRAW_MS`) rests before it confirms (:data:`DRAW_DUTY`),
so it does not spend all its main thread drawing: a starved page that drew without pause queued
the user's own input and the server's messages behind seconds-long frames. The first rows computed
with the user's own change skip both the window and the stream budget (``flush(urgent=True)``).
Measured (``scripts/bench_dashboard.py``, one session, 2026-12-02): 13.4 plot updates/s and 0.155 s
slider latency with a window of two, against 10.2 /s and 0.298 s with three and no rest.
"""
from __future__ import annotations

import math

import holoviews as hv
import numpy as np
import pandas as pd
import time

from bokeh.models import ColumnDataSource, CustomJS, DataRange1d, HoverTool, Legend
from bokeh.plotting import figure

from amra_core.simulation import COL

from .browser_tuning import LIVE_PLOT_TAG

BUFFER_ROWS = 24_000  #: 120 s at 200 rows/s
ACK_TIMEOUT_S = 1.0  #: a batch not confirmed by the browser within this is followed by the next [s]

WINDOW_BATCHES = 2  #: batches sent and not yet confirmed by the browser, at most

#: share of the page's wall-clock time that drawing the live plots may take, at most, once a drawing
#: takes longer than FAST_DRAW_MS: the page then waits (1 - DRAW_DUTY) / DRAW_DUTY times the excess
#: before it confirms, so a slow or starved page (eight browsers on two cores) keeps time for the
#: user's input and the server's messages instead of drawing without pause; a page that draws ten
#: frames a second (the dashboard's target) never waits
DRAW_DUTY = 0.5
FAST_DRAW_MS = 100.0  #: a drawing (batch applied -> frame painted) this quick needs no rest [ms]

#: the browser counts the streamed batches it has applied; after the frame that draws them, and a
#: rest if that drawing was slow (``DRAW_DUTY``), it reports the count in ``tags[0]`` of a separate,
#: unplotted source (a property change that BokehJS sends back to the server; on the plotted source
#: itself, any property change makes every plot re-index its data and repaint)
_ACK_JS = """
cb_obj._amra_applied = (cb_obj._amra_applied || 0) + 1;
if (cb_obj._amra_ack_due) { return; }
cb_obj._amra_ack_due = true;
const t0 = performance.now();
const confirm = () => {
  cb_obj._amra_ack_due = false;
  ack.tags = [cb_obj._amra_applied];
};
requestAnimationFrame(() => setTimeout(() => {
  const drawn_ms = performance.now() - t0;
  setTimeout(confirm, Math.min(REST_CAP_MS, Math.max(0, drawn_ms - FAST_MS) * REST_RATIO));
}, 0));
"""


def _ack_js() -> str:
    rest_cap_ms = 0.9 * ACK_TIMEOUT_S * 1000.0  # a rest never outlasts the server's patience
    return (_ACK_JS.replace("REST_RATIO", repr((1.0 - DRAW_DUTY) / DRAW_DUTY))
            .replace("REST_CAP_MS", repr(rest_cap_ms)).replace("FAST_MS", repr(FAST_DRAW_MS)))


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


def columns_from_rows(rows: np.ndarray, gj_nm2: float) -> dict:
    """History rows (columns of ``amra_core.simulation.HISTORY_COLUMNS``, SI) to the plotted
    columns (:data:`COLUMNS`, display units), as float arrays of their own.

    (Plain arrays, not a DataFrame: the pump converts every chunk of every session, and on a server
    with eight sessions streaming, building DataFrames took 6 % of the event loop, py-spy, 2026-12-01.)"""
    deg = 180.0 / math.pi
    rows = np.asarray(rows, dtype=float)
    return {
        "t_s": rows[:, COL["t_s"]].copy(),
        "omega_rad_s": rows[:, COL["omega_rad_s"]].copy(),
        "teeter_deg": rows[:, COL["teeter_rad"]] * deg,
        "twist0_deg": rows[:, COL["tip_twist_0_rad"]] * deg,
        "twist1_deg": rows[:, COL["tip_twist_1_rad"]] * deg,
        "descent_m_s": rows[:, COL["descent_rate_m_s"]].copy(),
        "gj_nm2": np.full(len(rows), float(gj_nm2)),
    }


def frame_from_rows(rows: np.ndarray, gj_nm2: float) -> pd.DataFrame:
    """:func:`columns_from_rows` as a DataFrame (for the run-to-run comparison and exports)."""
    return pd.DataFrame(columns_from_rows(rows, gj_nm2))


class TimeHistories:
    """The session's data source and the four time-history plots built on it.

    :meth:`send` and :meth:`clear` must run on the session's event loop (the dashboard's pump)."""

    def __init__(self, length: int = BUFFER_ROWS):
        self.length = int(length)
        self.source = ColumnDataSource({c: np.zeros(0) for c in COLUMNS}, name="amra-time-histories")
        self.ack = ColumnDataSource({}, name="amra-stream-ack", tags=[0])  #: the browser's drawn-batch count
        self.sent_rows = 0
        self.last_sent_gj = float("nan")  #: GJ of the newest row sent [N m²/rad]
        self.batches_sent = 0
        self.batches_confirmed = 0
        self.flow_control = False
        self._pending: list = []
        self._awaiting_since: float | None = None  #: when the window filled
        self.min_interval_s = 0.0  #: shortest interval between batches (the server's stream budget) [s]
        self._sent_at = -1e9

    def enable_flow_control(self) -> None:
        """Keep at most :data:`WINDOW_BATCHES` batches undrawn in the browser (module docstring)."""
        if not self.flow_control:
            self.flow_control = True
            self.source.js_on_change("streaming", CustomJS(args={"ack": self.ack}, code=_ack_js()))
            self.ack.on_change("tags", self._confirmed)

    def _confirmed(self, attr, old, new) -> None:
        try:
            count = int(new[0])
        except (TypeError, ValueError, IndexError):
            return  # not a count: ignore it
        if count > self.batches_confirmed:
            self.batches_confirmed = min(count, self.batches_sent)
            self._awaiting_since = None

    @property
    def in_flight(self) -> int:
        """Batches sent that the browser has not confirmed drawing."""
        return self.batches_sent - self.batches_confirmed

    def queue(self, columns) -> None:
        """Queue rows to send: a mapping of :data:`COLUMNS` to equal-length arrays (a dict from
        :func:`columns_from_rows`, or a DataFrame)."""
        cols = {c: np.asarray(columns[c], dtype=float) for c in COLUMNS}
        if len(cols["t_s"]):
            self._pending.append(cols)

    def send(self, columns) -> int:
        """:meth:`queue` the rows and send what is queued if the browser is ready (see
        :meth:`flush`); returns the number of rows sent now."""
        self.queue(columns)
        return self.flush()

    def flush(self, now: float | None = None, urgent: bool = False) -> int:
        """Send the queued rows as one batch, unless flow control waits for the browser to confirm
        earlier batches (:data:`WINDOW_BATCHES` are unconfirmed; then one batch per
        :data:`ACK_TIMEOUT_S`) or the stream budget's interval has not passed; returns the number
        of rows sent. ``urgent`` (the first rows computed with the user's own change) goes at once."""
        if not self._pending:
            return 0
        now = time.monotonic() if now is None else now
        if not urgent:
            if now - self._sent_at < self.min_interval_s:
                return 0
            if self.flow_control and self.in_flight >= WINDOW_BATCHES:
                if self._awaiting_since is None:
                    self._awaiting_since = now
                if now - self._awaiting_since < ACK_TIMEOUT_S:
                    return 0
                self._awaiting_since = now  # no confirmation for a while (a hidden tab draws nothing): one batch
        batch = self._pending
        self._pending = []
        cols = batch[0] if len(batch) == 1 else {c: np.concatenate([b[c] for b in batch]) for c in COLUMNS}
        self.source.stream(cols, rollover=self.length)
        self.sent_rows += len(cols["t_s"])
        self.last_sent_gj = float(cols["gj_nm2"][-1])
        self.batches_sent += 1
        self._sent_at = now
        return len(cols["t_s"])

    @property
    def pending_rows(self) -> int:
        """Rows queued, not yet sent (waiting for the browser)."""
        return sum(len(b["t_s"]) for b in self._pending)

    def clear(self) -> None:
        """Empty the live plots (a new run starts)."""
        self._pending = []
        self.source.data = {c: np.zeros(0) for c in COLUMNS}
        self.sent_rows = 0

    def frame(self) -> pd.DataFrame:
        """What the plots hold now, as a frame of :data:`COLUMNS`."""
        return pd.DataFrame({c: np.asarray(self.source.data[c], dtype=float) for c in COLUMNS})

    def plots(self) -> list:
        """Rotor speed, teeter, tip twist (both blades) and descent rate against time, with the
        time axis shared (pan or zoom one, all follow)."""
        # the ranges follow the data in the browser and stay there (syncable=False): synced back,
        # every drawing sent the server a message per range moved (98 of the page's 176 messages
        # in 8 s of a run, 2026-12-02), each handled on the event loop of the whole server, where
        # eight sessions' range updates queued the users' slider moves by seconds
        x_range = DataRange1d(only_visible=True, syncable=False)
        out = []
        for cols, title, colours in ((("omega_rad_s",), "Rotor speed", ("#1f77b4",)),
                                     (("teeter_deg",), "Teeter angle", ("#2ca02c",)),
                                     (("twist0_deg", "twist1_deg"), "Elastic tip twist, both blades",
                                      ("#d62728", "#ff7f0e")),
                                     (("descent_m_s",), "Descent rate", ("#9467bd",))):
            fig = figure(title=title, height=220, sizing_mode="stretch_width", x_range=x_range,
                         y_range=DataRange1d(only_visible=True, syncable=False), tools="pan,wheel_zoom,box_zoom,reset,save",
                         x_axis_label=_axis_label("t_s"), y_axis_label=_axis_label(cols[0]),
                         output_backend="canvas", tags=[LIVE_PLOT_TAG])
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
