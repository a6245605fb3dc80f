"""Stability boundary map (issue 4): progression, verdicts, boundaries, paper points, CLI, PNG."""
from __future__ import annotations

import json
import math
import threading

import pytest

from amra_core import cli
from amra_core.boundary import (DEFAULT_CG, MapSpec, MapSpecError, cell_class, iter_map, run_map,
                                solver_fingerprint)
from amra_core.flight import FlightCondition, SolverSettings
from amra_core.rotor_io import load_preset
from amra_core.stability import assess_cell
from amra_core.store import CellStore

EA = 0.32


def _cell(fidelity, cg, gj):
    rotor = load_preset("paper-boundary").with_overrides(gj_nm2=gj, x_ea=EA, x_cg=cg)
    return assess_cell(rotor, FlightCondition(), SolverSettings(fidelity=fidelity))


@pytest.fixture(scope="module")
def full_map(tmp_path_factory):
    """The default 16-column rigid axial map (EA 0.32, 2 %), on 2 local processes, with a store."""
    path = tmp_path_factory.mktemp("map") / "cells.sqlite"
    store = CellStore(path, solver=solver_fingerprint())
    seen = []
    bmap = run_map(MapSpec(), workers=2, store=store, on_cell=seen.append)
    yield bmap, store, seen
    store.close()


# ----------------------------------------------------------------------------- spec
def test_spec_defaults_and_validation():
    s = MapSpec()
    assert s.cg_values == DEFAULT_CG and len(DEFAULT_CG) == 16
    assert DEFAULT_CG[0] == pytest.approx(0.20) and DEFAULT_CG[-1] == pytest.approx(0.50)
    assert (s.gj_min, s.gj_max, s.gj_rel_tol, s.method, s.aero) == (30.0, 3000.0, 0.02, "eigen", "theodorsen")
    assert s.coarse_gj[0] == pytest.approx(30.0) and s.coarse_gj[-1] == pytest.approx(3000.0)
    bad = [dict(fidelity="beam"), dict(aero="wagner"), dict(method="euler"), dict(mu=0.7), dict(ea=1.5),
           dict(cg_values=(0.3, 1.2)), dict(cg_values=()), dict(gj_min=0.0), dict(gj_min=500.0, gj_max=400.0),
           dict(gj_rel_tol=0.0), dict(n_coarse=1), dict(rotor=3)]
    for kw in bad:
        name = next(iter(kw))
        with pytest.raises(MapSpecError) as ei:
            MapSpec(**kw)
        assert name.split("_")[0] in str(ei.value)


def test_case_key_covers_every_parameter_and_the_solver():
    s = MapSpec()
    k = s.key(0.4, 100.0)
    assert k == MapSpec().key(0.4, 100.0)
    others = {s.key(0.41, 100.0), s.key(0.4, 101.0), MapSpec(ea=0.3).key(0.4, 100.0),
              MapSpec(fidelity="fem-coupled").key(0.4, 100.0), MapSpec(aero="quasi-steady").key(0.4, 100.0),
              MapSpec(mu=0.1).key(0.4, 100.0), MapSpec(method="time").key(0.4, 100.0),
              MapSpec(rotor="mccutcheon").key(0.4, 100.0), MapSpec(n_elements=8).key(0.4, 100.0)}
    assert k not in others and len(others) == 9
    # map-level settings (range, tolerance, other columns) do not change a cell's key: cells are shared
    assert MapSpec(gj_max=5000.0, cg_values=(0.4,), gj_rel_tol=0.05).key(0.4, 100.0) == k
    assert s.case_params(0.4, 100.0)["solver"] == solver_fingerprint()


