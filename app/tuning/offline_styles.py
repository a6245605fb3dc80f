"""Page resources (JS, CSS) from this server, never a CDN: classrooms and team servers are often offline.

Bokeh's resource mode ``server`` covers the page as first rendered. In Panel 1.9.4 a pane updated
while detached from its document (a hidden tab of dynamic ``Tabs``) recomputes its stylesheets
with ``doc=None`` and rewrites the session's shared ``ImportedStyleSheet``s to the CDN. The bug,
its reproducer and the fix to propose: ``docs/upstream/panel-hidden-tab-stylesheets-cdn.md``.
:func:`serve_resources_locally` sets the mode and, on the :data:`CHECKED` Panel versions only,
wraps ``patch_stylesheet`` so that a patch towards the CDN goes to this server's own copy.
``test_every_view_tab_opens_offline`` shows after an upgrade whether the bug is still there.
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
