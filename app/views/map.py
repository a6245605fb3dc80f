"""The boundary map (paper Fig. 14) for the current EA, μ, fidelity and aerodynamics, filling in.

The view follows the server-wide :class:`app.server.map_jobs.MapJob` of the case (stored cells at
once, new ones as they finish), which calls back on every change; the view redraws at most every
:data:`REDRAW_S` seconds, streaming the new cells into a plain Bokeh figure. The current (CG, GJ)
is a star; the fold and flutter lines of every fidelity computed so far are overlaid. Clicking
the map loads the nearest cell's (CG, GJ) into the controls.
"""
from __future__ import annotations

import html
import io
import math
import time

import numpy as np
import panel as pn
from bokeh.events import Tap
from bokeh.models import (CDSView, ColumnDataSource, GroupFilter, HoverTool, Legend, LegendItem, Line, Quad, Range1d,
                          Scatter, Segment, VSpan)
from bokeh.plotting import figure

from amra_core.boundary import MapSpec, cell_class
from amra_core.stability import CellResult

from . import FIDELITY_COLOURS
from .status import text

CG_LABEL = "CG [% chord]"
GJ_LABEL = "GJ [N m²/rad]"
CLASS_COLOURS = {"stable": "#2e7d32", "flutter": "#c62828", "fold": "#8d6e63", "windmill-brake": "#90a4ae",
                 "failed": "#212121"}
REDRAW_S = 1.0  #: shortest wall-clock period between redraws of the map [s]
BUSY_RETRY_MS = 5000  #: a map refused as "server busy" is asked for again after this [ms]


def cell_columns(cells) -> dict:
    """The plot's columns of ``cells`` (text as lists of str: an empty float array as a colour column
    is an "invalid color array")."""
    classes = [cell_class(c) for c in cells]
    growth = [np.nan if c.growth_rate_per_s is None else c.growth_rate_per_s for c in cells]
    return {"cg_pct": np.array([100.0 * c.cg for c in cells], dtype=float),
            "gj_nm2": np.array([c.gj_nm2 for c in cells], dtype=float), "class": classes,
            "verdict": [str(c.verdict) for c in cells], "growth_rate_per_s": np.array(growth, dtype=float),
            "growth_text": [growth_text(g) for g in growth],
            "colour": [CLASS_COLOURS.get(k, CLASS_COLOURS["failed"]) for k in classes]}


def growth_text(growth_per_s) -> str:
    """A cell's growth rate for the hover, "—" where it has none (a windmill-brake or failed cell):
    Bokeh's number format wrote NaN as "NaN"."""
    ok = growth_per_s is not None and math.isfinite(growth_per_s)
    return f"{growth_per_s:.3f} 1/s" if ok else "—"


def nearest_cell(cells, cg_pct: float, gj: float):
    """The cell nearest to a click at (CG [% chord], GJ [N m^2/rad]), distance in column widths and
    decades of GJ."""
    if not cells or gj is None or cg_pct is None or not gj > 0:
        return None
    cgs = sorted({c.cg for c in cells})
    dcg = (cgs[-1] - cgs[0]) / max(len(cgs) - 1, 1) * 100.0 if len(cgs) > 1 else 10.0
    return min(cells, key=lambda c: ((100 * c.cg - cg_pct) / dcg) ** 2 + (4 * math.log10(c.gj_nm2 / gj)) ** 2)


class Eta:
    """Time left of a filling map [s], from the rate of computed (not stored) cells so far."""

    def __init__(self):
        self._clock, self._t0 = time.monotonic, None

    def update(self, computed: int, remaining: int, running: bool) -> str:
        """``", about N s left"`` once a few cells were computed while running ('' otherwise)."""
        if not running or remaining <= 0:
            return ""
        if self._t0 is None:
            self._t0 = (self._clock(), computed)
            return ""
        elapsed, done = self._clock() - self._t0[0], computed - self._t0[1]
        if done < 3 or elapsed <= 0:
            return ""
        left = remaining * elapsed / done
        return f", about {left:.0f} s left" if left < 120 else f", about {left / 60:.0f} min left"