# ----------------------------------------------------------------------------- physics of the map
def test_full_map_brackets_every_column_to_tolerance(full_map):
    bmap, _, seen = full_map
    assert bmap.complete and not bmap.cancelled
    assert len(bmap.columns) == 16 and len(bmap.critical_gj) == 16
    assert bmap.verdict_counts()["failed"] == 0
    assert [c.gj_nm2 for c in seen] and len(seen) == bmap.cases == len(bmap.cells)
    for col in bmap.columns:
        assert col["status"] in ("bracketed", "stable-throughout", "unstable-at-gj-max")
        if col["status"] == "bracketed":
            lo, hi = col["bracket"]
            assert hi / lo - 1 <= 0.02 + 1e-9
            assert col["critical_gj"] == hi  # the upper end of the final bracket
            assert col["kind"] in ("flutter", "fold")
            assert hi == max(g for g in (col["fold_gj"], col["flutter_gj"]) if g is not None)
        assert col["intervals"] and col["intervals"][-1]["kind"] == "stable"
    for b in bmap.boundaries:
        assert b["kind"] in ("flutter", "fold", "windmill-brake")
        assert b["gj_lo"] < b["gj"] < b["gj_hi"]
        if "stable" in (b["below"], b["above"]):  # every change of stability on a branch: to tolerance
            assert b["resolved"], b
    # each column's cells above its critical GJ are all stable, the one just below is not
    for col in bmap.columns:
        cells = [c for c in bmap.cells if c.cg == col["cg"]]
        g = col["critical_gj"]
        weak = [iv for iv in col["intervals"] if iv["kind"] == "flutter" and iv["strength"] == "weak"]
        if g is not None and math.isfinite(g):
            # above the critical GJ: stable, or inside a weak window (which never moves it)
            assert all(c.stable or any(iv["gj_lo_nm2"] <= c.gj_nm2 <= iv["gj_hi_nm2"] for iv in weak)
                       for c in cells if c.gj_nm2 >= g)
            assert not max((c for c in cells if c.gj_nm2 < g), key=lambda c: c.gj_nm2).stable


def test_no_windmill_state_counted_stable(full_map):
    """Issue 8: the old map read GJ 68-280 at CG 0.36 stable (windmill-brake roots); now every
    windmill-brake cell is its own class and the CG 0.36 column reads like its neighbours."""
    bmap, _, _ = full_map
    wb = [c for c in bmap.cells if c.branch == "windmill-brake"]
    assert wb and not any(c.stable for c in wb)
    # one vocabulary with the runs: a run started from the branch end falls into that state
    assert {c.verdict for c in wb} == {"no-autorotation"} and all(cell_class(c) == "windmill-brake" for c in wb)
    assert all(c.descent_rate_m_s > 2.0 * 5.0 for c in wb)
    crit = dict((round(cg, 6), g) for cg, g in bmap.critical_gj)
    fold = {round(c["cg"], 6): c["fold_gj"] for c in bmap.columns}
    assert crit[0.36] > 250.0 and fold[0.36] is not None and crit[0.36] >= fold[0.36]  # not the old 68


def test_a_column_draws_its_overspeeding_stretch_as_fold_not_flutter():
    """Fem-coupled axial, CG 40 % (the Fig. 11 case): below the fold the walk finds the normal branch
    overspeeding (rotor speed 52-70 rad/s against 25) with a growing mode (divergence, 250-340 1/s).
    Its intervals call that stretch ``overspeed`` (no normal autorotation) and the fold line sits
    above it; its cells were drawn red as flutter, under the line saying no autorotation exists. Every
    cell is now drawn as the interval it lies in says, and keeps the verdict a run from it gives."""
    from amra_core.boundary import compute_column
    spec = MapSpec(rotor="paper-boundary", fidelity="fem-coupled", ea=EA, cg_values=(0.40,))
    col = compute_column(spec.column_task(0.40))
    drawn = {"overspeed": {"fold"}, "fold": {"fold"}, "windmill-brake": {"windmill-brake", "fold"},
             "flutter": {"flutter"}, "stable": {"stable"}}
    over = [c for c in col.cells if c.branch == "overspeed"]
    assert over and any(not c.stable and c.verdict in ("flutter", "divergence") for c in over)
    for c in col.cells:
        iv = next(i for i in col.intervals if i["gj_lo_nm2"] <= c.gj_nm2 <= i["gj_hi_nm2"])
        assert cell_class(c) in drawn[iv["kind"]], (c.gj_nm2, c.verdict, c.branch, iv["kind"])
    assert all(cell_class(c) == "fold" for c in over)
    assert col.fold_gj > max(c.gj_nm2 for c in over)


