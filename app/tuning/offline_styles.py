"""Page resources (JS, CSS) from this server, never a CDN: classrooms and team servers are often offline.

Reproducer and upstream report: ``docs/upstream/panel-hidden-tab-stylesheets-cdn.md``. The
work-around is applied only on :data:`CHECKED` (the versions it was verified on); on any other
Panel the page may fetch two stylesheets from the CDN, which ``test_every_view_tab_opens_offline``
reports, so an upgrade re-checks whether the bug is still there.

Setting Bokeh's resource mode to ``server`` covers the page as first rendered. It does not cover
one path in Panel 1.9.4: a pane updated while its model is outside the document (a Markdown pane in
a tab that is not shown: Panel's dynamic tabs detach the hidden tab's models but still update them)
recomputes its stylesheets with ``doc=None``. Panel then has no ``dist_url`` to go by and rewrites
its stylesheets to the CDN (``panel.io.resources.patch_stylesheet(sheet, CDN_DIST)``). Those
``ImportedStyleSheet`` objects are shared by every model of the session's document (Panel caches one
per URL and document), so every view switches to ``cdn.holoviz.org/.../loading.css`` and
``markdown.css``: measured, 12 outside requests and 3 console errors offline for a first switch to
the "Modes & root locus" tab while the map's status line updated (``test_every_view_tab_opens_offline``).

:func:`serve_resources_locally` sets the mode and wraps ``patch_stylesheet`` so that, while the
process serves its resources itself, a request to patch towards the CDN patches towards this
server's own copy (the same path Panel uses when the document is known) instead. It is idempotent.
"""
from __future__ import annotations

__all__ = ["serve_resources_locally"]

CHECKED = ("1.9.4",)  #: Panel versions with the bug and this fix verified


def _local_instead_of_cdn(patch):
    from panel.io.resources import CDN_DIST, get_dist_path, use_cdn

    def patch_stylesheet(stylesheet, dist_url):
        if dist_url == CDN_DIST and not use_cdn():
            dist_url = get_dist_path(cdn=False)
        return patch(stylesheet, dist_url)

    patch_stylesheet.amra_local = True
    patch_stylesheet.__wrapped__ = patch
    return patch_stylesheet


def serve_resources_locally() -> None:
    """Serve Bokeh and Panel JS/CSS from this server and keep later stylesheet patches local."""
    from importlib.metadata import version

    import panel.io.resources as resources
    import panel.reactive as reactive
    from bokeh.settings import settings

    settings.resources.set_value("server")
    if version("panel") not in CHECKED:
        return
    for module in (resources, reactive):  # theme.base imports it from panel.io.resources per call
        if not getattr(module.patch_stylesheet, "amra_local", False):
            module.patch_stylesheet = _local_instead_of_cdn(module.patch_stylesheet)
