"""``panel serve --setup app/warmup.py``: run once per server process before any session.

Compiles (or loads from Numba's cache) the kernels a session uses (:func:`app.compute.warm`), and
creates the process-wide map registry and the process pools, its map workers' included (warmed
too), so the first user does not wait for the JIT.
"""
from __future__ import annotations

#: allocations between two young-generation collections in the server process (CPython's default: 700)
GC_YOUNG_THRESHOLD = 20_000

if __name__ in ("panel_setup_module", "__main__"):
    import gc
    import logging
    import os

    import holoviews as hv

    import app.app  # noqa: F401 - the page's modules, imported once here rather than in the first session

    from app.compute import warm, warm_worker
    from app.server.map_jobs import get_registry
    from app.server.pool import get_analysis_pool, get_run_pool
    from app.server.settings import ServerSettings

    # the app's loggers ("amra.*", e.g. the server-side latency of live changes) at the server's level
    level = os.environ.get("AMRA_LOG_LEVEL", "info")
    logging.getLogger("amra").setLevel({"trace": "DEBUG"}.get(level, level).upper())
    get_registry(ServerSettings.from_env()).warm_map_pool()  # map workers started and warm too
    get_analysis_pool().submit(warm_worker)  # start and warm the pool processes too
    get_run_pool().submit(warm_worker)
    hv.extension("bokeh", logo=False)
    print(f"AMRA warm-up: kernels ready in {warm():.1f} s", flush=True)
    gc.freeze()  # the imported libraries stay: later collections do not walk them again
    # a page keeps ~37,000 objects the collector tracks (its Panel and Bokeh models): with CPython's
    # default thresholds (700, 10, 10) building one ran ~50 young collections, and every few pages a
    # full one that walks every open session's objects (23-100 ms measured, growing with the sessions
    # open). Fewer, larger young generations: served page build, median of 14 pages in three pairs
    # of runs, 0.287 / 0.309 / 0.300 s -> 0.270 / 0.287 / 0.278 s (the "page built in" log lines)
    gc.set_threshold(GC_YOUNG_THRESHOLD, 20, 20)