def boundary_lines(columns) -> tuple:
    """``(fold, flutter)``: ``[(cg, gj), ...]`` of the columns' fold GJ and strong-flutter GJ [N m²/rad]."""
    fold = [(c["cg"], c["fold_gj"]) for c in columns if c.get("fold_gj") is not None]
    flutter = [(c["cg"], c["flutter_gj"]) for c in columns if c.get("flutter_gj") is not None]
    return fold, flutter


def flutter_bands(columns, width_pct: float) -> list:
    """The flutter intervals of the columns as bands ``left``/``right`` [% chord], ``bottom``/``top``
    [N m²/rad], with their ``strength`` and a hover ``text``."""
    out = []
    for c in columns:
        for iv in c.get("intervals", []):
            if iv.get("kind") != "flutter" or iv.get("fold_approach"):
                continue
            lo, hi = iv.get("gj_lo_nm2"), iv.get("gj_hi_nm2")
            if lo is None or hi is None or not hi > lo:
                continue
            zeta, growth = iv.get("damping_ratio"), iv.get("peak_growth_rate_1_s")
            text = (f"{iv.get('strength', '')} flutter, GJ {lo:.4g}-{hi:.4g} N m²/rad, "
                    + (f"damping ratio {zeta:+.3f}, " if zeta is not None else "")
                    + (f"growth {growth:+.3g} 1/s" if growth is not None else ""))
            out.append({"left": 100 * c["cg"] - 0.35 * width_pct, "right": 100 * c["cg"] + 0.35 * width_pct,
                        "bottom": lo, "top": hi, "strength": iv.get("strength", "strong"), "text": text})
    return out


def map_csv(cells, spec=None, complete: bool = True, columns=()) -> io.StringIO:
    """The map's cells, CG in % chord as on the page, numbers to 8 digits; the map's case, whether it
    is complete (a half-finished map says so) and, per finished column, the fold, strong-flutter and
    critical GJ the page draws as lines, in ``#`` lines above (the file had the cells only)."""
    from amra_core.export import table_csv
    fields = [k for k in CellResult.__dataclass_fields__ if k != "cg"]
    meta = {"complete": "yes" if complete else f"NO: {len(cells)} cells so far, the map was still filling"}
    if spec is not None:
        meta |= {**spec.grid_meta(), "ea_pct_chord": 100 * spec.ea,
                 "cg_columns_pct_chord": " ".join(f"{100 * c:g}" for c in spec.cg_values)}

    def gj(v) -> str:
        return "none" if v is None else ("above the range" if v == math.inf else f"{v:.8g}")
    for col in sorted(columns, key=lambda c: c["cg"]):
        meta[f"column cg_pct_chord {100 * col['cg']:g}"] = (
            f"fold_gj_nm2 {gj(col.get('fold_gj'))}, strong_flutter_gj_nm2 {gj(col.get('flutter_gj'))}, "
            f"critical_gj_nm2 {gj(col.get('critical_gj'))}, status {col.get('status', '')}")
    rows = [[100.0 * c.cg] + ["" if getattr(c, k) is None else getattr(c, k) for k in fields]
            for c in sorted(cells, key=lambda c: (c.cg, c.gj_nm2))]
    return io.StringIO(table_csv(["cg_pct_chord", *fields], rows, meta))


