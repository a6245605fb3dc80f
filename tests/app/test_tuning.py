"""app/tuning: stylesheets stay on this server even where Panel has no document to take its resource
path from (on the checked Panel versions only); and nothing else in app/ touches framework internals."""
from __future__ import annotations

from bokeh.models import ImportedStyleSheet

import pytest

from app.tuning.offline_styles import CHECKED, serve_resources_locally


def test_a_stylesheet_patched_without_a_document_stays_local():
    from importlib.metadata import version
    if version("panel") not in CHECKED:
        pytest.skip(f"the work-around is for Panel {CHECKED} only (docs/upstream/)")
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


def test_no_module_outside_app_tuning_replaces_framework_attributes():
    """Only app/tuning may assign to attributes of panel, bokeh, tornado or holoviews objects."""
    import re
    from pathlib import Path
    root = Path(__file__).resolve().parents[2] / "app"
    bad = re.compile(r"^\s*(panel|pn|bokeh|tornado|hv|holoviews|resources|reactive)\.[\w.]+\s*=[^=]", re.M)
    offenders = [str(p.relative_to(root)) for p in root.rglob("*.py")
                 if "tuning" not in p.parts and (bad.search(p.read_text()) or "prototype" in p.read_text())]
    assert offenders == []
