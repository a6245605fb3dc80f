"""Writing the validation report: one self-contained HTML file (PNG figures embedded as base64
data URIs, inline CSS, no external links) and ``results.json``; plus text and markdown summaries."""
from __future__ import annotations

import html
import json
import math
from pathlib import Path

from .common import _clean

STATUS_COLOURS = {"pass": "#1a7f37", "fail": "#cf222e", "info": "#0969da", "error": "#8250df", "skipped": "#6e7781"}

CSS = """
body{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;margin:1.5em auto;max-width:1200px;color:#1f2328;padding:0 1em}
h1{font-size:1.6em}h2{border-bottom:1px solid #d0d7de;padding-bottom:.2em;margin-top:2em}
table{border-collapse:collapse;font-size:.82em;margin:.6em 0 1.2em 0;width:100%}
th,td{border:1px solid #d0d7de;padding:3px 6px;vertical-align:top;text-align:left}
th{background:#f6f8fa}td.num{text-align:right;white-space:nowrap}
.st{font-weight:600;color:#fff;border-radius:4px;padding:1px 6px;white-space:nowrap}
.fig{margin:1em 0 2em 0}.fig img{max-width:100%;border:1px solid #eee}.cap{font-size:.85em;color:#57606a}
.meta{font-size:.85em;color:#57606a}.note{font-size:.92em;color:#57606a}
pre{background:#f6f8fa;padding:.6em;font-size:.78em;overflow-x:auto}
.counts span{margin-right:1em}
"""


def _fmt(v) -> str:
    if v is None:
        return "—"
    if isinstance(v, float):
        if not math.isfinite(v):
            return str(v)
        return f"{v:.6g}"
    return str(v)


def _badge(status: str) -> str:
    return f'<span class="st" style="background:{STATUS_COLOURS.get(status, "#444")}">{html.escape(status)}</span>'


def counts(cases) -> dict:
    out = {}
    for c in cases:
        out[c.status] = out.get(c.status, 0) + 1
    return out


def _case_table(cases) -> str:
    e = html.escape
    rows = ["<table><tr><th>id</th><th>case</th><th>reference</th><th>source</th><th>value</th><th>unit</th>"
            "<th>tolerance</th><th>status</th><th>note</th></tr>"]
    for c in cases:
        rows.append(f'<tr id="{e(c.id)}"><td><code>{e(c.id)}</code></td><td>{e(c.title)}</td><td class="num">{e(_fmt(c.reference))}</td>'
                    f"<td>{e(c.reference_source)}</td><td class=\"num\">{e(_fmt(c.value))}</td><td>{e(c.unit)}</td>"
                    f"<td>{e(c.tolerance)}</td><td>{_badge(c.status)}</td><td class=\"note\">{e(c.note)}</td></tr>")
    rows.append("</table>")
    return "\n".join(rows)


def write_html(path: Path, sections, meta: dict) -> None:
    e = html.escape
    all_cases = [c for s in sections for c in s.cases]
    n = counts(all_cases)
    parts = ["<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\">",
             "<title>AMRA validation report</title>", f"<style>{CSS}</style></head><body>",
             "<h1>AMRA validation report</h1>",
             f"<p class=\"meta\">{e(meta['mode'])} run, {e(meta['created'])}, {meta['wall_time_s']:.0f} s wall time; "
             f"amra {e(str(meta.get('amra_version')))}, solver {e(str(meta.get('git_commit')))}; "
             f"Python {e(meta.get('python', ''))}, numpy {e(meta.get('numpy', ''))}, scipy {e(meta.get('scipy', ''))}, "
             f"matplotlib {e(meta.get('matplotlib', ''))}.</p>",
             "<p>Every validation case of model-notes §6: the reference and where it comes from, the acceptance rule, "
             "the figure this model obtains, and pass or fail, with a sentence on why any discrepancy is expected. "
             "<b>info</b> cases are reported without an acceptance rule; <b>error</b> means the computation raised (the "
             "message is in the note); <b>skipped</b> cases are not run in this mode.</p>",
             "<p class=\"counts\">" + "".join(f"<span>{_badge(k)} {v}</span>" for k, v in sorted(n.items())) + "</p>",
             "<h2>Summary</h2>", _case_table(all_cases)]
    if meta.get("failures"):
        parts.append("<p><b>Failing cases:</b> " + ", ".join(f'<a href="#{e(i)}">{e(i)}</a>' for i in meta["failures"]) + "</p>")
    for s in sections:
        parts.append(f'<h2 id="sec-{e(s.name)}">{e(s.title)}</h2>')
        if s.intro:
            parts.append(f"<p>{e(s.intro)}</p>")
        parts.append(f"<p class=\"meta\">section wall time {s.wall_time_s:.1f} s</p>")
        parts.append(_case_table(s.cases))
        for title, header, rows in s.tables:
            parts.append(f"<h3>{e(title)}</h3><table><tr>" + "".join(f"<th>{e(h)}</th>" for h in header) + "</tr>")
            for r in rows:
                parts.append("<tr>" + "".join(f"<td>{e(str(x))}</td>" for x in r) + "</tr>")
            parts.append("</table>")
        for f in s.figures:
            parts.append(f'<div class="fig"><h3>{e(f.title)}</h3><img alt="{e(f.title)}" src="{f.data_uri}">'
                         f'<div class="cap">{e(f.caption)}</div></div>')
        if s.messages:
            parts.append("<details><summary>Errors and warnings in this section</summary><pre>"
                         + e("\n\n".join(s.messages)) + "</pre></details>")
    parts.append("</body></html>")
    path.write_text("\n".join(parts), encoding="utf-8")


def write_json(path: Path, sections, meta: dict) -> dict:
    doc = {"meta": meta,
           "counts": counts([c for s in sections for c in s.cases]),
           "sections": [{"name": s.name, "title": s.title, "wall_time_s": s.wall_time_s,
                         "figures": [f.title for f in s.figures], "messages": s.messages} for s in sections],
           "cases": [c.to_dict() for s in sections for c in s.cases]}
    doc = _clean(doc)
    path.write_text(json.dumps(doc, indent=1, ensure_ascii=False, allow_nan=False), encoding="utf-8")
    return doc


def _short(v, width) -> str:
    s = _fmt(v)
    return s if len(s) <= width else s[: width - 1] + "…"


def summary_text(cases) -> str:
    lines = [f"{'case':52s} {'reference':>14s} {'value':>16s}  status", "-" * 92]
    for c in cases:
        lines.append(f"{_short(c.id, 52):52s} {_short(c.reference, 14):>14s} {_short(c.value, 16):>16s}  {c.status}")
    n = counts(cases)
    lines.append("-" * 92)
    lines.append("  ".join(f"{k}: {v}" for k, v in sorted(n.items())))
    return "\n".join(lines)


def summary_markdown(cases, meta: dict) -> str:
    def cell(v):
        return _fmt(v).replace("|", "\\|").replace("\n", " ")
    n = counts(cases)
    out = [f"Mode: {meta.get('mode')}, {meta.get('created')}, wall time {meta.get('wall_time_s', 0):.0f} s, "
           f"solver commit {meta.get('git_commit')}. Counts: " + ", ".join(f"{k} {v}" for k, v in sorted(n.items())) + ".",
           "", "| id | case | reference | value | unit | tolerance | status |", "|---|---|---|---|---|---|---|"]
    for c in cases:
        out.append(f"| `{c.id}` | {cell(c.title)} | {cell(c.reference)} | {cell(c.value)} | {cell(c.unit)} | "
                   f"{cell(c.tolerance)} | **{c.status}** |")
    return "\n".join(out)