def test_critical_gj_rises_as_cg_moves_aft(full_map):
    """The paper: CG aft of the EA is destabilising (model-notes section 6). From CG 0.36 aft every
    column's trim branch folds, and the fold GJ (top of its ``fold`` interval) rises monotonically;
    narrow flutter windows just above the fold (CG 0.36-0.42, torsion meeting the cyclic flap) can
    set a column's critical GJ, so the critical GJ is checked end to end."""
    bmap, _, _ = full_map
    aft = [(cg, g) for cg, g in bmap.critical_gj if cg >= EA + 0.03]
    assert len(aft) >= 6
    gjs = [g for _, g in aft]
    assert all(g is not None and math.isfinite(g) for g in gjs), aft
    folds = [max(iv["gj_hi_nm2"] for iv in col["intervals"] if iv["kind"] == "fold")
             for col in bmap.columns if col["cg"] >= 0.36 - 1e-9]
    assert len(folds) >= 8 and all(b > a for a, b in zip(folds, folds[1:])), folds
    assert gjs[-1] > gjs[0]


def test_serial_map_streams_points_as_the_walk_finds_them():
    """In one process the cells of a column come as its walk finds them: the stiffest blade first,
    then downward (bisection points in between), one column after the other."""
    seen = []
    spec = MapSpec(cg_values=(0.40, 0.46))
    bmap = run_map(spec, workers=1, on_cell=seen.append)
    assert len(seen) == bmap.cases
    first = [c for c in seen if c.cg == 0.40]
    assert seen[:len(first)] == first  # column by column
    assert first[0].gj_nm2 == spec.gj_max and first[0].stable
    walk = [c.gj_nm2 for c in first if c.branch == "normal"]
    assert walk[:5] == sorted(walk[:5], reverse=True)


def test_rigid_paper_point_is_on_the_unstable_side(full_map):
    """Fig. 10: axial, rigid, EA 32 %, CG 40 %, GJ 100 -> unstable."""
    bmap, _, _ = full_map
    crit = dict((round(cg, 6), g) for cg, g in bmap.critical_gj)[0.40]
    assert crit is not None and crit > 100.0
    cell = _cell("rigid", 0.40, 100.0)
    assert not cell.stable and cell.verdict != "failed"


@pytest.mark.slow
def test_fem_coupled_paper_point_is_on_the_unstable_side():
    """Fig. 11: axial, fem-coupled, EA 32 %, CG 40 %, GJ 400 -> unstable; fem-coupled needs a higher
    GJ than rigid at the same CG (model-notes section 6)."""
    spec = MapSpec(fidelity="fem-coupled", cg_values=(0.40,))
    bmap = run_map(spec, workers=1)
    (cg, crit), = bmap.critical_gj
    assert bmap.columns[0]["status"] == "bracketed"
    assert crit > 400.0
    cell = _cell("fem-coupled", 0.40, 400.0)
    assert not cell.stable and cell.verdict != "failed"
    rigid = run_map(MapSpec(cg_values=(0.40,)), workers=1)
    assert crit > rigid.critical_gj[0][1]


# ----------------------------------------------------------------------------- robustness
def test_failed_point_is_recorded_and_the_column_not_stored(monkeypatch, tmp_path):
    import amra_core.column as column
    real = column.analyse

    def flaky(model, tr, *a, **k):
        gj = float(model.rotor.stations.gj_nm2[0])
        if 900.0 < gj < 1100.0:
            raise FloatingPointError("synthetic blow-up")
        return real(model, tr, *a, **k)

    monkeypatch.setattr(column, "analyse", flaky)
    spec = MapSpec(cg_values=(0.44,))
    with CellStore(tmp_path / "s.sqlite", solver=solver_fingerprint()) as st:
        bmap = run_map(spec, workers=1, store=st)
        assert len(st) == 0  # a column with a failed cell is not stored
    failed = [c for c in bmap.cells if c.verdict == "failed"]
    assert failed and all("FloatingPointError: synthetic blow-up" in c.reason for c in failed)
    assert cell_class(failed[0]) == "failed"
    col = bmap.columns[0]
    assert col["status"] == "unresolved"
    assert any(b["kind"] == "unknown" and not b["resolved"] for b in bmap.boundaries)
    json.dumps(bmap.to_dict(), allow_nan=False)


