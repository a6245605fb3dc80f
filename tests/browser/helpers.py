"""Reading the dashboard's state in the browser (BokehJS documents) for the browser tests."""
from __future__ import annotations

import time

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
    """Open the page and wait until the controls are rendered; returns the time taken [s]."""
    t0 = time.monotonic()
    page.goto(url)
    page.wait_for_selector(".amra-run button", timeout=timeout_ms)
    return time.monotonic() - t0
