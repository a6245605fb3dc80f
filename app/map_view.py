"""The boundary map (paper Fig. 14) for the current EA, μ, fidelity and aerodynamics, filling in.

Cells come from the session's subscription to the server-wide :class:`app.map_jobs.MapJob`
(stored cells at once, new ones as they finish); a progress bar counts them. The current
(CG, GJ) is a star; the critical-GJ lines of every fidelity computed so far for the same case are
overlaid with a legend. Clicking the map loads the nearest cell's (CG, GJ) into the controls.

Redraws are spaced: a redraw of the cells re-renders the HoloViews overlay, which recomputes the
references of every model of the session's document (about 0.1 s of the server's event loop,
shared by all sessions), so new cells are drawn at most every :data:`REDRAW_S` seconds times the
load factor (the number of sessions following a map, halved), and at once when the map is done.
"""
from __future__ import annotations

import csv
import io
import math
import time

import holoviews as hv
import numpy as np
import pandas as pd
import panel as pn
from holoviews.streams import Pipe, Stream, Tap

from amra_core.boundary import MapSpec, cell_class
from amra_core.stability import CellResult

CG_DIM = hv.Dimension("cg_pct", label="CG", unit="% chord")
GJ_DIM = hv.Dimension("gj_nm2", label="GJ", unit="N m²/rad")
CLASS_COLOURS = {"stable": "#2e7d32", "flutter": "#c62828", "fold": "#8d6e63", "failed": "#212121"}
FIDELITY_STYLE = {"rigid": ("#1565c0", "solid"), "fem-torsion": ("#ef6c00", "dashed"),
                  "fem-coupled": ("#6a1b9a", "dotdash")}
Marker = Stream.define("Marker", cg_pct=40.0, gj=1500.0)
REDRAW_S = 1.0  #: shortest wall-clock period between redraws of the cells on an idle server [s]


def cells_frame(cells) -> pd.DataFrame:
    rows = [(100.0 * c.cg, c.gj_nm2, cell_class(c), c.verdict,
             np.nan if c.growth_rate_per_s is None else c.growth_rate_per_s) for c in cells]
    return pd.DataFrame(rows, columns=["cg_pct", "gj_nm2", "class", "verdict", "growth_rate_per_s"])


def nearest_cell(cells, cg_pct: float, gj: float):
    """The cell nearest to a click at (CG [% chord], GJ [N m^2/rad]), distance in column widths and
    decades of GJ."""
    if not cells or gj is None or cg_pct is None or not gj > 0:
        return None
    cgs = sorted({c.cg for c in cells})
    dcg = (cgs[-1] - cgs[0]) / max(len(cgs) - 1, 1) * 100.0 if len(cgs) > 1 else 10.0
    return min(cells, key=lambda c: ((100 * c.cg - cg_pct) / dcg) ** 2 + (4 * math.log10(c.gj_nm2 / gj)) ** 2)


def map_csv(cells) -> io.StringIO:
    out = io.StringIO()
    cols = list(CellResult.__dataclass_fields__)
    w = csv.writer(out)
    w.writerow(cols)
    for c in sorted(cells, key=lambda c: (c.cg, c.gj_nm2)):
        w.writerow(["" if getattr(c, k) is None else getattr(c, k) for k in cols])
    out.seek(0)
    return out


