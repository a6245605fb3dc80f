"""PNG of a boundary map in the manner of the paper's Fig. 14 (matplotlib: a bare ``Figure`` on the Agg canvas, so
no GUI backend or global pyplot state is touched).

x: CG position [fraction of chord]; y: GJ [N m^2/rad], log scale. Every computed cell is a marker
coloured by its verdict; per column every flutter interval is a bar (strong: solid red; weak: light,
hatched; a fold approach: dotted brown); lines join the columns' fold GJ (brown) and strong-flutter
GJ (red, dashed), and the critical GJ (the larger, broad blue); optional marked points (e.g. the paper's unstable cases) are drawn as labelled
crosses. The title names the rotor, fidelity, aerodynamic model, advance ratio and elastic axis.
"""
from __future__ import annotations

import math
from typing import Iterable, Optional

VERDICT_COLOURS = {
    "stable": "#2ca02c",
    "flutter": "#d62728",
    "divergence": "#9467bd",
    "overspeed": "#ff7f0e",
    "no-autorotation": "#7f7f7f",
    "windmill-brake": "#17becf",
    "undetermined": "#bcbd22",
    "failed": "#000000",
}

#: the paper's unstable cases in axial flight (EA 32 %, CG 40 %), model-notes section 6
PAPER_AXIAL_POINTS = {"rigid": [(0.40, 100.0, "Fig. 10 (unstable)")],
                      "fem-coupled": [(0.40, 400.0, "Fig. 11 (unstable)")]}


def plot_map(bmap, path, marks: Optional[Iterable[tuple]] = None, title: Optional[str] = None) -> str:
    """Write ``bmap`` (:class:`~amra_core.boundary.BoundaryMap`) as a PNG to ``path``; ``marks``:
    ``(cg, gj, label)`` points to mark. Returns the path."""
    from matplotlib.figure import Figure
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    spec = bmap.spec
    fig = Figure(figsize=(8.0, 5.6), dpi=120)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    width = (spec.cg_values[1] - spec.cg_values[0]) * 0.6 if len(spec.cg_values) > 1 else 0.02
    for verdict, colour in VERDICT_COLOURS.items():
        pts = [(c.cg, c.gj_nm2) for c in bmap.cells if c.verdict == verdict]
        if pts:
            xs, ys = zip(*pts)
            ax.scatter(xs, ys, s=14, c=colour, marker="s", label=f"{verdict} ({len(pts)})", edgecolors="none",
                       zorder=2, alpha=0.6)
    # per column: every flutter interval as a bar, strong solid, weak light and hatched (issue 21 §2)
    seen = set()
    for col in bmap.columns:
        for iv in col.get("intervals") or []:
            if iv["kind"] != "flutter":
                continue
            style = "fold approach" if iv.get("fold_approach") else iv.get("strength", "strong")
            kw = {"strong": dict(facecolor="#d62728", alpha=0.55, hatch=None, edgecolor="#d62728"),
                  "weak": dict(facecolor="none", alpha=0.9, hatch="////", edgecolor="#f4a3a3"),
                  "fold approach": dict(facecolor="none", alpha=0.9, hatch="....", edgecolor="#8c564b")}[style]
            label = {"strong": "strong flutter interval", "weak": f"weak flutter window (damping ratio > "
                     f"-{spec.weak_damping:g})", "fold approach": "fold approach (merged into the fold)"}[style]
            ax.bar(col["cg"], iv["gj_hi_nm2"] - iv["gj_lo_nm2"], bottom=iv["gj_lo_nm2"], width=width, lw=0.8,
                   zorder=2.5, label=None if style in seen else label, **kw)
            seen.add(style)
    for key, colour, ls, label in (("fold_gj", "#8c564b", "-", "fold GJ (no autorotation below)"),
                                   ("flutter_gj", "#d62728", "--", "strong flutter GJ (top)")):
        pts = [(c["cg"], c.get(key)) for c in bmap.columns if c.get(key) is not None and math.isfinite(c[key])]
        if pts:
            xs, ys = zip(*pts)
            ax.plot(xs, ys, ls, color=colour, lw=1.6, marker="o", ms=3, zorder=3, label=label)
    crit = [(cg, g) for cg, g in bmap.critical_gj if g is not None and math.isfinite(g)]
    if crit:
        xs, ys = zip(*crit)
        ax.plot(xs, ys, "-", color="#1f77b4", lw=2.5, alpha=0.5, zorder=2.8, label="critical GJ (the larger)")
    for cg, g in bmap.critical_gj:
        if g is not None and not math.isfinite(g):
            ax.annotate("unstable at GJ max", (cg, spec.gj_max), textcoords="offset points", xytext=(0, 6),
                        ha="center", fontsize=7, rotation=90)
    for cg, gj, label in (marks or []):
        ax.plot([cg], [gj], "x", color="black", ms=10, mew=2.5, zorder=4)
        ax.annotate(label, (cg, gj), textcoords="offset points", xytext=(6, -12), fontsize=8)
    ax.set_yscale("log")
    ax.set_ylim(spec.gj_min / 1.15, spec.gj_max * 1.15)
    lo, hi = min(spec.cg_values), max(spec.cg_values)
    pad = max((hi - lo) * 0.05, 0.01)
    ax.set_xlim(lo - pad, hi + pad)
    ax.axvline(spec.ea, color="#1f77b4", ls=":", lw=1)
    ax.annotate("EA", (spec.ea, spec.gj_max), textcoords="offset points", xytext=(3, -10), fontsize=8,
                color="#1f77b4")
    ax.set_xlabel("CG position [fraction of chord from the leading edge]")
    ax.set_ylabel("torsional stiffness GJ [N m$^2$/rad]")
    flight = "axial flight" if spec.mu == 0 else f"mu = {spec.mu:g}"
    ax.set_title(title or (f"Stability boundary: {spec.rotor_name()}, {spec.fidelity}, {spec.aero}, {flight}, "
                           f"EA {spec.ea:g} c ({spec.method})"), fontsize=10)
    ax.grid(True, which="both", alpha=0.25)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    fig.tight_layout()
    fig.savefig(path, format="png")
    return str(path)
