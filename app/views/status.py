"""What the run is doing: the verdict card (class of the run with growth rate, frequency and
collapse time), its badge for the presentation header, the run status line and the note on live
changes. They change only in the session's deliveries (event loop, document locked)."""
from __future__ import annotations

import html
from typing import Optional

import panel as pn

from ..events import Applied, RunStatus, Started, VerdictNews

COLOURS = {"stable": "#2e7d32", "flutter": "#c62828", "divergence": "#ef6c00", "overspeed": "#6a1b9a",
           "no-autorotation": "#5d4037", "numerical-failure": "#424242"}


def units_as_shown(text: str) -> str:
    """The solver's plain-text units as the page writes them (N m^2/rad -> N m²/rad)."""
    return text.replace("m^2", "m²")


def _fmt(x, unit, digits=3):
    return "—" if x is None else f"{x:.{digits}g} {unit}"


#: verdicts whose instability is not the fitted oscillation: a negative growth rate there is not a decay
_NOT_THE_OSCILLATION = ("divergence", "no-autorotation", "overspeed", "windmill-brake")


def _growth(verdict) -> str:
    """The fitted growth rate; on a verdict whose instability is the rotor speed or the descent, a
    negative one says in place that only the oscillation on top decays (it read as a decay)."""
    g = verdict.growth_rate_per_s
    if g is not None and g <= 0.0 and verdict.verdict in _NOT_THE_OSCILLATION:
        return f"{_fmt(g, '1/s')} (the oscillation on top decays; the {verdict.verdict} is the instability)"
    return _fmt(g, "1/s")


def _frequency(verdict) -> str:
    """The run's dominant frequency; once the run has a growth rate, a missing one means that no
    oscillation was resolved: the largest deviation's spectrum peaks below two cycles per record
    (:func:`amra_core.verdict._dominant_frequency`), a slow one-way change such as a recovering or a
    collapsing rotor speed. ("A slow drift from the trim" read false beside a collapse far from any
    trim, and beside a stable run's decay.)"""
    if verdict.frequency_hz is None and verdict.growth_rate_per_s is not None:
        # (in few words: a longer text made the card's row six lines tall at 1280 x 720)
        return "none resolved: the largest deviation is a one-way change (1/rev is the trim's own)"
    return _fmt(verdict.frequency_hz, "Hz")


#: the card's words for a verdict's outcome (:data:`amra_core.verdict.OUTCOMES`): "runaway" alone,
#: on a rotor whose speed was still falling, read as a rotor running away upwards
OUTCOME_WORDS = {"runaway": "still growing or leaving its start at the end of the run (runaway)",
                 "neutral": "no measurable growth or decay (neutral)",
                 "rotor-speed-collapse": "rotor speed collapse"}


def verdict_html(verdict, final: bool, status: str = "", start_note: str = "", case: str = "",
                 pending: str = "") -> str:
    """HTML of the card for an :class:`amra_core.verdict.Verdict` (``None``: no run yet, or, with
    ``pending``, a run started whose first verdict is still to come: those words) of the run of
    ``case`` (a one-line description)."""
    if verdict is None:
        words = html.escape(pending) if pending else "no run yet. Press <i>Run</i>."
        return ("<div class='amra-verdict' data-verdict='none' style='padding:8px;border-radius:6px;"
                f"background:#eceff1'><b>Verdict:</b> {words}</div>")
    colour = COLOURS.get(verdict.verdict, "#37474f")
    state = "final" if final else "so far"
    outcome = getattr(verdict, "outcome", "") or ""
    cycle = getattr(verdict, "limit_cycle", None) or {}
    if outcome == "bounded-oscillation" and cycle:
        outcome += " (" + ", ".join(f"{k.replace('_', ' ')} {v:.3g}" for k, v in cycle.items()
                                    if isinstance(v, (int, float))) + ")"
    rows = [("Outcome", html.escape(OUTCOME_WORDS.get(outcome, outcome.replace("-", " ")) or "—")),
            # the envelope's fit over the run, not the linear eigenvalue the map and the Modes tab show
            # (a limit cycle fits ~0 where the mode's real part is +0.97 1/s): named apart
            ("Growth rate (run's fit)", _growth(verdict)),
            ("Frequency", _frequency(verdict)),
            ("Collapse time (Ω < 50 % of trim)", _fmt(verdict.collapse_time_s, "s")),
            ("Solver status", html.escape(status or "—"))]
    table = "".join(f"<tr><td style='padding-right:12px'>{k}</td><td><b>{v}</b></td></tr>" for k, v in rows)
    note = f"<div style='font-size:85%;margin-top:4px'>{html.escape(start_note)}</div>" if start_note else ""
    return (f"<div class='amra-verdict' data-verdict='{html.escape(verdict.verdict)}' data-final='{str(final).lower()}' "
            f"style='padding:8px;border-radius:6px;border-left:8px solid {colour};background:#fafafa'>"
            f"<div style='font-size:130%;color:{colour}'><b>{html.escape(verdict.verdict)}</b> "
            f"<span style='font-size:70%;color:#555'>({state})</span></div>"
            f"<div class='amra-verdict-case' style='font-size:85%;color:#555'>{html.escape(case)}</div>"
            f"<div class='amra-rotor-speed'><b>{html.escape(getattr(verdict, 'rotor_speed', '') or '')}</b></div>"
            f"<div>{html.escape(units_as_shown(verdict.explanation))}</div><table>{table}</table>{note}</div>")


