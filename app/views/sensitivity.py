"""Which conclusions of the map rest on guesses (issue 21 §6), in the map tab: a button walks the
current CG column again with each estimated rotor value -10 % and +10 %
(:func:`app.compute.sensitivity_study`, in the analysis pool); the answer is a table of the fold-
and flutter-GJ changes, a band on the map around each boundary at that CG
(:meth:`app.views.map.MapView.show_sensitivity`) and a CSV export.
"""
from __future__ import annotations

import html
import io
import math
import time
from typing import Callable

import pandas as pd
import panel as pn

from amra_core.export import table_csv

from .. import compute
from ..events import Sensitivity
from .status import text
from . import signed

TABLE_COLUMNS = ("estimate", "change_pct", "value", "unit", "fold_gj_nm2", "d_fold_gj_nm2", "flutter_gj_nm2",
                 "d_flutter_gj_nm2", "note")
HEADERS = ("Estimate", "Change [%]", "Value", "Unit", "Fold GJ [N m²/rad]", "Δ fold [N m²/rad]",
           "Flutter GJ [N m²/rad]", "Δ flutter [N m²/rad]", "Note")


def _gj(g) -> str:
    if g is None:
        return "none in range"
    return "unstable at the top of the range" if not math.isfinite(g) else f"{g:.0f}"


def _band(b) -> str:
    return "—" if b is None else f"{_gj(b[0])} to {_gj(b[1])} N m²/rad"


def display_frame(result: dict) -> pd.DataFrame:
    """The table as the page shows it: numbers to 4 significant digits, a missing boundary said in
    words, a missing change as a dash."""
    def delta(d):
        return "–" if d is None else signed(d, 0)
    rows = [(r["label"], f"{100.0 * r['change']:+.0f}", f"{r['value']:.4g}", r["unit"], _gj(r["fold_gj_nm2"]),
             delta(r["d_fold_gj_nm2"]), _gj(r["flutter_gj_nm2"]), delta(r["d_flutter_gj_nm2"]), r["note"] or "")
            for r in result["rows"]]
    return pd.DataFrame(rows, columns=list(HEADERS))


def summary_html(result: dict) -> str:
    b = result["baseline"]
    flutter = math.inf if b["flutter_at_gj_max"] else b["flutter_gj_nm2"]
    step = f"±{100 * result['step']:.0f} %"

    def boundary(name, base, band):  # "none in range, band 591 to 680" read as a contradiction
        if band is None:
            return f"{name} GJ {_gj(base)}"
        if base is None:
            return f"{name} GJ none in range at the baseline, {_band(band)} under some of the {step} changes"
        return f"{name} GJ {_gj(base)}, {_band(band)} over the baseline and every {step} change"
    return (f"<b>Sensitivity</b> at CG {100 * result['cg']:.1f} % chord ({html.escape(result['fidelity'])}, "
            f"μ {result['mu']:g}, every estimate {step}, {result['wall_time_s']:.0f} s): "
            f"{boundary('fold', b['fold_gj_nm2'], result['fold_band_nm2'])}; "
            f"{boundary('strong-flutter', flutter, result['flutter_band_nm2'])}. "
            "The bands are drawn on the map at this CG.")


class SensitivityView(pn.viewable.Viewer):
    """``case()`` returns ``(rotor, flight, settings, cg, map_spec)`` of the current case (raises with a
    message if it is invalid); ``submit(key, event, fn, *args)`` runs ``fn`` in the analysis pool
    (:class:`app.server.pool.LatestTasks`); ``on_bands(result)`` draws the bands on the map."""

    def __init__(self, session, case: Callable, submit: Callable, on_bands: Callable, notify: Callable, **params):
        super().__init__(**params)
        self.case, self.submit, self.on_bands, self.notify = case, submit, on_bands, notify
        self.result: dict | None = None
        self.button = pn.widgets.Button(name="Sensitivity at this CG: every estimate ±10 %", button_type="default",
                                        css_classes=["amra-sensitivity"], sizing_mode="stretch_width")
        self.busy = pn.indicators.Progress(value=-1, active=False, visible=False, sizing_mode="stretch_width",
                                           bar_color="info")
        self.info = text("Which conclusions rest on estimates? The button walks this CG column again with each "
                         "estimated rotor value 10 % lower and 10 % higher.", "amra-sensitivity-info")
        self.table = pn.pane.DataFrame(None, index=False, sizing_mode="stretch_width", name="sensitivity-table")
        self.download = pn.widgets.FileDownload(callback=self.csv, filename="amra-sensitivity.csv",
                                                label="Sensitivity table (CSV)", disabled=True,
                                                css_classes=["amra-export-sensitivity"], sizing_mode="stretch_width")
        session.subscribe(Sensitivity, lambda ev: self.show(ev.result))

    def start(self) -> None:
        try:
            rotor, flight, settings, cg, spec = self.case()
        except Exception as exc:  # noqa: BLE001 - RotorError, SettingsError, ValueError
            self.notify(f"cannot study the sensitivity of this case: {exc}")
            return
        self.busy.visible = self.busy.active = True
        self.info.value = (f"computing: 17 walks of the CG {100 * cg:.1f} % column ({html.escape(settings.fidelity)}), "
                            f"started {time.strftime('%H:%M:%S')}; the map's own walk takes a few seconds per column "
                            "for rigid and up to a minute for the FEM fidelities ...")
        self.submit("sensitivity", Sensitivity, compute.sensitivity_study, rotor, flight, settings, cg,
                    (spec.gj_min, spec.gj_max), spec.gj_rel_tol, spec.n_coarse)

    def show(self, result: dict) -> None:
        self.result = result
        self.busy.visible = self.busy.active = False
        self.table.object = display_frame(result)
        self.info.value = summary_html(result)
        self.download.disabled = False
        self.download.filename = f"amra-sensitivity-{result['fidelity']}-cg{100 * result['cg']:.0f}.csv"
        self.on_bands(result)

    def csv(self) -> io.StringIO:
        r = self.result or {"rows": []}
        meta = {k: r.get(k) for k in ("rotor", "fidelity", "rigid_spring", "aero", "mu", "ea", "cg", "step",
                                      "gj_min_nm2", "gj_max_nm2", "rel_tol")}
        rows = [[_cell(v) for v in (x["label"], 100.0 * x["change"], x["value"], x["unit"], x["fold_gj_nm2"],
                                    x["d_fold_gj_nm2"], x["flutter_gj_nm2"], x["d_flutter_gj_nm2"], x["note"])]
                for x in r["rows"]]  # one per perturbation, changes in %
        return io.StringIO(table_csv(TABLE_COLUMNS, rows, meta))

    def __panel__(self):
        return pn.Column(self.button, self.busy, self.info, self.table, self.download, sizing_mode="stretch_width")


def _cell(v):
    """A CSV field: empty for None, a text with a comma or quote quoted."""
    if v is None:
        return ""
    if isinstance(v, str) and ("," in v or '"' in v):
        return '"' + v.replace('"', '""') + '"'
    return v
