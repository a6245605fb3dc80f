"""Browser-side tuning of BokehJS for streaming plots: installed once per page, on document ready.

BokehJS (3.x) lets CSS variables (``--bk-text-color``, ``--bk-fill-color``, ...) override every
visual property, so each visual it paints (every tick label, title, axis and border region) calls
``getComputedStyle(el).getPropertyValue(...)``. Measured with a CPU profile of a streaming session
(Chrome DevTools protocol, 6 s of a run, 2026-12-01): 30 % of the page's main-thread time was in
``getPropertyValue``, because the text measurements between those calls keep invalidating the
page's style, so each call recomputes it; after that, 15 % in the plots' ``base_font_size``
(``getComputedStyle(el).fontSize``, once per plot and paint), for the same reason. Neither this app nor Panel's or Bokeh's themes set those
variables, but to stay correct if a theme does, both lookups are cached per element for
:data:`CSS_CACHE_MS` rather than ignored: a theme change shows within that time. (A cache of one
second did nothing in a starved page, whose frames are more than a second apart: in a page among
eight on two cores, ``getPropertyValue`` was still 14 % of the main thread; with 30 s, 2 %.)

BokehJS also rewrites the ``<style>`` text of each plot element's position and CSS variables on
every paint, with the same text almost always (4610 of 5000 such writes in 5 s of a run, one page,
2026-12-02); each write makes the browser re-parse the sheet and recompute the style of its shadow
tree (1506 sheet parses and 0.7 s of style updates in those 5 s). A write of the same text is
skipped: the sheet already says it (after: 199 parses, 0.2 s).

A Bokeh ``Div`` whose text changes re-renders and then lays out the whole page again (BokehJS's
``LayoutDOMView.rerender``: ``compute_layout`` from the root, which measures every element and
repaints every plot). The run clock, the verdict card and the map status line
(:class:`app.live_text.LiveText`, class :data:`LIVE_TEXT_CLASS`) change about four times a second
in a run: 3.9 page layouts a second, 12 % of one page's main thread (CPU profile, one session,
2026-12-02). Their text is set in place instead; the page's CSS layout moves what follows, as for
any text, and the plots keep their size, so nothing of Bokeh's layout changes.

A live plot's y axes follow the data, so their tick labels change width ("0.5" -> "0.25") every
few drawings; each change of an axis's size lays out the whole page again (BokehJS's
``PlotView._invalidate_layout_if_needed``), 1.1 s of 15 s of a page among eight (CPU profile,
2026-12-02). The axes of the plots tagged :data:`LIVE_PLOT_TAG` keep the largest size they have
needed: the page is laid out again only when a label is wider than any before (the axis may then
keep a few pixels more room than its labels need).

Each streamed batch makes every glyph of a live plot build a search tree of all its points
(BokehJS's ``GlyphView.index_data``: a Flatbush index, sorted), though a line's hover and tap
tests do not use it and the auto-ranges need only its bounding box. With 12 000 rows in the page
(60 s of a run), that was a fifth of an uncontended page's main thread (CPU profile, 2026-12-02),
and it grows with the rows. In the plots tagged :data:`LIVE_PLOT_TAG`, a point glyph (``x``, ``y``)
now finds its bounding box in one pass over the points, and builds the tree only when something
asks it for a search.

And each glyph takes its columns through its view's index set (``BitSet.select``: a list of the
set indices, then a gather into a new array), though a live plot's view selects every row: 7 % of
the same page's time. When every index is set, the same new array is made with a plain copy.

Last, the lines themselves: without a GPU the browser strokes a path in software, about 2 ms per
1000 points and worse beyond (90 ms for 24 000 points on a 1300 px canvas, measured in this
Chromium), and a live plot holds up to 24 000 rows on about 1200 pixel columns. A line of a live
plot with more than twice as many points as its canvas has device pixel columns is drawn through the M4 reduction (Jugel
et al., "M4: a visualization-oriented time series data aggregation", VLDB 2014): in each pixel
column, its first, lowest, highest and last point, in their order. That draws the line of all
the points but for antialiasing at the joins: of a 24 000-point line's pixels, 0.1 % (a growing
1/rev-like oscillation) to 0.6 % (a line with gaps) differ by more than a quarter of full intensity
(``tests/browser`` compares the pixels). A line whose x goes back is drawn as BokehJS draws it;
gaps and non-finite values break the line as before. Measured in one page (60 s into a run,
11 600 rows): 52 ms of renderer CPU per update against 83 ms without (4 400 rows: 51 against 59).

And the sliders. This app's server uses a slider's value only once the handle is released (Panel's
``config.throttled``), but BokehJS sends the value at every step of a drag as well: five messages
for one slider move, each of which the server must read, apply and answer, one after another on
the page's connection, before it reads the release. On a loaded server (eight browsers on two
cores) the release reached the server 0.5-0.9 s after the pointer went up (p50; ``scripts/load_test.py``,
2026-12-02). With ``install(doc, sliders_on_release=True)``, a drag updates the slider's value in
the page (its title shows it as before) without sending it; the release sends it, once.
"""
from __future__ import annotations