def test_crashed_worker_column_is_never_stored(tmp_path):
    """A column whose worker died (Outcome.ok False) is shown as failed in this run only."""
    from amra_core.executor import CellExecutor, Outcome

    class Crashing(CellExecutor):
        name = "crashing"

        def __init__(self):
            self.q = []

        def submit(self, fn, arg, tag=None):
            self.q.append(tag)

        def wait(self, timeout=None):
            out = [Outcome(t, False, RuntimeError("worker died (segfault)")) for t in self.q]
            self.q = []
            return out

        @property
        def n_pending(self):
            return len(self.q)

        def cancel_pending(self):
            self.q = []

    spec = MapSpec(cg_values=(0.40, 0.46))
    with CellStore(tmp_path / "s.sqlite", solver=solver_fingerprint()) as st:
        bmap = run_map(spec, executor=Crashing(), store=st)
        assert len(st) == 0
    assert bmap.cases > 0 and all(c.verdict == "failed" and "worker died" in c.reason for c in bmap.cells)
    assert all(col["status"] == "unresolved" for col in bmap.columns)
    # the next run (a working executor) computes them afresh
    again = run_map(MapSpec(cg_values=(0.46,)), workers=1, store=tmp_path / "s.sqlite")
    assert again.cached_cases == 0 and again.verdict_counts()["failed"] == 0


def test_cancel_returns_the_partial_map():
    cancel = threading.Event()
    got = []

    def on_cell(c):
        got.append(c)
        if len(got) == 5:
            cancel.set()

    bmap = run_map(MapSpec(cg_values=(0.4, 0.46)), workers=1, on_cell=on_cell, cancel=cancel)
    assert bmap.cancelled and not bmap.complete
    assert bmap.cases == 5 == len(bmap.cells)
    assert all(c["status"] == "incomplete" for c in bmap.columns)
    assert bmap.to_dict()["cancelled"] is True


def test_iter_map_yields_cells_then_result():
    run = iter_map(MapSpec(cg_values=(0.46,), n_coarse=4, gj_rel_tol=0.2), workers=1)
    cells = list(run)
    bmap = run.result()
    assert len(cells) == bmap.cases and bmap.complete
    assert {(c.cg, c.gj_nm2) for c in cells} == {(c.cg, c.gj_nm2) for c in bmap.cells}


def test_result_while_iterating_summarises_without_restarting_the_walk(tmp_path):
    """A progress view asks for the columns while the cells still arrive: no second walk, and the
    map's own freshly stored columns are not counted as read from the store."""
    spec = MapSpec(cg_values=(0.40, 0.46), n_coarse=4, gj_rel_tol=0.2)
    store = CellStore(tmp_path / "s.sqlite", solver=solver_fingerprint())
    run = iter_map(spec, workers=2, store=store)
    seen = []
    for cell in run:
        seen.append(cell)
        part = run.result()
        assert part.cached_cases == 0 and part.cases >= len(seen)  # a finished column's cells at once
    bmap = run.result()
    assert bmap.complete and bmap.cached_cases == 0 and bmap.cases == len(seen)
    store.close()


def test_csv_and_json(tmp_path, full_map):
    bmap, _, _ = full_map
    d = json.loads(json.dumps(bmap.to_dict(), allow_nan=False))
    for k in ("critical_gj", "boundaries", "cells", "cases", "cached_cases", "wall_time_s"):
        assert k in d
    assert len(d["cells"]) == bmap.cases
    p = tmp_path / "map.csv"
    bmap.to_csv(p)
    lines = p.read_text().splitlines()
    meta = [ln for ln in lines if ln.startswith("# ")]  # the map's case above the table (it had none)
    assert meta[0].startswith("# AMRA ") and "# complete: yes" in meta and f"# fidelity: {bmap.spec.fidelity}" in meta
    assert f"# rotor: {bmap.spec.rotor_name()}" in meta and any(m.startswith("# gj_range_nm2: ") for m in meta)
    assert lines[len(meta)].startswith("cg,gj_nm2,verdict,stable,boundary_kind")
    assert len(lines) == len(meta) + bmap.cases + 1


def test_png_is_written(tmp_path, full_map):
    from amra_core.map_plot import PAPER_AXIAL_POINTS, plot_map
    bmap, _, _ = full_map
    p = tmp_path / "map.png"
    plot_map(bmap, p, marks=PAPER_AXIAL_POINTS["rigid"])
    data = p.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20_000


