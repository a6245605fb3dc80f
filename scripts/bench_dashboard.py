"""Benchmark the dashboard in headless Chromium (a measurement, not a test).

Serves ``app.main.create_app`` in-process (warmed as ``--setup app/warmup.py`` does), opens it with
Playwright in /usr/bin/chromium and prints:

* first paint [s]: the browser's ``first-contentful-paint`` after navigation, and the time until the
  controls are rendered;
* slider release -> first new streamed point on screen [s]: the GJ slider is dragged during a run
  and the page is polled every animation frame until a point computed with the new GJ is in the
  plot's data source (median of ``--repeats``);
* plot updates per second while streaming: distinct data-source states seen per second of
  animation frames over ``--window`` seconds of a run;
* Run -> first streamed point at mu 0.1 [s]: the forward-flight trim included (issue 24: <= 2 s).

Usage: ``.venv/bin/python scripts/bench_dashboard.py [--repeats 5] [--window 5]``. Targets (issue 9):
first paint <= 3 s, latency <= 0.3 s (no more than 0.5 s), >= 10 updates/s.
"""
from __future__ import annotations

import argparse
import os
import socket
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

# latest streamed point's [n rows, t, gj] straight from the BokehJS data sources
JS_LAST = """() => { let best = null;
  for (const doc of Bokeh.documents) { for (const m of doc._all_models.values()) { const d = m.data;
    if (d && typeof d === 'object' && !Array.isArray(d)) { const g = (k) => d instanceof Map ? d.get(k) : d[k];
      const t = g('t_s'), gj = g('gj_nm2'), om = g('omega_rad_s');
      if (t && gj && om && t.length && (!best || t.length > best[0])) best = [t.length, t[t.length - 1], gj[gj.length - 1]];
  } } } return best; }"""

# arm (without waiting): note the page time of the next pointer release, then poll every animation
# frame until the newest point has a GJ other than `old` and note that time too. (A function that
# returned the Promise would make Playwright wait for it before the drag could even start.)
JS_ARM_NEW_GJ = """(old) => { window.__amraRelease = null; window.__amraSeen = null; const get = %s;
  document.addEventListener('pointerup', () => { window.__amraRelease = performance.now(); },
                            {capture: true, once: true});
  const t0 = performance.now();
  const step = () => { const s = get(); const now = performance.now();
    if (window.__amraRelease !== null && s && s[2] !== old) window.__amraSeen = now;
    else if (now - t0 < 30000) requestAnimationFrame(step); };
  step(); }""" % JS_LAST

# seconds from the release to the first frame showing the new GJ (-1: not seen in 20 s)
JS_LATENCY = """() => new Promise((resolve) => { const t0 = performance.now();
  const step = () => { if (window.__amraSeen !== null) resolve((window.__amraSeen - window.__amraRelease) / 1000);
    else if (performance.now() - t0 > 20000) resolve(-1); else requestAnimationFrame(step); };
  step(); })"""

# count distinct data states over `secs` seconds of animation frames
JS_RATE = """(secs) => new Promise((resolve) => { const t0 = performance.now(); const get = %s;
  let last = null, n = 0, frames = 0; const step = () => { const s = get(); const k = s ? s[0] + ':' + s[1] : '';
    frames += 1; if (k !== last) { n += 1; last = k; }
    if (performance.now() - t0 < secs * 1000) requestAnimationFrame(step);
    else resolve([(n - 1) / secs, frames / secs]); };
  step(); })""" % JS_LAST


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def drag_gj(page, dx: float) -> float:
    """Drag the GJ slider handle by dx pixels; returns perf time of the release (page clock)."""
    h = page.locator(".amra-gj-slider .noUi-handle").first
    box = h.bounding_box()
    page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
    page.mouse.down()
    page.mouse.move(box["x"] + box["width"] / 2 + dx, box["y"] + box["height"] / 2, steps=4)
    page.mouse.up()


