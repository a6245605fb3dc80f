"""The placeholder dashboard page builds and renders without a server."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import panel as pn
from bokeh.document import Document
from bokeh.models import Model
from pyviz_comms import Comm

from app.main import TITLE, create_app

REPO_ROOT = Path(__file__).resolve().parents[2]


def test_placeholder_does_not_import_solver():
    # The placeholder must stay independent of the solver package.
    code = "import sys, app.main; sys.exit('amra_core' in sys.modules)"
    subprocess.run([sys.executable, "-c", code], check=True, cwd=REPO_ROOT, timeout=120)


def test_placeholder_builds_fresh_template_per_call():
    first, second = create_app(), create_app()
    assert isinstance(first, pn.template.FastListTemplate)
    assert first is not second
    assert first.title == TITLE
    assert first.main[0] is not second.main[0]


def test_placeholder_renders_to_bokeh_model():
    template = create_app()
    doc, comm = Document(), Comm()
    root = pn.Column(*template.main).get_root(doc, comm=comm)
    assert isinstance(root, Model)
    (markdown_model,) = root.children
    for command in ("amra rotor", "amra modes", "amra trim", "amra simulate", "amra bench"):
        assert command in markdown_model.text
    for word in ("GJ", "EA", "CG", "advance ratio", "fidelity", "time histories", "boundary map"):
        assert word in markdown_model.text


def test_placeholder_saves_to_html_with_title(tmp_path):
    out = tmp_path / "placeholder.html"
    create_app().save(str(out), resources="inline")
    html = out.read_text(encoding="utf-8")
    # A static save titles the document "Panel"; the template's header carries ours.
    assert TITLE in html
    assert "amra simulate" in html