from bokeh.models import CustomJS

LIVE_TEXT_CLASS = "amra-live-text"  #: a Div whose text alone changes, set in place (module docstring)
LIVE_PLOT_TAG = "amra-live-plot"  #: a streaming plot: axes that never shrink, a lazy search tree (docstring)
CSS_CACHE_MS = 30_000  #: how long a looked-up CSS variable of a plot element is reused [ms]

_PATCH_JS = """
const need = (name) => {  // a BokehJS module, or null (a Bokeh without it: that patch is left out)
  try { return (window.Bokeh && Bokeh.require) ? Bokeh.require(name) : null; } catch (e) { return null; }
};
const in_live_plot = (plot_view) => {
  const plot = plot_view != null ? plot_view.model : null;
  return plot != null && plot.tags != null && plot.tags.includes(LIVE_PLOT);
};
const mod = need("core/visuals/visual");
const V = mod ? mod.VisualProperties : null;
if (V && !V.prototype.__amra_css_cache) {
  const lookup = V.prototype._get_css_value;
  V.prototype.__amra_css_cache = true;
  V.prototype._get_css_value = function (name) {
    const el = this.obj.el;
    if (!el) { return lookup.call(this, name); }
    const now = performance.now();
    let cache = el.__amra_css;
    if (cache === undefined || now - cache.at > TTL_MS) {
      cache = el.__amra_css = {at: now, values: new Map()};
    }
    const key = this.css_prefix + name;
    let value = cache.values.get(key);
    if (value === undefined) {
      value = lookup.call(this, name);
      cache.values.set(key, value);
    }
    return value;
  };
}
const dom = need("core/dom");
const IS = dom ? dom.InlineStyleSheet : null;
if (IS && IS.prototype._update && !IS.prototype.__amra_same_css) {
  IS.prototype.__amra_same_css = true;
  const update = IS.prototype._update;
  IS.prototype._update = function (css) {
    // the same text again: setting it would still make the browser re-parse the sheet and
    // recompute the style of its whole shadow tree
    if (this.el.textContent !== css) { update.call(this, css); }
  };
}
const divs = need("models/widgets/div");
const DV = divs ? divs.DivView : null;
if (DV && !DV.prototype.__amra_live_text) {
  DV.prototype.__amra_live_text = true;
  const rerender = DV.prototype.rerender;
  DV.prototype.rerender = function () {
    const m = this.model;
    if (this._was_built && this.markup_el && m.css_classes.includes(LIVE_CLASS) && !m.render_as_text
        && this.has_math_disabled()) {
      // only the text of a live text changes: no new render, no layout of the whole page
      if (this.__amra_text !== m.text) { this.markup_el.innerHTML = m.text; this.__amra_text = m.text; }
      return;
    }
    return rerender.call(this);
  };
}
const axes = need("models/axes/axis");
const AV = axes ? axes.AxisView : null;
if (AV && AV.prototype.get_size && !AV.prototype.__amra_steady) {
  AV.prototype.__amra_steady = true;
  const get_size = AV.prototype.get_size;
  AV.prototype.get_size = function () {
    const size = get_size.call(this);
    if (!in_live_plot(this.plot_view) || (size.width == 0 && size.height == 0)) { return size; }
    // the largest size this axis has needed: a narrower label does not lay out the page again
    const kept = this.__amra_size || {width: 0, height: 0};
    this.__amra_size = {width: Math.max(kept.width, size.width), height: Math.max(kept.height, size.height)};
    return this.__amra_size;
  };
}
const spatial = need("core/util/spatial"), xy = need("models/glyphs/xy_glyph");
const SI = spatial ? spatial.SpatialIndex : null;
const XYV = xy ? xy.XYGlyphView : null;
if (SI && XYV && XYV.prototype.index_data && !XYV.prototype.__amra_lazy_index) {
  XYV.prototype.__amra_lazy_index = true;
  const point_index = XYV.prototype._index_data;
  class LazyIndex extends SI {
    // the bounding box of the finite points now (what the auto-ranges ask), the tree on a search
    constructor(view) {
      super(0);
      this.view = view;
      this.tree = null;
      const {x, y, data_size} = view;
      let x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity;
      for (let i = 0; i < data_size; i++) {
        const xi = x[i], yi = y[i];
        if (!isFinite(xi + yi)) { continue; }
        if (xi < x0) { x0 = xi; }
        if (xi > x1) { x1 = xi; }
        if (yi < y0) { y0 = yi; }
        if (yi > y1) { y1 = yi; }
      }
      this.box = {x0, y0, x1, y1};
    }
    built() {
      if (this.tree === null) {
        const tree = new SI(this.view._index_size);
        point_index.call(this.view, tree);
        tree.finish();
        this.tree = tree;
      }
      return this.tree;
    }
    get bbox() { return {...this.box}; }
    indices(rect) { return this.built().indices(rect); }
    bounds(rect) { return this.built().bounds(rect); }
  }
  const index_data = XYV.prototype.index_data;
  XYV.prototype.index_data = function () {
    if (in_live_plot(this.renderer ? this.renderer.plot_view : null) && this._index_data === point_index) {
      this._index = new LazyIndex(this);
      return;
    }
    return index_data.call(this);
  };
}
const bitset = need("core/util/bitset");
const BS = bitset ? bitset.BitSet : null;
if (BS && BS.prototype.select && !BS.prototype.__amra_all_set) {
  BS.prototype.__amra_all_set = true;
  const select = BS.prototype.select;
  BS.prototype.select = function (array) {
    // every index set: the selection is the whole array, in order (a copy, as before)
    if (this.size == array.length && this.count == this.size && typeof array.slice === "function") {
      return array.slice();
    }
    return select.call(this, array);
  };
}
const m4_path = function (ctx, sx, sy, indices, dpr) {
  // the M4 path of a line whose x never decreases; false (and nothing worth keeping) otherwise
  let col = NaN, first = -1, last = -1, lo = -1, hi = -1, prev = -2, move = true, last_x = -Infinity;
  const emit = (i) => { if (move) { ctx.moveTo(sx[i], sy[i]); move = false; } else { ctx.lineTo(sx[i], sy[i]); } };
  const flush = () => {
    if (first < 0) { return; }
    // first <= lo, hi <= last (indices in time order): the four in their order, each once
    const a = Math.min(lo, hi), b = Math.max(lo, hi);
    emit(first);
    if (a !== first) { emit(a); }
    if (b !== a) { emit(b); }
    if (last !== b) { emit(last); }
    first = -1;
  };
  ctx.beginPath();
  for (const i of indices) {
    const x = sx[i], y = sy[i];
    if (!isFinite(x + y)) { flush(); move = true; prev = i; continue; }
    if (prev !== -2 && i - prev !== 1) { flush(); move = true; }  // a gap in the indices
    if (x < last_x) { return false; }
    last_x = x;
    const c = Math.floor(x * dpr);
    if (first < 0 || c !== col) {
      flush();
      col = c; first = last = lo = hi = i;
    } else {
      last = i;
      if (y < sy[lo]) { lo = i; }
      if (y > sy[hi]) { hi = i; }
    }
    prev = i;
  }
  flush();
  return true;
};
window.__amraM4Path = m4_path;  // for the browser tests
const lines = need("models/glyphs/line");
const LV = lines ? lines.LineView : null;
if (LV && LV.prototype._paint && !LV.prototype.__amra_m4) {
  LV.prototype.__amra_m4 = true;
  const paint = LV.prototype._paint;
  LV.prototype._paint = function (ctx, indices, data) {
    const n = indices.count !== undefined ? indices.count : indices.length;
    const width = ctx.canvas ? ctx.canvas.width : Infinity;  // device pixels
    if (in_live_plot(this.renderer ? this.renderer.plot_view : null) && this.parent.nonselection_glyph != this
        && n > 2 * width) {
      const {sx, sy} = {...this, ...data};
      if (m4_path(ctx, sx, sy, indices, window.devicePixelRatio || 1)) {
        this.visuals.line.set_value(ctx);
        ctx.stroke();
        return;
      }
    }
    return paint.call(this, ctx, indices, data);
  };
}
const canvas = need("models/plots/plot_canvas");
const P = canvas ? canvas.PlotView : null;
const font = P ? Object.getOwnPropertyDescriptor(P.prototype, "base_font_size") : null;
if (font && font.get && !P.prototype.__amra_font_cache) {
  P.prototype.__amra_font_cache = true;
  Object.defineProperty(P.prototype, "base_font_size", {
    configurable: true,
    get() {
      const now = performance.now();
      if (this.__amra_font === undefined || now - this.__amra_font.at > TTL_MS) {
        this.__amra_font = {at: now, value: font.get.call(this)};
      }
      return this.__amra_font.value;
    },
  });
}
const sliders = need("models/widgets/sliders/abstract_slider");
const SV = sliders ? sliders.AbstractSliderView : null;
if (SLIDERS_ON_RELEASE && SV && SV.prototype._slide && !SV.prototype.__amra_on_release) {
  SV.prototype.__amra_on_release = true;
  SV.prototype._slide = function (values) {  // while dragging: shown in the page, not sent
    this.model.setv({value: this._calc_from(values)}, {sync: false});
  };  // on release, BokehJS's _change sets value_throttled (and value): that is sent
}
"""


def patch_js(sliders_on_release: bool = False) -> str:
    return (_PATCH_JS.replace("TTL_MS", str(int(CSS_CACHE_MS))).replace("LIVE_CLASS", repr(LIVE_TEXT_CLASS))
            .replace("LIVE_PLOT", repr(LIVE_PLOT_TAG))
            .replace("SLIDERS_ON_RELEASE", "true" if sliders_on_release else "false"))


def install(doc, sliders_on_release: bool = False) -> None:
    """Run the patch in the browser when ``doc`` is ready (a served session's document).

    ``sliders_on_release``: the server uses a slider's value only when the handle is released
    (Panel's ``config.throttled``), so a dragged slider sends nothing until then (module docstring)."""
    doc.js_on_event("document_ready", CustomJS(code=patch_js(sliders_on_release)))
