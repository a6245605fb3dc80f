"""Server time to build one dashboard page, in this process and without a browser (a benchmark, not
a test): the session's :class:`app.app.Dashboard`, its layout and the Bokeh document of the page with
its first tab (the boundary map; outside a server Panel builds the deferred tabs area at once),
built with the page's document current (``set_curdoc``), as Panel's server builds a session: Panel
then makes one stylesheet model per CSS file and document, not one per component.

The served figure leaves the deferred tabs out and varies by +/- 40 ms from page to page with the
server's garbage collections; this one, averaged over many pages in a quiet process, shows what a
change to the page costs. Pin it to one core for comparable figures:

    taskset -c 0 python scripts/bench_page_build.py [--pages 30]

``--served`` measures the served figure instead: ``amra serve`` on CPU 0 (``scripts/load_test.py``'s
server), the pages opened one after another in headless Chromium on CPU 1, and the server's own
"page built in" log lines (the first page, which warms the process, left out):

    python scripts/bench_page_build.py --served [--pages 15]
"""
from __future__ import annotations

import argparse
import collections
import gc
import json
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


class _NoPool:
    """The analysis pool's interface, doing nothing: the analyses are not part of the page."""

    def submit(self, *args, **kwargs):
        return None


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pages", type=int, default=None, help="pages to build (30; served: 15)")
    ap.add_argument("--served", action="store_true", help="the served page build (amra serve, Chromium)")
    args = ap.parse_args(argv)
    if args.served:
        return served(args.pages or 15)
    args.pages = args.pages or 30
    import holoviews as hv
    import panel as pn
    from bokeh.document import Document
    from panel.io.state import set_curdoc

    from app.app import Dashboard
    from app.server.map_jobs import get_registry
    from app.server.settings import ServerSettings
    from app.tuning.offline_styles import serve_resources_locally

    serve_resources_locally()
    pn.extension(notifications=True, throttled=True)
    hv.extension("bokeh", logo=False)
    settings = ServerSettings.from_env()
    registry = get_registry(settings)
    times, models = [], None
    for _ in range(args.pages + 3):  # the first three warm the caches
        doc = Document()
        t0 = time.perf_counter()
        with set_curdoc(doc), pn.io.hold(freeze=True):  # as a served session: Panel shares stylesheets per document
            dash = Dashboard(settings, registry=registry, pool=_NoPool(), doc=doc)
            dash.__panel__().server_doc(doc)
        times.append(time.perf_counter() - t0)
        models = collections.Counter(type(m).__name__ for m in doc.models)
        dash.close()
        del dash, doc
        gc.collect()
    times = times[3:]
    print(json.dumps({"pages": len(times), "median_ms": round(1e3 * statistics.median(times), 1),
                      "min_ms": round(1e3 * min(times), 1), "bokeh_models": sum(models.values()),
                      "most_common_models": dict(models.most_common(8))}, indent=1))
    registry.close()
    return 0


def served(pages: int) -> int:
    """Server time of ``pages`` + 1 served pages (module docstring)."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from load_test import Server, wrapped_chromium
    from playwright.sync_api import sync_playwright
    server = Server(cpus="0")
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=wrapped_chromium(0, "1"))
            for _ in range(pages + 1):
                page = browser.new_page()
                page.goto(server.url)
                page.wait_for_selector(".amra-run", timeout=60_000)
                page.wait_for_timeout(1000)  # the deferred tabs arrive after the first paint
                page.close()
            browser.close()
        builds = server.page_builds_s()[1:]
    finally:
        server.stop()
    print(json.dumps({"pages": len(builds), "median_s": round(statistics.median(builds), 3),
                      "mean_s": round(statistics.mean(builds), 3), "min_s": round(min(builds), 3),
                      "max_s": round(max(builds), 3)}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