class MapView(pn.viewable.Viewer):
    def __init__(self, registry, who, on_pick, **params):
        super().__init__(**params)
        self.registry = registry
        self.who = who
        self.on_pick = on_pick
        self.job = None
        self.seen = 0
        self.cells: list = []
        self.pipe = Pipe(data=cells_frame([]))
        self.lines = Pipe(data={})
        self.marker = Marker()
        self.progress = pn.indicators.Progress(value=0, max=100, sizing_mode="stretch_width", name="map-progress",
                                               bar_color="info")
        self.status = pn.pane.Markdown("Map: waiting ...", name="map-status")
        self._lines_key = None
        self._undrawn = False  #: cells received but not drawn yet
        self._drawn_at = -1e9

    def load_factor(self) -> float:
        """1 on a server with one or two sessions following maps, n/2 with n sessions."""
        try:
            return max(1.0, self.registry.viewers() / 2.0)
        except Exception:  # noqa: BLE001 - a registry stand-in without viewers()
            return 1.0

    # -- subscription
    def follow(self, spec: MapSpec) -> None:
        if self.job is not None and self.job.spec == spec and self.job.state not in ("cancelled", "failed", "busy"):
            return
        self.release()
        self.job = self.registry.subscribe(spec, self.who)
        self.seen = 0
        self.cells = []
        self._undrawn = False
        self.pipe.send(cells_frame([]))
        self.progress.value = 0

    def release(self) -> None:
        if self.job is not None:
            self.registry.unsubscribe(self.job, self.who)
            self.job = None

    def poll(self) -> None:
        """Pull new cells and progress from the job (event loop)."""
        if self.job is None:
            return
        if self.job.state == "busy":  # the server's map queue was full: ask again every few seconds
            self._busy_polls = getattr(self, "_busy_polls", 0) + 1
            if self._busy_polls % 10 == 0:
                self.follow(self.job.spec)
        snap = self.job.snapshot(self.seen)
        if snap["cells"]:
            self.cells.extend(snap["cells"])
            self.seen = snap["n"]
            self._undrawn = True
        now = time.monotonic()
        if self._undrawn and (snap["state"] != "running" or now - self._drawn_at >= REDRAW_S * self.load_factor()):
            self._undrawn = False
            self._drawn_at = now
            self.pipe.send(cells_frame(self.cells))
        total = max(snap["total"], 1)
        pct = 100 if snap["state"] == "done" else min(99, int(100 * snap["n"] / total))
        if self.progress.value != pct:
            self.progress.value = pct
        spec = self.job.spec
        queued = f"queued, position {snap['position']}" if snap.get("position") else "waiting for a free map worker"
        state = {"queued": queued, "running": "computing", "done": "complete",
                 "cancelled": "cancelled", "failed": f"failed: {snap['error']}",
                 "busy": snap["error"]}[snap["state"]]
        text = (f"**Map** ({spec.fidelity}, {spec.aero}, EA {100 * spec.ea:.1f} %, μ {spec.mu:g}): {state}; "
                f"{snap['n']} cells ({snap['cached']} from the store) of about {total}")
        if snap.get("notice"):  # the store could not be used or written (server_limits.open_store)
            text += f"\n\n**Result store:** {snap['notice']}"
        if self.status.object != text:
            self.status.object = text
        related = self.registry.related(spec)
        lines = {}
        for fid, job in related.items():
            pts = job.critical_line()
            if len(pts) >= 1:
                lines[fid] = pts
        key = repr(lines)
        if key != self._lines_key:
            self._lines_key = key
            self.lines.send(lines)

    def mark(self, cg_pct: float, gj: float) -> None:
        self.marker.event(cg_pct=float(cg_pct), gj=float(gj))

    def csv(self) -> io.StringIO:
        return map_csv(self.cells)

    # -- plot
    def _cells_plot(self, data):
        return hv.Points(data, [CG_DIM, GJ_DIM], ["class", "verdict", "growth_rate_per_s"]).opts(
            color="class", cmap=CLASS_COLOURS, marker="square", size=11, tools=["hover", "tap"], logy=True,
            show_legend=True)

    def _lines_plot(self, data):
        layers = []
        for fid, (colour, dash) in FIDELITY_STYLE.items():
            pts = data.get(fid, [])
            layers.append(hv.Curve([(100 * cg, gj) for cg, gj in pts], CG_DIM, GJ_DIM,
                                   label=f"boundary {fid}").opts(color=colour, line_dash=dash, line_width=2.5,
                                                                 logy=True))
        return hv.Overlay(layers)

    def _marker_plot(self, cg_pct, gj):
        return hv.Points([(cg_pct, gj)], [CG_DIM, GJ_DIM], label="current case").opts(
            marker="star", size=20, color="gold", line_color="black", logy=True)

    def _tapped(self, x=None, y=None):
        cell = nearest_cell(self.cells, x, y)
        if cell is not None:
            self.on_pick(cell)

    def __panel__(self):
        cells = hv.DynamicMap(self._cells_plot, streams=[self.pipe])
        lines = hv.DynamicMap(self._lines_plot, streams=[self.lines])
        marker = hv.DynamicMap(self._marker_plot, streams=[self.marker])
        tap = Tap(source=cells, x=None, y=None)
        tap.add_subscriber(self._tapped)
        plot = (cells * lines * marker).opts(
            hv.opts.Overlay(title="Stability boundary map (click a cell to load it)", responsive=True, height=420,
                            show_grid=True, legend_position="right", xlim=(18, 52), ylim=(25, 3600), logy=True))
        return pn.Column(self.status, self.progress, pn.pane.HoloViews(plot, sizing_mode="stretch_width",
                                                                       name="map-plot"),
                         sizing_mode="stretch_width")