class MapView(pn.viewable.Viewer):
    def __init__(self, session, registry, who, on_pick, **params):
        super().__init__(**params)
        self.doc = session.doc
        self.redraw = session.throttle(self.poll, REDRAW_S)
        self.registry, self.who, self.on_pick = registry, who, on_pick
        self.job = None
        self.cells: list = []
        self.cells_source = ColumnDataSource(cell_columns([]))
        self.fold_sources = {fid: ColumnDataSource({"cg_pct": [], "gj_nm2": []}) for fid in FIDELITY_COLOURS}
        self.flutter_sources = {fid: ColumnDataSource({"cg_pct": [], "gj_nm2": []}) for fid in FIDELITY_COLOURS}
        self.band_sources = {k: ColumnDataSource({"left": [], "right": [], "bottom": [], "top": [], "text": []})
                             for k in ("strong", "weak")}
        self.marker_source = ColumnDataSource({"cg_pct": [40.0], "gj_nm2": [1500.0]})
        self.progress = pn.indicators.Progress(value=0, max=100, sizing_mode="stretch_width", label="map-progress",
                                               bar_color="info")
        self.status = text("Map: waiting ...", "amra-map-status")
        self.elsewhere = ""  #: how the current case's flight differs from the map's (see mark)
        self._legend_items: list = []  #: (LegendItem, its source, its cell class or "") of every figure
        self._lines_key = None
        self.eta = Eta()
        self.ea_source = ColumnDataSource({"x": [32.0]})
        #: sensitivity bands (app.views.sensitivity): per boundary at one CG, lowest to highest GJ
        self.sens_source = ColumnDataSource({"cg_pct": [], "lo": [], "hi": [], "text": []})

    # -- subscription
    def follow(self, spec: MapSpec) -> None:
        if self.job is not None and self.job.spec == spec and self.job.state not in ("cancelled", "failed", "busy"):
            return
        self.release()
        self.job = self.registry.subscribe(spec, self.who, self.redraw.kick)
        self.cells, self.eta = [], Eta()
        self.cells_source.data = cell_columns([])
        self.ea_source.data = {"x": [100.0 * spec.ea]}
        self.sens_source.data = {"cg_pct": [], "lo": [], "hi": [], "text": []}  # another case's bands
        self.progress.value = 0
        if self.job.state == "busy" and self.doc is not None:  # the queue was full: ask again later
            job = self.job
            self.doc.add_timeout_callback(lambda: self.job is job and self.follow(job.spec), BUSY_RETRY_MS)
        self.redraw.kick()

    def release(self) -> None:
        if self.job is not None:
            self.registry.unsubscribe(self.job, self.who)
            self.job = None

    def poll(self) -> None:
        """Pull new cells and progress from the job and draw them (event loop)."""
        if self.job is None:
            return
        snap = self.job.snapshot(len(self.cells))
        if snap["cells"]:  # cells only arrive, in order, until follow() starts another map
            self.cells.extend(snap["cells"])
            self.cells_source.stream(cell_columns(snap["cells"]))
        total = max(snap["total"], 1)
        pct = 100 if snap["state"] == "done" else min(99, int(100 * snap["n"] / total))
        eta = self.eta.update(snap["n"] - snap["cached"], total - snap["n"], snap["state"] == "running")
        if self.progress.value != pct:
            self.progress.value = pct
        spec = self.job.spec
        queued = f"queued, position {snap['position']}" if snap.get("position") else "waiting for a free map worker"
        state = {"queued": queued, "running": "computing", "done": "complete",
                 "cancelled": "cancelled", "failed": f"failed: {snap['error']}",
                 "busy": snap["error"]}[snap["state"]]
        line = (f"<b>Map</b> ({spec.fidelity}, {spec.aero}, EA {100 * spec.ea:.1f} %, μ {spec.mu:g}): "
                f"{html.escape(state)}; {snap['n']} cells ({snap['cached']} from the store) of about {total}{eta}")
        if self.elsewhere:
            line += f"<br><b>Not this case's flight:</b> {html.escape(self.elsewhere)}"
        if snap.get("notice"):  # the store could not be used or written (app.server.map_jobs.open_store)
            line += f"<br><b>Result store:</b> {html.escape(snap['notice'])}"
        self.status.value = line
        self.draw_boundaries(self.registry.related(spec))
        self.show_legend()

    def draw_boundaries(self, related: dict) -> None:
        """Per fidelity computed so far (``{fidelity: MapJob}``): the fold line (no autorotation below)
        and the strong-flutter line; for the map shown, its flutter intervals as shaded bands, the
        weak windows lighter and hatched (shown, but they do not move the critical GJ)."""
        lines = {fid: boundary_lines(job.columns()) for fid, job in related.items()}
        cgs = sorted(self.job.spec.cg_values) if self.job is not None else []
        width_pct = 100.0 * min((b - a for a, b in zip(cgs, cgs[1:])), default=0.05)
        bands = flutter_bands(self.job.columns() if self.job is not None else [], width_pct)
        key = repr((lines, bands))
        if key == self._lines_key:
            return
        self._lines_key = key
        for fid in FIDELITY_COLOURS:
            fold, flutter = lines.get(fid, ([], []))
            for src, pts in ((self.fold_sources[fid], fold), (self.flutter_sources[fid], flutter)):
                src.data = {"cg_pct": [100.0 * cg for cg, _ in pts], "gj_nm2": [gj for _, gj in pts]}
        for strength, src in self.band_sources.items():
            rows = [b for b in bands if b["strength"] == strength]
            src.data = {k: [b[k] for b in rows] for k in ("left", "right", "bottom", "top", "text")}

    def show_sensitivity(self, result: dict) -> None:
        """Bands at the study's CG (:mod:`app.views.sensitivity`): fold (left of the column) and strong
        flutter (right), each from its lowest to its highest GJ over the baseline and every ±10 %
        change of an estimate; a band open at the top (unstable at the top of the GJ range) is drawn
        to the top of the plot."""
        cg_pct, top = 100.0 * result["cg"], self.job.spec.gj_max if self.job is not None else 3000.0
        rows = []
        for dx, name, key in ((-0.6, "fold", "fold_band_nm2"), (0.6, "strong flutter", "flutter_band_nm2")):
            band = result.get(key)
            if band is None:
                continue
            lo, hi = band
            open_top = not math.isfinite(hi)
            rows.append((cg_pct + dx, lo, top * 1.2 if open_top else hi,
                         f"{name} GJ over every estimate ±{100 * result['step']:.0f} %: {lo:.0f} to "
                         + ("the top of the range" if open_top else f"{hi:.0f}") + " N m²/rad"))
        self.sens_source.data = {k: [r[i] for r in rows] for i, k in enumerate(("cg_pct", "lo", "hi", "text"))}
        self.show_legend()

    def mark(self, cg_pct: float, gj: float, elsewhere: str = "") -> None:
        """The current case as a star; ``elsewhere`` (not empty) says how the case's flight differs from
        every map's (an airspeed, a held rotor speed): then no star, and the status line says so
        (Table 1's 14 m/s case sat as a star on the axial map)."""
        self.elsewhere = elsewhere
        shown = {"cg_pct": [float(cg_pct)], "gj_nm2": [float(gj)]} if not elsewhere else {"cg_pct": [], "gj_nm2": []}
        self.marker_source.data = shown
        self.show_legend()
        self.redraw.kick()

    def csv(self) -> io.StringIO:
        job = self.job
        if job is None:
            return map_csv([], None, complete=False)
        cells, columns, done = job.for_export()
        return map_csv(cells, job.spec, complete=done, columns=columns)

    # -- plot
    def figure(self):
        """The map: cells coloured by class (hover: verdict and growth rate), the critical-GJ line
        of every fidelity computed so far, the current case as a star; a tap loads the nearest cell."""
        fig = figure(title="Stability boundary map: critical GJ vs CG, as the paper's Fig. 14 (click a cell to load it)",
                     height=460, sizing_mode="stretch_width",
                     y_axis_type="log", x_range=Range1d(18, 52), y_range=Range1d(25, 3600),
                     x_axis_label=CG_LABEL, y_axis_label=GJ_LABEL, tools="pan,wheel_zoom,box_zoom,reset,save",
                     output_backend="canvas", name="map-plot")
        # one renderer per class, so the legend keeps one order whatever class a map meets first; every
        # renderer has its one glyph (add_glyph: unselected and muted looks derived in the browser, two
        # models fewer each than the plotting helpers make: the map is drawn in every page)
        cells, class_items = [], []
        for cls, colour in CLASS_COLOURS.items():
            r = fig.add_glyph(self.cells_source, Scatter(x="cg_pct", y="gj_nm2", marker="square", size=11,
                                                         fill_color=colour, line_color=colour),
                              view=CDSView(filter=GroupFilter(column_name="class", group=cls)))
            cells.append(r)
            class_items.append(self._legend(LegendItem(label=cls, renderers=[r]), self.cells_source, cls))
        fig.add_tools(HoverTool(renderers=cells, tooltips=[
            ("CG", "@cg_pct{0.0} % chord"), ("GJ", "@gj_nm2{0.0} N m²/rad"), ("class", "@class"),
            ("verdict", "@verdict"), ("growth rate (eigenvalue)", "@growth_text")]))
        band = {"left": "left", "right": "right", "bottom": "bottom", "top": "top"}
        strong = fig.add_glyph(self.band_sources["strong"], Quad(**band, fill_color="#c62828", fill_alpha=0.35,
                                                                 line_color="#c62828"))
        weak = fig.add_glyph(self.band_sources["weak"], Quad(**band, fill_color="#ef9a9a", fill_alpha=0.15,
                                                             line_color="#ef9a9a", line_dash="dotted", hatch_pattern="/",
                                                             hatch_color="#e57373", hatch_alpha=0.5))
        items = [self._legend(LegendItem(label="strong flutter (this map)", renderers=[strong]), self.band_sources["strong"]),
                 self._legend(LegendItem(label="weak window (does not set GJ)", renderers=[weak]), self.band_sources["weak"])]
        fig.add_tools(HoverTool(renderers=[strong, weak], tooltips=[("", "@text")]))
        xy = {"x": "cg_pct", "y": "gj_nm2"}
        for fid, colour in FIDELITY_COLOURS.items():
            dots = {"fill_color": colour, "line_color": colour}
            fold = fig.add_glyph(self.fold_sources[fid], Line(**xy, line_color=colour, line_width=3))
            fig.add_glyph(self.fold_sources[fid], Scatter(**xy, size=6, **dots))
            flutter = fig.add_glyph(self.flutter_sources[fid], Line(**xy, line_color=colour, line_width=2.5,
                                                                    line_dash="dashed"))
            fig.add_glyph(self.flutter_sources[fid], Scatter(**xy, marker="triangle", size=8, **dots))
            items += [self._legend(LegendItem(label=f"{fid}: fold (no autorotation below)", renderers=[fold]),
                                   self.fold_sources[fid]),
                      self._legend(LegendItem(label=f"{fid}: strong flutter", renderers=[flutter]),
                                   self.flutter_sources[fid])]
        sens = fig.add_glyph(self.sens_source, Segment(x0="cg_pct", y0="lo", x1="cg_pct", y1="hi", line_color="#000000",
                                                       line_width=7, line_alpha=0.3))
        for end in ("lo", "hi"):
            fig.add_glyph(self.sens_source, Scatter(x="cg_pct", y=end, marker="dash", size=16, line_width=2,
                                                    line_color="#000000", fill_color="#000000"))
        fig.add_tools(HoverTool(renderers=[sens], tooltips=[("", "@text")]))
        items.append(self._legend(LegendItem(label="sensitivity band (estimates ±10 %)", renderers=[sens]),
                                  self.sens_source))
        star = fig.add_glyph(self.marker_source, Scatter(**xy, marker="star", size=20, fill_color="gold",
                                                         line_color="black"))
        items.append(self._legend(LegendItem(label="current case", renderers=[star]), self.marker_source))
        ea = fig.add_glyph(self.ea_source, VSpan(x="x", line_color="black", line_width=1.5, line_dash="dotted"))
        items.append(LegendItem(label="elastic axis (EA)", renderers=[ea]))
        classes = Legend(items=class_items, location="top_left", title="cells")
        fig.add_layout(classes, "right")
        fig.add_layout(Legend(items=items, location="top_left"), "right")
        fig.toolbar.logo = None
        fig.on_event(Tap, self._tapped)
        return fig

    def _legend(self, item: LegendItem, source: ColumnDataSource, cls: str = "") -> LegendItem:
        """``item``, listed only while ``source`` has something to draw (of class ``cls`` when given):
        empty entries (fem-coupled lines on a rigid map, "failed" with no failed cell) stood in the legend
        without a swatch."""
        self._legend_items.append((item, source, cls))
        self._show_legend_item(item, source, cls)
        return item

    @staticmethod
    def _show_legend_item(item: LegendItem, source: ColumnDataSource, cls: str) -> None:
        column = source.data["class"] if cls else next(iter(source.data.values()), [])
        shown = (cls in list(column)) if cls else len(column) > 0
        if item.visible != shown:
            item.visible = shown

    def show_legend(self) -> None:
        """Every legend entry listed exactly when its glyph draws something (event loop)."""
        for item, source, cls in self._legend_items:
            self._show_legend_item(item, source, cls)

    def _tapped(self, event) -> None:
        cell = nearest_cell(self.cells, event.x, event.y)
        if cell is not None:
            self.on_pick(cell)

    def __panel__(self):
        return pn.Column(self.status, self.progress, pn.pane.Bokeh(self.figure(), sizing_mode="stretch_width"),
                         sizing_mode="stretch_width")
