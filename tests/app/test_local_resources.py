"""Stylesheets stay on this server even where Panel has no document to take its resource path from."""
from __future__ import annotations

from bokeh.models import ImportedStyleSheet

from app.local_resources import serve_resources_locally


def test_a_stylesheet_patched_without_a_document_stays_local():
    import panel.io.resources as resources
    import panel.reactive as reactive

    serve_resources_locally()
    serve_resources_locally()  # idempotent: one wrapper, not two
    assert reactive.patch_stylesheet.__wrapped__ is resources.patch_stylesheet.__wrapped__
    assert not getattr(resources.patch_stylesheet.__wrapped__, "amra_local", False)
    local = ImportedStyleSheet(url=f"{resources.LOCAL_DIST}css/loading.css")
    cdn = ImportedStyleSheet(url=f"{resources.CDN_DIST}css/markdown.css")
    for sheet in (local, cdn):
        # what a Markdown pane updated while detached from its document does (doc=None -> CDN_DIST)
        reactive.patch_stylesheet(sheet, resources.CDN_DIST)
        resources.patch_stylesheet(sheet, resources.CDN_DIST)
        assert not sheet.url.startswith("http"), sheet.url
        assert sheet.url.startswith(resources.LOCAL_DIST), sheet.url
