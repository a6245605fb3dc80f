"""Reading the dashboard's state in the browser (BokehJS documents) for the browser tests."""
from __future__ import annotations

import time
from pathlib import Path

# all ColumnDataSources whose data has the streamed columns: [n rows, last t, last gj]
JS_STREAM = """
() => {
  const out = [];
  for (const doc of Bokeh.documents) {
    const models = doc._all_models instanceof Map ? doc._all_models.values() : Object.values(doc._all_models);
    for (const m of models) {
      const d = m.data;
      if (d && typeof d === 'object' && !Array.isArray(d)) {
        const get = (k) => (d instanceof Map ? d.get(k) : d[k]);
        const t = get('t_s'), gj = get('gj_nm2'), om = get('omega_rad_s');
        if (t && gj && om && t.length) out.push([t.length, t[t.length - 1], gj[gj.length - 1]]);
      }
    }
  }
  return out;
}
"""


def streamed(page):
    """(rows, last time [s], last GJ) of the most filled live source in the page, or (0, None, None)."""
    rows = page.evaluate(JS_STREAM)
    if not rows:
        return 0, None, None
    return max(rows, key=lambda r: r[0])


def wait_for(predicate, timeout_s: float = 30.0, every_s: float = 0.1, what: str = "condition"):
    deadline = time.monotonic() + timeout_s
    while True:
        v = predicate()
        if v:
            return v
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")
        time.sleep(every_s)


def open_dashboard(page, url: str, timeout_ms: int = 60_000) -> float:
    """Open the page and wait until the controls and plots are rendered; returns the time taken [s]."""
    t0 = time.monotonic()
    page.goto(url)
    page.wait_for_selector(".amra-run button", timeout=timeout_ms)
    # the plots are rendered after the first paint (defer_load); a user presses Run once they show
    wait_for(lambda: plot_point(page, "Rotor speed", 0.0, 0.0) is not None
             and plot_point(page, "Stability boundary map", 30.0, 100.0) is not None,
             timeout_ms / 1000, every_s=0.25, what="the plots to render")
    page.wait_for_timeout(500)
    return time.monotonic() - t0


JS_PLOT_POINT = """
([title, x, y]) => {
  for (const v of Bokeh.index.all_views()) {
    const m = v.model;
    if (m && m.title && m.title.text && m.title.text.startsWith(title) && v.frame && v.canvas_view) {
      const r = v.canvas_view.el.getBoundingClientRect();
      return [r.left + v.frame.x_scale.compute(x), r.top + v.frame.y_scale.compute(y)];
    }
  }
  return null;
}
"""

# map cells in the browser: number of points in sources with a 'class' column
JS_MAP_CELLS = """
() => {
  let n = 0;
  for (const doc of Bokeh.documents) {
    const models = doc._all_models instanceof Map ? doc._all_models.values() : Object.values(doc._all_models);
    for (const m of models) {
      const d = m.data;
      if (d && typeof d === 'object' && !Array.isArray(d)) {
        const c = d instanceof Map ? d.get('class') : d['class'];
        const cg = d instanceof Map ? d.get('cg_pct') : d['cg_pct'];
        if (c && cg) n = Math.max(n, c.length);
      }
    }
  }
  return n;
}
"""


def plot_point(page, title: str, x: float, y: float):
    """Page coordinates [px] of data point (x, y) in the Bokeh plot whose title starts with ``title``."""
    return page.evaluate(JS_PLOT_POINT, [title, x, y])


def map_cells(page) -> int:
    return page.evaluate(JS_MAP_CELLS)


def progress_value(page, name: str = "map-progress"):
    """Value of the first <progress> element on the page (Panel's Progress indicator), or None."""
    return page.evaluate("""() => {
      const find = (root) => {
        for (const el of root.querySelectorAll('*')) {
          if (el.tagName === 'PROGRESS') return el;
          if (el.shadowRoot) { const f = find(el.shadowRoot); if (f) return f; }
        }
        return null;
      };
      const p = find(document);
      return p ? Number(p.getAttribute('value') ?? p.value) : null;
    }""")


SCREENSHOTS = Path(__file__).resolve().parents[2] / "test-results" / "screenshots"


def shot(page, name: str) -> Path:
    """Save a full-page screenshot as a test artifact (test-results/screenshots/NAME.png)."""
    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    path = SCREENSHOTS / f"{name}.png"
    page.screenshot(path=str(path), full_page=True)
    return path
