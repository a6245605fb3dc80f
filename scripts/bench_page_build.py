"""Server time to build one dashboard page, in this process and without a browser (a benchmark, not
a test): the session's :class:`app.app.Dashboard`, its layout and the Bokeh document of the page with
its first tab (the boundary map; outside a server Panel builds the deferred tabs area at once).

The served figure (``amra serve``'s "page built in" log lines, ``scripts/load_test.py``) leaves the
deferred tabs out and varies by +/- 40 ms from page to page with the server's garbage collections;
this one, averaged over many pages in a quiet process, shows what a change to the page costs.
Pin it to one core for comparable figures:

    taskset -c 0 python scripts/bench_page_build.py [--pages 30]
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
    ap.add_argument("--pages", type=int, default=30)
    args = ap.parse_args(argv)
    import holoviews as hv
    import panel as pn
    from bokeh.document import Document

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
        with pn.io.hold(freeze=True):
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


if __name__ == "__main__":
    sys.exit(main())
