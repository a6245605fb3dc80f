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
"""
from __future__ import annotations

from bokeh.models import CustomJS

LIVE_TEXT_CLASS = "amra-live-text"  #: a Div whose text alone changes, set in place (module docstring)
CSS_CACHE_MS = 30_000  #: how long a looked-up CSS variable of a plot element is reused [ms]

_PATCH_JS = """
const mod = (window.Bokeh && Bokeh.require) ? Bokeh.require("core/visuals/visual") : null;
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
const dom = (window.Bokeh && Bokeh.require) ? Bokeh.require("core/dom") : null;
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
let divs = null;
try { divs = Bokeh.require("models/widgets/div"); } catch (e) { divs = null; }
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
const canvas = (window.Bokeh && Bokeh.require) ? Bokeh.require("models/plots/plot_canvas") : null;
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
"""


def patch_js() -> str:
    return _PATCH_JS.replace("TTL_MS", str(int(CSS_CACHE_MS))).replace("LIVE_CLASS", repr(LIVE_TEXT_CLASS))


def install(doc) -> None:
    """Run the patch in the browser when ``doc`` is ready (a served session's document)."""
    doc.js_on_event("document_ready", CustomJS(code=patch_js()))
