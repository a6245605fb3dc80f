"""AMRA dashboard entry point: ``panel serve app/main.py --setup app/warmup.py`` (``amra serve``).

Panel runs this script once per browser session; :func:`create_app` builds that session's
:class:`app.app.Dashboard` and registers its clean-up. Server-wide state (map registry, process
pools) lives in ``pn.state.cache``; there are no mutable module globals.
"""
from __future__ import annotations

import holoviews as hv
import panel as pn

from app.app import TITLE, Dashboard
from app.controls import apply_session_query, sync_url
from app.server.map_jobs import get_registry
from app.server.pool import get_run_pool
from app.server.settings import ServerSettings
from app.tuning.offline_styles import serve_resources_locally

__all__ = ["TITLE", "configure_holoviews", "create_app"]


#: the HoloViews elements the views draw (each gets the page's default options)
HOLOVIEWS_ELEMENTS = ("Curve", "Points", "Scatter", "QuadMesh", "VLine", "HLine", "Overlay")


def configure_holoviews() -> None:
    """HoloViews' Bokeh renderer as the page wants it (process-wide settings, applied per page)."""
    if "bokeh" not in hv.Store.renderers:  # loaded once per process (--setup app/warmup.py), not per page
        hv.extension("bokeh", logo=False)
    # 2-D canvas, not WebGL: the plots are small, and without a GPU WebGL is drawn in software
    hv.renderer("bokeh").webgl = False
    # no HoloViews theme: rendering the first HoloViews view set it as the document's theme, and the
    # live plots (plain Bokeh figures) then changed their titles to black 12 pt mid-session
    hv.renderer("bokeh").theme = None
    # no plot takes the mouse wheel until its wheel-zoom tool is chosen: HoloViews activates it by
    # default, and scrolling the page down through the tabs zoomed the fan plot under the pointer
    hv.opts.defaults(*(getattr(hv.opts, element)(active_tools=["pan"]) for element in HOLOVIEWS_ELEMENTS))


def create_app():
    """Build a fresh page for one session."""
    serve_resources_locally()
    pn.extension(notifications=True, throttled=True)
    configure_holoviews()
    settings = ServerSettings.from_env()
    doc = pn.state.curdoc
    served = doc is not None and doc.session_context is not None
    dash = Dashboard(settings, registry=get_registry(settings), run_pool=get_run_pool() if served else None, doc=doc)
    if served:  # the link's values first, so the page is built for them (presentation mode)
        apply_session_query(dash.controls, dash.notify)
    page = dash.__panel__()
    if served:

        def loaded():  # after the first paint
            sync_url(dash.controls)
            dash.refresh_analyses()
        pn.state.onload(loaded)
        pn.state.on_session_destroyed(dash.close)
    else:
        dash.refresh_analyses()
    page.dashboard = dash  # handle for tests and the benchmark
    return page


if __name__.startswith("bokeh"):
    import logging
    import time

    t0 = time.perf_counter()
    with pn.io.hold(freeze=True):  # one recomputation of the document's references, not one per root
        create_app().servable(title=TITLE)  # the page's Bokeh models are built here
    logging.getLogger("amra.page").info("page built in %.3f s (server time)", time.perf_counter() - t0)
elif __name__ == "__main__":
    pn.serve(create_app, port=5006, address="127.0.0.1", show=False)
