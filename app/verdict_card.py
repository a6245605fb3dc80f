"""The verdict card: class of the run (stable, flutter, divergence, ...) with growth rate,
frequency and collapse time once known."""
from __future__ import annotations

import html

import panel as pn

from .live_text import LiveText

COLOURS = {"stable": "#2e7d32", "flutter": "#c62828", "divergence": "#ef6c00", "overspeed": "#6a1b9a",
           "no-autorotation": "#5d4037", "numerical-failure": "#424242"}


def _fmt(x, unit, digits=3):
    return "—" if x is None else f"{x:.{digits}g} {unit}"


def verdict_html(verdict, final: bool, status: str = "", start_note: str = "") -> str:
    """HTML of the card for an :class:`amra_core.verdict.Verdict` (``None``: no run yet)."""
    if verdict is None:
        return ("<div class='amra-verdict' data-verdict='none' style='padding:8px;border-radius:6px;"
                "background:#eceff1'><b>Verdict:</b> no run yet. Press <i>Run</i>.</div>")
    colour = COLOURS.get(verdict.verdict, "#37474f")
    state = "final" if final else "so far"
    rows = [("Growth rate", _fmt(verdict.growth_rate_per_s, "1/s")),
            ("Frequency", _fmt(verdict.frequency_hz, "Hz")),
            ("Collapse time (Ω < 50 % of trim)", _fmt(verdict.collapse_time_s, "s")),
            ("Solver status", html.escape(status or "—"))]
    table = "".join(f"<tr><td style='padding-right:12px'>{k}</td><td><b>{v}</b></td></tr>" for k, v in rows)
    note = f"<div style='font-size:85%;margin-top:4px'>{html.escape(start_note)}</div>" if start_note else ""
    return (f"<div class='amra-verdict' data-verdict='{html.escape(verdict.verdict)}' data-final='{str(final).lower()}' "
            f"style='padding:8px;border-radius:6px;border-left:8px solid {colour};background:#fafafa'>"
            f"<div style='font-size:130%;color:{colour}'><b>{html.escape(verdict.verdict)}</b> "
            f"<span style='font-size:70%;color:#555'>({state})</span></div>"
            f"<div>{html.escape(verdict.explanation)}</div><table>{table}</table>{note}</div>")


class VerdictCard(pn.viewable.Viewer):
    def __init__(self, **params):
        super().__init__(**params)
        # a Div, not an HTML pane: the "so far" card changes while a run streams (app.live_text)
        self.pane = LiveText(verdict_html(None, False), name="verdict")
        self.verdict = None

    def show(self, verdict, final: bool, status: str = "", start_note: str = "") -> None:
        self.verdict = verdict
        self.pane.object = verdict_html(verdict, final, status, start_note)

    def reset(self) -> None:
        self.show(None, False)

    def __panel__(self):
        return self.pane
