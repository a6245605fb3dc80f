"""The live time histories: rotor speed, teeter, tip twist of both blades and descent rate.

:class:`LivePlots` keeps every row of the run; the page holds at most
:data:`MAX_POINTS` points per plot, a min/max-preserving decimation made on the server with
tsdownsample (lowest and highest value per time bin: no peak of an oscillation is lost). New rows
are decimated at the plot's current density and streamed (only new points travel); a plot that
would exceed :data:`MAX_POINTS` is decimated again to half of it. A zoom (Bokeh's ``RangesUpdate``,
sent only on user interaction) shows the visible range at full resolution; reset shows the whole
run again. Each plot's source has ``t_s``, its curves and ``gj_nm2`` (the GJ of each row).
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
from bokeh.events import RangesUpdate, Reset
from bokeh.models import ColumnDataSource, DataRange1d, HoverTool, LabelSet, Legend, Line, VSpan
from bokeh.plotting import figure
from tsdownsample import MinMaxDownsampler, NaNMinMaxDownsampler

from amra_core.simulation import COL

MAX_POINTS = 2000  #: points per curve in the page, at most
MARK_LABEL_GAP_S = 1.0  #: live changes closer than this [s] of run time share one label (the last's)
NORMAL_HEIGHT = 220  #: height of a live plot [px]
PRESENT_HEIGHT = 290  #: in presentation mode: two rows and the header fill a 1280x720 screen [px]
#: axis names and units; a plot's title names the quantity, so its y label stays short enough for the
#: 220 px plot ("Rotor speed Ω [rad/s]" was cut to "otor speed Ω [rad/s]" at some ranges)
UNITS = {"t_s": ("Time", "s"), "omega_rad_s": ("Ω", "rad/s"), "teeter_deg": ("Teeter β", "deg"),
         "twist0_deg": ("Tip twist", "deg"), "twist1_deg": ("Tip twist", "deg"),
         "descent_m_s": ("Descent rate", "m/s"), "gj_nm2": ("GJ", "N m²/rad")}
COLUMNS = tuple(UNITS)
#: smallest y-axis span per plot [display units]: a steady run looks steady (0.003 rad/s of round-off
#: on a 34 rad/s rotor speed is not blown up to fill the plot)
MIN_SPAN = {"omega_rad_s": 2.0, "teeter_deg": 0.5, "twist0_deg": 0.5, "descent_m_s": 2.0}
#: what an empty plot spans [display units] (time 0-10 s): before a run, or after Reset, each plot
#: shows its axes, ticks and units over a typical run's range (empty, they were blank boxes, and
#: every page load logged "could not set initial ranges" for each); the first rows replace it
EMPTY_FRAME = {"omega_rad_s": (0.0, 40.0), "teeter_deg": (-1.0, 1.0), "twist0_deg": (-1.0, 1.0),
               "descent_m_s": (0.0, 10.0)}
EMPTY_FRAME_S = 10.0
#: (curves, title, colours) per plot
PLOTS = ((("omega_rad_s",), "Rotor speed", ("#1f77b4",)),
         (("teeter_deg",), "Teeter angle", ("#2ca02c",)),
         (("twist0_deg", "twist1_deg"), "Elastic tip twist, both blades", ("#d62728", "#ff7f0e")),
         (("descent_m_s",), "Descent rate", ("#9467bd",)))


def label(col: str) -> str:
    name, unit = UNITS[col]
    return f"{name} [{unit}]"


def columns_from_rows(rows: np.ndarray, gj_nm2: float) -> dict:
    """History rows (``HISTORY_COLUMNS``, SI) to the plotted columns (:data:`COLUMNS`, display units)."""
    rows = np.asarray(rows, dtype=float)
    deg = 180.0 / math.pi
    return {"t_s": rows[:, COL["t_s"]].copy(), "omega_rad_s": rows[:, COL["omega_rad_s"]].copy(),
            "teeter_deg": rows[:, COL["teeter_rad"]] * deg, "twist0_deg": rows[:, COL["tip_twist_0_rad"]] * deg,
            "twist1_deg": rows[:, COL["tip_twist_1_rad"]] * deg,
            "descent_m_s": rows[:, COL["descent_rate_m_s"]].copy(), "gj_nm2": np.full(len(rows), float(gj_nm2))}


def _empty(curves) -> dict:
    return {c: np.zeros(0) for c in ("t_s", *curves, "gj_nm2")}


def _frame(curves) -> dict:
    """The two corners of an empty plot's span (:data:`EMPTY_FRAME`), drawn transparent."""
    return {"t_s": [0.0, EMPTY_FRAME_S], "y": list(EMPTY_FRAME[curves[0]])}


