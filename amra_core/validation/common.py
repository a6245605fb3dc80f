"""Shared pieces of the validation report: the case record, figures, and error containment.

Every check is one :class:`CaseRecord`. A section module builds its records and figures inside a
:class:`Section`; :meth:`Section.guard` runs one block of work and, if it raises, records the
block's cases with status ``error`` and the message instead of stopping the report.
"""
from __future__ import annotations

import base64
import io
import math
import time
import traceback
from dataclasses import asdict, dataclass, field
from typing import Any, Callable, Optional

STATUSES = ("pass", "fail", "info", "error", "skipped")


@dataclass(frozen=True)
class CaseRecord:
    """One validation case.

    ``reference``: the value (or text) it is checked against, ``reference_source`` where that
    comes from; ``value``: the figure this model obtained (number or short text), in ``unit``;
    ``tolerance``: the acceptance rule in words; ``status``: pass | fail | info | error | skipped;
    ``note``: why a discrepancy is expected, or what was done. ``error`` is the signed relative
    error where one is defined; ``details`` any supporting numbers (JSON-serialisable)."""

    id: str
    section: str
    title: str
    reference: Any
    reference_source: str
    value: Any
    unit: str
    tolerance: str
    status: str
    note: str = ""
    error: Optional[float] = None
    details: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        d = asdict(self)
        return {k: _clean(v) for k, v in d.items()}


def _clean(v):
    """JSON-safe copy: numpy scalars to Python, non-finite floats to None."""
    try:
        import numpy as np
        if isinstance(v, np.generic):
            v = v.item()
        elif isinstance(v, np.ndarray):
            v = v.tolist()
    except ImportError:  # pragma: no cover
        pass
    if isinstance(v, float):
        return v if math.isfinite(v) else None
    if isinstance(v, dict):
        return {str(k): _clean(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_clean(x) for x in v]
    return v


@dataclass
class Figure:
    title: str
    data_uri: str  #: "data:image/png;base64,..."
    caption: str = ""


@dataclass
class Section:
    """Cases, figures and HTML tables of one report section."""

    name: str
    title: str
    quick: bool = False
    progress: Optional[Callable[[str], None]] = None
    intro: str = ""
    cases: list = field(default_factory=list)
    figures: list = field(default_factory=list)
    tables: list = field(default_factory=list)  #: (title, header list, rows list of lists)
    messages: list = field(default_factory=list)
    wall_time_s: float = 0.0

    # -- records -----------------------------------------------------------------------------
    def add(self, id, title, reference, reference_source, value, unit, tolerance, status, note="",
            error=None, details=None) -> CaseRecord:
        rec = CaseRecord(f"{self.name}.{id}", self.name, title, reference, reference_source, value, unit,
                         tolerance, status, note, error, details or {})
        self.cases.append(rec)
        return rec

    def check(self, id, title, reference, reference_source, value, unit, tolerance_text, ok: bool,
              note="", error=None, details=None) -> CaseRecord:
        return self.add(id, title, reference, reference_source, value, unit, tolerance_text,
                        "pass" if ok else "fail", note, error, details)

    def log(self, msg: str) -> None:
        if self.progress:
            self.progress(f"[{self.name}] {msg}")

    def guard(self, what: str, fn: Callable[[], Any], fallback_cases=()):
        """Run ``fn``; on an exception record ``fallback_cases`` (dicts with id, title, reference,
        reference_source, unit, tolerance) as ``error`` (or one generic error case) and go on."""
        t0 = time.perf_counter()
        self.log(f"{what} ...")
        try:
            out = fn()
            self.log(f"{what}: done in {time.perf_counter() - t0:.1f} s")
            return out
        except Exception as exc:  # noqa: BLE001 - the report must survive any one case
            msg = f"{type(exc).__name__}: {exc}"
            self.log(f"{what}: ERROR {msg}")
            self.messages.append(f"{what}: {msg}\n{traceback.format_exc(limit=6)}")
            done = {c.id for c in self.cases}
            specs = list(fallback_cases) or [dict(id=what.replace(" ", "-"), title=what, reference="",
                                                  reference_source="", unit="", tolerance="")]
            for spec in specs:
                if f"{self.name}.{spec['id']}" in done:
                    continue
                self.add(spec["id"], spec["title"], spec.get("reference", ""), spec.get("reference_source", ""),
                         "n/a (error)", spec.get("unit", ""), spec.get("tolerance", ""), "error",
                         f"the computation raised {msg}")
            return None

    def figure(self, title: str, make: Callable[[], Any], caption: str = "") -> None:
        """Add a figure built by ``make()`` (a matplotlib Figure); a failure is logged, not fatal."""
        try:
            fig = make()
            if fig is None:
                return
            uri = fig if isinstance(fig, str) and fig.startswith("data:image/") else fig_to_data_uri(fig)
            self.figures.append(Figure(title, uri, caption))
        except Exception as exc:  # noqa: BLE001
            msg = f"figure '{title}' failed: {type(exc).__name__}: {exc}"
            self.log(msg)
            self.messages.append(msg + "\n" + traceback.format_exc(limit=6))


def new_figure(w=7.5, h=4.5, **kw):
    """A matplotlib Figure on the Agg canvas (no pyplot, no global state)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure as MplFigure
    kw.setdefault("layout", "constrained")
    fig = MplFigure(figsize=(w, h), dpi=100, **kw)
    FigureCanvasAgg(fig)
    return fig


def fig_to_data_uri(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90, bbox_inches="tight")
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def rel_err(value: float, ref: float) -> float:
    return float(value / ref - 1.0)


def pct(x: Optional[float], digits: int = 3) -> str:
    return "n/a" if x is None or not math.isfinite(x) else f"{100 * x:+.{digits}g} %"