def main() -> int:  # noqa: C901
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--window", type=float, default=5.0)
    args = ap.parse_args()
    os.environ.setdefault("AMRA_STORE", str(Path(tempfile.mkdtemp()) / "cells.sqlite"))
    import panel as pn
    from playwright.sync_api import sync_playwright

    from app.compute import warm, warm_worker
    from app.main import create_app
    from app.server.pool import get_analysis_pool, get_run_pool

    print(f"warm-up: {warm():.1f} s", flush=True)
    for pool in (get_analysis_pool(), get_run_pool()):
        pool.submit(warm_worker).result(timeout=300)
    sessions = []

    def app():
        page = create_app()
        sessions.append(page.dashboard)
        return page

    port = free_port()
    server = pn.serve(app, port=port, address="127.0.0.1", websocket_origin=f"127.0.0.1:{port}", threaded=True,
                      show=False, verbose=False)
    url = f"http://127.0.0.1:{port}/?run_s=120&speed=1"
    time.sleep(1.0)
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path="/usr/bin/chromium",
                                        args=["--no-sandbox", "--disable-gpu", "--disable-background-networking"])
            page = browser.new_page(viewport={"width": 1500, "height": 1000})
            t0 = time.monotonic()
            page.goto(url)
            page.wait_for_selector(".amra-run button", timeout=120_000)
            controls_s = time.monotonic() - t0
            fcp = page.evaluate("() => (performance.getEntriesByName('first-contentful-paint')[0] || {}).startTime")
            page.wait_for_function("() => " + JS_LAST.replace("() =>", "(() =>", 1) + ")() !== undefined", timeout=60_000)
            _, idle_fps = page.evaluate(JS_RATE, 2.0)
            page.locator(".amra-run button").click()
            page.wait_for_function(f"() => {{ const s = ({JS_LAST})(); return s && s[1] > 2.0; }}", timeout=120_000)
            live = sessions[-1].live
            pushed0, t_server0 = live.sent_rows, time.monotonic()
            rate, fps = page.evaluate(JS_RATE, args.window)
            rows_per_s = (live.sent_rows - pushed0) / (time.monotonic() - t_server0)
            lat = []
            for i in range(args.repeats):
                old = page.evaluate(JS_LAST)[2]
                page.evaluate(JS_ARM_NEW_GJ, old)
                drag_gj(page, -25 if i % 2 == 0 else 25)
                lat.append(page.evaluate(JS_LATENCY))
                page.wait_for_timeout(1500)
            sessions[-1].session.stop()
            # Run -> first streamed point in forward flight (mu 0.1): the trim a user waits for
            fwd = browser.new_page(viewport={"width": 1500, "height": 1000})
            fwd.goto(url + "&mu=0.1")
            fwd.wait_for_selector(".amra-run button", timeout=120_000)
            fwd.wait_for_timeout(1000)
            t_click = time.monotonic()
            fwd.locator(".amra-run button").click()
            fwd.wait_for_function(f"() => {{ const s = ({JS_LAST})(); return s && s[0] > 0; }}", timeout=120_000)
            first_point_mu01_s = time.monotonic() - t_click
            sessions[-1].session.stop()
            browser.close()
    finally:
        server.stop()
    good = [x for x in lat if x >= 0]
    print(f"first contentful paint: {fcp / 1000:.2f} s (controls rendered after {controls_s:.2f} s)")
    print(f"slider release -> first new streamed point: median {statistics.median(good):.3f} s "
          f"(runs: {', '.join(f'{x:.3f}' for x in lat)}; -1 = not seen in 20 s)" if good else
          f"slider release -> first new point: not seen ({lat})")
    print(f"plot updates per second while streaming: {rate:.1f} /s (over {args.window:g} s; the browser drew "
          f"{fps:.0f} frames/s; {idle_fps:.0f} before the run)")
    print(f"server side: {rows_per_s:.0f} history rows/s reached the live plots")
    print(f"Run -> first streamed point at mu 0.1 (trim included): {first_point_mu01_s:.2f} s")
    print(f"machine load average: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    return 0


if __name__ == "__main__":
    sys.exit(main())
