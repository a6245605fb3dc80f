"""AMRA dashboard entry point: ``panel serve app/main.py --setup app/warmup.py`` (``amra serve``).

Panel runs this script once per browser session; :func:`create_app` builds that session's
objects (controls, run worker, buffer, views) and registers their clean-up. Server-wide state
(the map registry) lives in ``pn.state.cache``; there are no mutable module globals.
"""
from __future__ import annotations

import holoviews as hv
import panel as pn

from app import browser_tuning, message_tuning, socket_tuning
from app.dashboard import Dashboard
from app.layout import TITLE
from app.local_resources import serve_resources_locally
from app.map_jobs import get_registry
from app.settings import ServerSettings
from app.url_sync import apply_session_query, sync_url

__all__ = ["TITLE", "create_app"]


def create_app():
    """Build a fresh page for one session (needs a server session for URL sync and the pump)."""
    serve_resources_locally()
    pn.extension(notifications=True, throttled=True)
    hv.extension("bokeh", logo=False)
    # 2-D canvas, not WebGL (HoloViews' default): the plots are small, and on a machine without a
    # GPU each WebGL plot is drawn in software and copied to a canvas on every repaint
    hv.renderer("bokeh").webgl = False
    settings = ServerSettings.from_env()
    dash = Dashboard(settings, registry=get_registry(settings))
    page = dash.__panel__()
    if pn.state.curdoc is not None and pn.state.curdoc.session_context is not None:
        apply_session_query(dash.controls, dash.notify)
        browser_tuning.install(pn.state.curdoc, sliders_on_release=pn.config.throttled)
        message_tuning.install()  # once per process: Bokeh keeps the list of synced models
        socket_tuning.install()  # once per process: a message's frames are written in one go
        dash.start_periodic()

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
    create_app().servable(title=TITLE)
elif __name__ == "__main__":
    pn.serve(create_app, port=5006, address="127.0.0.1", show=False)
