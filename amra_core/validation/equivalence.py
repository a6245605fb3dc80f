"""The equivalent rigid blade against the FEM (issue 21 item 5): the cyclic flap frequency for
several hub-inertia estimates, the static twist of the two torsion springs, and the fold GJ of the
rigid blade with either spring beside the fem-coupled blade's."""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..column import walk_column
from ..flight import FlightCondition, SolverSettings
from ..modes import mode_labels, solve_modes
from ..rigid_equivalence import static_torsion_coefficients, torsion_spring_nm_rad
from ..rotor_io import load_preset
from .common import Section

SRC = "model-notes §2 (equivalent root springs) and §8 (rigid vs FEM torsion; forward-of-EA flutter)"
HUB_INERTIAS = (0.12, 1.0, 3.0)
FOLD_CG, FOLD_EA = 0.40, 0.32


def _cyclic_flap_hz(rotor, fidelity, omega):
    sol = solve_modes(rotor, fidelity, 10, omega)
    f = np.sqrt(np.abs(sol.eigenvalues)) / (2 * np.pi)
    return float(next(x for lab, x in zip(mode_labels(sol), f) if lab == "flap 1 (cyclic)"))


def run(sec: Section, n_el: int) -> None:
    base = load_preset("paper-boundary")
    om = 150.0 / base.radius_m
    rows, worst = [], 0.0
    for hub in HUB_INERTIAS:
        rot = dataclasses.replace(base, hub_teeter_inertia_kg_m2=hub)
        fr, ff = _cyclic_flap_hz(rot, "rigid", om), _cyclic_flap_hz(rot, "fem-coupled", om)
        worst = max(worst, abs(fr / ff - 1))
        rows.append(f"{hub:g} kg m²: rigid {fr:.1f} Hz, fem-coupled {ff:.1f} Hz")
    sec.check("equivalence.cyclic-flap", f"Rigid cyclic flap frequency vs the FEM's at {om:.1f} rad/s, hub teeter "
              "inertia 0.12 / 1 / 3 kg m² (GJ 1500)", "FEM pinned-free (cyclic flap) mode", SRC, "; ".join(rows), "Hz",
              "within 5 % for every hub inertia", worst < 0.05,
              f"largest difference {worst:.1%}. The rigid blade's effective teeter inertia and cyclic root spring are "
              "derived from the FEM mode (amra_core.rigid_equivalence); with the estimated hub inertia alone the rigid "
              "mode was 29.4 / 22.0 / 15.5 Hz against 15.2 / 14.9 / 14.0 Hz.")

    w0, tip0 = static_torsion_coefficients(0.0)
    ratio = w0 * (math.pi / 2) ** 2
    k_f, k_s = torsion_spring_nm_rad(base, "frequency"), torsion_spring_nm_rad(base, "static")
    sec.check("equivalence.static-twist", "Static twist under an r²-distributed moment: uniform cantilever vs the "
              "frequency-matched root spring", "9/14 = 0.643 and 4/π² = 0.405 M L/GJ", SRC,
              f"{w0:.3f} vs {4 / math.pi ** 2:.3f} M L/GJ (×{ratio:.2f}); this rotor (10 % cut-out): ×{k_f / k_s:.2f}",
              "M L/GJ", "analytic, 1e-9", abs(w0 - 9 / 14) < 1e-9,
              f"load-weighted twist ∫tθ/M (the tip twist is {tip0:.3f}). The default rigid spring (π/2)² GJ/L matches "
              "the first torsion frequency and is statically stiffer; --rigid-spring static matches this twist "
              f"(k = {k_s * base.blade_length_m / 1500.0:.3f} GJ/L for this blade).")

    tol = 0.05 if sec.quick else 0.02
    folds = {}
    for label, fid, spring in (("rigid, frequency spring", "rigid", "frequency"),
                               ("rigid, static spring", "rigid", "static"),
                               ("fem-coupled", "fem-coupled", "frequency")):
        def go(fid=fid, spring=spring):
            w = walk_column(base.with_overrides(x_ea=FOLD_EA), FlightCondition(),
                            SolverSettings(fidelity=fid, n_elements=n_el, rigid_spring=spring), FOLD_CG, 30.0, 3000.0,
                            rel_tol=tol)
            return w.fold_gj_nm2
        folds[label] = sec.guard(f"fold GJ {label}", go)
    f_freq, f_stat, f_fem = (folds[k] for k in ("rigid, frequency spring", "rigid, static spring", "fem-coupled"))
    ok = None not in (f_freq, f_stat, f_fem)
    closer = ok and abs(f_stat / f_fem - 1) < abs(f_freq / f_fem - 1)

    def fmt(g):
        return "no fold" if g is None else f"{g:.0f}"
    sec.check("equivalence.fold-gj", f"Fold GJ, axial, EA {FOLD_EA:g}, CG {FOLD_CG:g}: rigid (both torsion springs) "
              "beside fem-coupled", "fem-coupled", SRC,
              " / ".join(f"{k}: {fmt(v)}" for k, v in folds.items()), "N m²/rad",
              "the static spring brings the rigid fold closer to the fem-coupled one", bool(closer),
              "the fold is set by the static twist (total pitch reaching the root's stall), so a spring with the FEM's "
              "static twist should give about the FEM's fold; the frequency spring is statically stiffer."
              + (f" Ratios to fem-coupled: frequency {f_freq / f_fem:.2f}, static {f_stat / f_fem:.2f}." if ok else ""),
              details={"fold_gj_nm2": folds, "rel_tol": tol})
