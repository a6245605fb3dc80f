"""``amra validate``: every validation case of model-notes §6 in one self-contained HTML report
plus ``results.json``.

Sections (one module each): :mod:`.structure` (analytic beam and rotor-dynamics checks, convergence,
the McCutcheon fan plot), :mod:`.aero` (airfoil tables, Theodorsen function), :mod:`.autorotation`
(spanwise torque, vertical descent rate), :mod:`.system` (G-UNIV Table 1, the paper's Figs 10-13 as
time histories, the boundary map); :mod:`.report` writes the files. A case that raises is recorded
with status ``error`` and the report goes on.

``quick=True``: fewer elements, shorter runs and a 4-column coarse rigid axial map (about a minute
on two cores); the full report adds the fem-coupled and forward-flight maps (several minutes).
"""
from __future__ import annotations

import datetime as _dt
import platform
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Optional

from .common import CaseRecord, Section

SECTIONS = (
    ("structure", "Structure: analytic frequencies, static twist, convergence, fan plot",
     "Uniform-beam checks use a test blade of round numbers (m = 3 kg/m, I = 0.01 kg m, GJ = 1500 N m², EI = 1200 N m², "
     "L = 3.5 m) clamped at the root cut-out; the McCutcheon checks use the shipped preset."),
    ("aero", "Aerodynamics: airfoil tables and the Theodorsen function",
     "The solver's airfoil lookup and its time-domain unsteady aerodynamics (R.T. Jones two-state Wagner lag)."),
    ("autorotation", "Autorotation: torque distribution and vertical descent",
     "The McCutcheon preset in steady vertical autorotation (trimmed: thrust = weight, torque = 0)."),
    ("system", "System: G-UNIV teeter, the paper's unstable cases, the stability boundary",
     "The paper-boundary rotor (McCutcheon with uniform EA 32 %, CG 40 %) at the paper's GJ values, and the nominal "
     "McCutcheon blade; time marching from trim plus a small teeter and twist kick (model-notes §5)."),
)


@dataclass
class ValidationResult:
    sections: list
    meta: dict
    html_path: Path
    json_path: Path

    @property
    def cases(self) -> list:
        return [c for s in self.sections for c in s.cases]

    @property
    def failures(self) -> list:
        return [c for c in self.cases if c.status in ("fail", "error")]


def _git_commit() -> Optional[str]:
    try:
        root = Path(__file__).resolve().parents[2]
        out = subprocess.run(["git", "-C", str(root), "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                             timeout=5)
        return out.stdout.strip() or None
    except Exception:  # noqa: BLE001
        return None


def _versions() -> dict:
    import matplotlib
    import numpy
    import scipy
    from .. import __version__
    return {"amra_version": __version__, "python": platform.python_version(), "numpy": numpy.__version__,
            "scipy": scipy.__version__, "matplotlib": matplotlib.__version__}


def run_validation(out_dir, quick: bool = False, progress: Optional[Callable[[str], None]] = None,
                   sections: Optional[tuple] = None) -> ValidationResult:
    """Run every section, write ``report.html``, ``results.json`` and ``summary.md`` (markdown table)
    into ``out_dir`` (created),
    and return the :class:`ValidationResult`. ``progress(msg)`` receives one-line progress
    messages; ``sections`` optionally restricts to some section names."""
    import importlib
    import numpy as np
    from . import report

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    done = []
    for name, title, intro in SECTIONS:
        if sections is not None and name not in sections:
            continue
        sec = Section(name, title, quick=quick, progress=progress, intro=intro)
        ts = time.perf_counter()
        try:
            mod = importlib.import_module(f".{name}", __name__)
            with np.errstate(all="ignore"):
                mod.run(sec)
        except Exception as exc:  # noqa: BLE001 - a whole section failing still gives a report
            sec.add("section", f"{title} (whole section)", "", "", "n/a (error)", "", "", "error",
                    f"the section raised {type(exc).__name__}: {exc}")
        sec.wall_time_s = time.perf_counter() - ts
        if progress:
            progress(f"[{name}] section finished in {sec.wall_time_s:.1f} s")
        done.append(sec)
    cases = [c for s in done for c in s.cases]
    meta = {"mode": "quick" if quick else "full", "created": _dt.datetime.now().isoformat(timespec="seconds"),
            "wall_time_s": time.perf_counter() - t0, "git_commit": _git_commit(),
            "failures": [c.id for c in cases if c.status in ("fail", "error")]}
    try:
        meta.update(_versions())
    except Exception:  # noqa: BLE001
        pass
    html_path, json_path = out / "report.html", out / "results.json"
    report.write_json(json_path, done, meta)
    report.write_html(html_path, done, meta)
    (out / "summary.md").write_text(report.summary_markdown(cases, meta) + "\n", encoding="utf-8")
    return ValidationResult(done, meta, html_path, json_path)


__all__ = ["run_validation", "ValidationResult", "CaseRecord", "Section"]