def minmax_indices(t: np.ndarray, ys, n_out: int) -> np.ndarray:
    """Sorted row indices keeping each curve's min and max in about ``n_out / 2`` time bins (all rows
    if there are not more than ``n_out``)."""
    n = len(t)
    if n <= n_out:
        return np.arange(n)
    n_out = max(4, n_out - n_out % 2)
    keep = [np.array([0, n - 1])]
    for y in ys:
        ds = MinMaxDownsampler() if np.isfinite(y).all() else NaNMinMaxDownsampler()
        keep.append(ds.downsample(t, y, n_out=n_out).astype(np.int64))
    return np.unique(np.concatenate(keep))


class LivePlots:
    """The four live plots of one session, and every row of its run (module docstring)."""

    def __init__(self, max_points: int = MAX_POINTS):
        self.max_points = int(max_points)
        self._chunks: list = []  #: the run's rows in display units (dicts of COLUMNS), joined when read
        self.sources = [ColumnDataSource(_empty(curves)) for curves, _, _ in PLOTS]
        self.sources[0].name = "amra-live-omega"
        #: per plot, the corners of its span while it has no rows (emptied by the first rows)
        self.frames = [ColumnDataSource(_frame(curves)) for curves, _, _ in PLOTS]
        #: live and scripted changes: time [s] and what changed, drawn as a vertical line in every plot
        self.markers = ColumnDataSource({"t_s": [], "text": []}, name="amra-live-markers")
        self.zoom: tuple | None = None  #: the visible time range [s] while the user has zoomed
        self.figures_made: list = []
        self._density = 1.0  #: points per history row of the plots (1: full resolution)
        self._counts = [0] * len(PLOTS)

    @property
    def sent_rows(self) -> int:
        """Rows of the run so far (every one is represented in the plots)."""
        return sum(len(k["t_s"]) for k in self._chunks)

    def whole(self) -> dict:
        """Every row of the run so far (the chunks joined, once)."""
        if len(self._chunks) != 1:
            self._chunks = [{c: np.concatenate([np.zeros(0), *(k[c] for k in self._chunks)]) for c in COLUMNS}]
        return self._chunks[0]

    def clear(self) -> None:
        self._chunks, self.zoom, self._density = [], None, 1.0
        self._counts = [0] * len(PLOTS)
        self.markers.data = {"t_s": [], "text": []}
        for src, frame, (curves, _, _) in zip(self.sources, self.frames, PLOTS):
            src.data = _empty(curves)
            frame.data = _frame(curves)

    def append(self, cols: dict) -> int:
        """Add rows (a dict of :data:`COLUMNS`) and send what the page shows of them; returns rows added."""
        n = len(cols["t_s"])
        if not n:
            return 0
        if not self._chunks:  # the run's first rows: the plots span them, not the empty frame
            for frame in self.frames:
                frame.data = {"t_s": [], "y": []}
        self._chunks.append(cols)
        if self.zoom is not None:
            return n  # the user looks at a range: it stays as it is until reset
        for i, (src, (curves, _, _)) in enumerate(zip(self.sources, PLOTS)):
            per_curve = n if self._density >= 1.0 else max(4, int(round(n * self._density / len(curves))))
            idx = minmax_indices(cols["t_s"], [cols[c] for c in curves], per_curve)
            if self._counts[i] + len(idx) > self.max_points:
                self._overview()
                return n
            src.stream({c: cols[c][idx] for c in ("t_s", *curves, "gj_nm2")})
            self._counts[i] += len(idx)
        return n

    def mark(self, t_s: float, text: str) -> None:
        """A vertical line at ``t_s`` [s] in every plot, labelled ``text`` (a change's new value). Of
        changes less than :data:`MARK_LABEL_GAP_S` apart only the last keeps its label: ten arrow-key
        presses on a slider mid-run wrote ten labels over each other ("CGCG4343%%..."); the card's case
        line names every change."""
        times = list(self.markers.data["t_s"])
        if times and float(t_s) - times[-1] < MARK_LABEL_GAP_S:
            self.markers.patch({"text": [(len(times) - 1, "")]})
        self.markers.stream({"t_s": [float(t_s)], "text": [text]})

    def _fill(self, cols: dict, points: int) -> None:
        """Each plot's source from ``cols``, at most ``points`` rows (shared by a plot's curves)."""
        for i, (src, (curves, _, _)) in enumerate(zip(self.sources, PLOTS)):
            idx = minmax_indices(cols["t_s"], [cols[c] for c in curves], points // len(curves))
            src.data = {c: cols[c][idx] for c in ("t_s", *curves, "gj_nm2")}
            self._counts[i] = len(idx)

    def _overview(self) -> None:
        """The whole run, decimated to half the limit per plot (room to stream into)."""
        whole = self.whole()
        n = len(whole["t_s"])
        self._density = min(1.0, self.max_points / 2 / max(n, 1))
        self._fill(whole, self.max_points // 2)

    def show_range(self, t0_s: float, t1_s: float) -> None:
        """Zoom: the rows in [t0, t1] (and a margin) at full resolution, or the whole run when the
        range covers it."""
        whole = self.whole()
        t = whole["t_s"]
        if not len(t) or (t0_s <= t[0] and t1_s >= t[-1]):
            self.reset()
            return
        self.zoom = (t0_s, t1_s)
        pad = 0.1 * (t1_s - t0_s)
        lo, hi = np.searchsorted(t, t0_s - pad), np.searchsorted(t, t1_s + pad, side="right")
        self._fill({c: v[max(0, lo - 1):hi + 1] for c, v in whole.items()}, self.max_points)

    def reset(self) -> None:
        """Back to the whole run (the toolbar's reset)."""
        self.zoom = None
        self._overview()

    def frame(self) -> pd.DataFrame:
        """Every row of the run so far, as a frame of :data:`COLUMNS`."""
        return pd.DataFrame(self.whole())

    def shown(self, plot: int = 0) -> dict:
        """What plot ``plot`` holds now (the page's copy)."""
        return {c: np.asarray(v) for c, v in self.sources[plot].data.items()}

    def _on_ranges(self, event) -> None:
        if event.x0 is not None and event.x1 is not None:
            self.show_range(float(event.x0), float(event.x1))

    def present(self, on: bool) -> None:
        """Presentation mode: plots tall enough for two rows to fill a 1280x720 screen, larger fonts."""
        for fig in self.figures_made:
            fig.height = PRESENT_HEIGHT if on else NORMAL_HEIGHT
            fig.title.text_font_size = "18px" if on else "13px"
            for axis in (*fig.xaxis, *fig.yaxis):
                axis.axis_label_text_font_size = "16px" if on else "13px"
                axis.major_label_text_font_size = "14px" if on else "11px"

    def figures(self) -> list:
        """The four plots, time axis shared (pan or zoom one, all follow)."""
        # the ranges follow the data in the browser (syncable=False: not sent back at each drawing);
        # a zoom reaches the server as one RangesUpdate event
        x_range = DataRange1d(only_visible=True, syncable=False)
        out = []
        for (curves, title, colours), src, frame in zip(PLOTS, self.sources, self.frames):
            fig = figure(title=title, height=NORMAL_HEIGHT, sizing_mode="stretch_width", x_range=x_range,
                         y_range=DataRange1d(only_visible=True, syncable=False, min_interval=MIN_SPAN[curves[0]]),
                         tools="pan,box_zoom,wheel_zoom,reset,save", x_axis_label=label("t_s"),
                         y_axis_label=label(curves[0]), output_backend="canvas")
            items = []
            # one glyph per renderer (add_glyph): the unselected and muted looks are derived in the
            # browser, not two more glyph models each in every page (no selection, no muting here)
            for col, colour, name in zip(curves, colours, ("blade 0", "blade 1") if len(curves) == 2 else ("run",)):
                r = fig.add_glyph(src, Line(x="t_s", y=col, line_width=2, line_color=colour))
                items.append((name, [r]))
            fig.add_glyph(frame, Line(x="t_s", y="y", line_alpha=0.0))  # spans the empty plot (EMPTY_FRAME)
            tips = [("t", "@t_s{0.000} s"), (UNITS[curves[0]][0], f"@{curves[0]}{{0.000}} {UNITS[curves[0]][1]}"),
                    ("GJ", "@gj_nm2{0.0} N m²/rad")]
            fig.add_tools(HoverTool(tooltips=tips, mode="vline", renderers=[r]))
            fig.add_glyph(self.markers, VSpan(x="t_s", line_color="#37474f", line_dash="dashed", line_width=1.5))
            fig.add_layout(LabelSet(x="t_s", y=4, y_units="screen", text="text", source=self.markers,
                                    text_font_size="11px", text_color="#37474f", x_offset=3))
            if len(curves) == 2:  # above the plot, in one row: inside, it hid the first second's twist
                fig.add_layout(Legend(items=items, location="top_right", orientation="horizontal", padding=2,
                                      margin=0, label_height=14, glyph_height=14, spacing=12), "above")
            fig.toolbar.logo = None
            out.append(fig)
        # the linked plots all report a zoom: listen to one
        out[0].on_event(RangesUpdate, self._on_ranges)
        self.figures_made = out
        for fig in out:
            fig.on_event(Reset, lambda event: self.reset())
        return out