# ----------------------------------------------------------------------------- CLI
def test_cli_json_contract(tmp_path, capsys):
    png, csv_path, store = tmp_path / "m.png", tmp_path / "m.csv", tmp_path / "s.sqlite"
    argv = ["boundary", "--preset", "paper-boundary", "--fidelity", "rigid", "--mu", "0", "--ea", "0.32",
            "--cg", "0.40:0.46:2", "--gj", "30:3000", "--workers", "1", "--store", str(store),
            "--out", str(csv_path), "--plot", str(png), "--json", "--quiet"]
    assert cli.main(argv) == 0
    d = json.loads(capsys.readouterr().out)
    assert [round(cg, 6) for cg, _ in d["critical_gj"]] == [0.40, 0.46]
    assert all(g > 100 for _, g in d["critical_gj"])
    assert d["cases"] == len(d["cells"]) > 14 and d["cached_cases"] == 0 and d["wall_time_s"] > 0
    assert {b["kind"] for b in d["boundaries"]} <= {"flutter", "fold", "windmill-brake"}
    assert all(col["intervals"] for col in d["columns"])
    assert png.read_bytes()[:4] == b"\x89PNG" and csv_path.is_file()
    assert cli.main(argv) == 0  # again: everything from the store
    d2 = json.loads(capsys.readouterr().out)
    assert d2["cached_cases"] == d2["cases"] == d["cases"] and d2["critical_gj"] == d["critical_gj"]


@pytest.mark.parametrize("args, name", [
    (["--cg", "0.5:0.2:4"], "--cg"), (["--cg", "0.2:1.5:4"], "--cg"), (["--cg", "x"], "--cg"),
    (["--gj", "0:100"], "--gj"), (["--gj", "300:100"], "--gj"), (["--mu", "0.9"], "--mu"),
    (["--ea", "-0.1"], "--ea"), (["--workers", "0"], "--workers"), (["--tol", "0"], "--tol"),
    (["--fidelity", "beam"], "--fidelity"), (["--method", "rk4"], "--method"), (["--coarse", "1"], "--coarse"),
])
def test_cli_bad_values_exit_2_naming_the_parameter(args, name, capsys):
    with pytest.raises(SystemExit) as ei:
        cli.main(["boundary", *args])
    assert ei.value.code == 2
    assert name in capsys.readouterr().err


def test_cli_errors_raised_after_parsing_exit_2(capsys, tmp_path):
    assert cli.main(["boundary", "--preset", "nope", "--quiet"]) == 2
    assert "preset" in capsys.readouterr().err
    assert cli.main(["boundary", "--workers", "2", "--scheduler", "tcp://127.0.0.1:1", "--quiet"]) == 2
    assert "--scheduler" in capsys.readouterr().err
    assert cli.main(["boundary", "--rotor", str(tmp_path / "missing.toml"), "--quiet"]) == 2
    assert "rotor file" in capsys.readouterr().err


# ----------------------------------------------------------------------------- time marching
@pytest.mark.slow
def test_time_marching_boundary_agrees_with_eigen():
    """Issue 4: eigen and time-marching boundaries within 5 % in GJ (rigid axial, one CG column)."""
    cg = (0.42,)
    eig = run_map(MapSpec(cg_values=cg), workers=1)
    tim = run_map(MapSpec(cg_values=cg, method="time"), workers=1)
    g_e, g_t = eig.critical_gj[0][1], tim.critical_gj[0][1]
    print(f"critical GJ at CG {cg[0]}: eigen {g_e:.1f}, time {g_t:.1f} N m^2/rad "
          f"({100 * (g_t / g_e - 1):+.2f} %); cells/s eigen {eig.cells_per_s:.1f}, time {tim.cells_per_s:.1f}")
    assert tim.columns[0]["status"] == "bracketed"
    assert abs(g_t / g_e - 1) <= 0.05


def test_every_module_a_map_computes_with_is_in_the_solver_fingerprint():
    """A stored cell is keyed by the fingerprint of the solver sources: a module that changes the
    answers but is not hashed would let a store serve cells of an older solver (shooting.py,
    atan2_kernel.py and jit.py's fast-math flags were missing, 2026-12-04)."""
    import subprocess
    import sys
    code = ("import sys, amra_core.boundary.tasks, amra_core.column, amra_core.stability, amra_core.simulation\n"
            "print(' '.join(m[len('amra_core.'):].replace('.', '/') for m in sys.modules if m.startswith('amra_core.')))")
    used = set(subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True).stdout.split())
    from amra_core.boundary.spec import _SOLVER_SOURCES, ORCHESTRATION_SOURCES
    assert used - set(_SOLVER_SOURCES) - set(ORCHESTRATION_SOURCES) == set()