def badge_html(verdict, final: bool, gj_nm2: Optional[float] = None) -> str:
    """The verdict for the header in presentation mode (on its dark background): the verdict word, the
    GJ it was found at (beside the header's GJ input, a class read "stable" as the verdict of a GJ
    typed after the run) and the rotor-speed collapse on a second line (one line overflowed a
    1280 px projector's header)."""
    if verdict is None:
        return "<span style='color:#eceff1;font-size:20px'>no run yet</span>"
    colour = {"stable": "#a5d6a7"}.get(verdict.verdict, "#ffab91")
    second = [f"at GJ {gj_nm2:.4g} N m²/rad"] if gj_nm2 is not None else []
    if verdict.collapse_time_s is not None:
        second.append(f"Ω collapsed at {verdict.collapse_time_s:.1f} s")
    second_line = "<br>" + " · ".join(second) if second else ""
    return (f"<span style='color:{colour};font-size:22px;font-weight:bold'>{html.escape(verdict.verdict)}</span>"
            f"<span style='color:#eceff1;font-size:16px'> ({'final' if final else 'so far'}){second_line}</span>")


def run_html(text: str) -> str:
    return f"<b>Run:</b> {html.escape(text)}"


def text(html_text: str = "", css_class: str = "", **kw) -> pn.widgets.StaticText:
    """A line of HTML that changes in place: set its ``value`` (a same-text set sends nothing).

    A ``StaticText``, not an HTML pane: in a template, an HTML pane's first update also rewrites its
    stylesheets, and Bokeh then walks the whole document's models (about 500) and sends three
    stylesheet models; a widget's update sends only its text. Under 16 sessions that walk was 18 %
    of the server's event loop (docs/upstream/panel-template-pane-first-update-stylesheets.md)."""
    kw.setdefault("sizing_mode", "stretch_width")
    return pn.widgets.StaticText(value=html_text, css_classes=[css_class] if css_class else [], **kw)


#: the card's words between Run and a run's first verdict
TRIMMING_WORDS = "the run is starting: finding its trimmed autorotation ..."
RUNNING_WORDS = "the run has started: its first verdict comes after about a second of it."


class StatusView(pn.viewable.Viewer):
    """Verdict card, run status and live-change note of one session."""

    def __init__(self, session, notify, **params):
        super().__init__(**params)
        self.card = text(verdict_html(None, False))
        self.badge = text(badge_html(None, False), "amra-badge", width=360, sizing_mode=None)
        self.run = text(run_html("idle"), "amra-run-status")
        self.note = text("", "amra-live-note")
        self.verdict, self.final, self.solver_status = None, False, ""
        self.notify = notify
        self.case = ""  #: the case of the run the card speaks of (set when a run starts)
        self.case_at_start = ""  #: ... as it started (before any live change)
        self.live_changes: list = []  #: the run's live changes so far, in words with their times
        self.gj_nm2: Optional[float] = None  #: the run's GJ [N m²/rad] (set at its start, moved by its changes)
        session.subscribe(RunStatus, lambda ev: setattr(self.run, "value", run_html(ev.text)))
        session.subscribe(Started, self._started)
        session.subscribe(VerdictNews, lambda ev: self.show(ev.verdict, ev.final, ev.status, ev.start_note))
        session.subscribe(Applied, self._applied)

    def _started(self, ev: Started) -> None:
        self.case_at_start = self.case
        self.live_changes = []
        self.pending(RUNNING_WORDS)
        if ev.start_note.startswith("no steady"):
            self.notify(f"no trim exists for this case: {ev.start_note}", "warning")

    def _applied(self, ev: Applied) -> None:
        how = "softened as scripted" if ev.values.get("scripted") else "applied live"
        self.gj_nm2 = ev.values.get("gj_nm2", self.gj_nm2)
        self.note.value = f"{how} at t = {ev.t_s:.2f} s: {ev.text(', ', unit=True)}"
        if not ev.values.get("scripted"):  # the card's case: the run's start, then every live change
            # (only the last was named: after GJ 300, CG 43 % and EA 30 % the card read "GJ 1500 ... live
            # at 15.15 s: EA 30 %" over a collapse that GJ 300 had started at 6.85 s)
            self.live_changes.append(f"{ev.text(', ', unit=True)} at {ev.t_s:.2f} s")
            self.case = f"{self.case_at_start} · live: {'; '.join(self.live_changes)}"

    def show(self, verdict, final: bool, status: str = "", start_note: str = "") -> None:
        self.verdict, self.final, self.solver_status = verdict, final, status
        self.card.value = verdict_html(verdict, final, status, start_note, self.case)
        self.badge.value = badge_html(verdict, final, self.gj_nm2)
        if final and status == "numerical-failure":
            self.notify(f"the run failed numerically: {verdict.explanation}")

    def pending(self, words: str) -> None:
        """A run started, its first verdict to come: the card says so (it read "no run yet. Press Run."
        beside "Run: running, t = 0.44 s", or kept the last case's "stable (final)")."""
        self.verdict, self.final, self.solver_status = None, False, ""
        self.card.value = verdict_html(None, False, pending=words)
        self.badge.value = "<span style='color:#eceff1;font-size:20px'>running ...</span>"

    def reset(self) -> None:
        self.show(None, False)
        self.run.value = run_html("idle")
        self.note.value = ""

    def __panel__(self):
        return pn.Column(self.card, self.run, self.note, width=380)
