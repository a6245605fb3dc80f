"""Regression tests for the reproducers of issue 10 §2-3 and issue 8 §4 (files in, files out, wrong
accepts, physically impossible sections, strict JSON): each ends in exit 2 with one message that
names the input and the reason, before any work is done -- or in an answer."""
from __future__ import annotations

import json
import math
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from amra_core.cli.common import dumps_strict
from amra_core.rotor import RotorError
from amra_core.rotor_io import load_preset, load_rotor_file
from cli_helpers import run_cli, strict_json

REPO = Path(__file__).resolve().parents[2]
PRESET_TEXT = (REPO / "assets" / "rotors" / "mccutcheon.toml").read_text()


def one_error_line(err: str, command: str) -> str:
    assert "Traceback" not in err, err
    lines = [ln for ln in err.strip().splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith(f"amra {command}: error:"), err
    return lines[0]


# ----------------------------------------------------------------------------- output paths
def _bad_outputs(tmp_path):
    (tmp_path / "d").mkdir()
    fifo = tmp_path / "fifo.csv"
    os.mkfifo(fifo)
    return [("directory", str(tmp_path / "d"), "directory"),
            ("missing-parent", str(tmp_path / "no" / "such" / "x.csv"), "does not exist"),
            ("dev-full", "/dev/full", "device"),
            ("fifo", str(fifo), "FIFO"),
            ("file-as-folder", str(tmp_path / "f.txt" / "x.csv"), "Not a directory")]


@pytest.mark.parametrize("command, flag", [("boundary", "--out"), ("boundary", "--plot"), ("simulate", "--out")])
def test_bad_output_path_exits_2_before_any_work(capsys, tmp_path, command, flag):
    (tmp_path / "f.txt").write_text("x")
    for case, path, why in _bad_outputs(tmp_path):
        t0 = time.perf_counter()
        rc, out, err = run_cli(capsys, command, "--preset", "paper-boundary", flag, path, "--quiet")
        wall = time.perf_counter() - t0
        assert rc == 2 and out == "", (case, err)
        line = one_error_line(err, command)
        assert flag in line and path in line and why in line, (case, line)
        assert wall < 5.0, f"{case}: {wall:.1f} s -- the check must come before the computation"


def test_validate_report_folder_is_checked_first(capsys, tmp_path):
    f = tmp_path / "file"
    f.write_text("x")
    for path, why in ((str(f), "not a folder"), (str(tmp_path / "a" / "b"), "does not exist"), ("/dev/full", "device")):
        rc, out, err = run_cli(capsys, "validate", "--out", path, "--quick", "--quiet")
        assert rc == 2, err
        line = one_error_line(err, "validate")
        assert path in line and why in line, line


def test_output_on_a_read_only_mount_is_refused(tmp_path):
    if shutil.which("unshare") is None or subprocess.run(["unshare", "-m", "true"]).returncode != 0:
        pytest.skip("needs unshare -m (a private mount namespace) for a read-only mount")
    ro = tmp_path / "ro"
    ro.mkdir()
    env = dict(os.environ, PYTHONPATH=str(REPO))
    cmd = (f"mount --bind {ro} {ro} && mount -o remount,ro,bind {ro} && exec {sys.executable} -m amra_core.cli "
           f"simulate --preset paper-boundary --out {ro}/x.csv --quiet")
    r = subprocess.run(["unshare", "-m", "sh", "-c", cmd], capture_output=True, text=True, timeout=120, env=env)
    assert r.returncode == 2 and r.stdout == ""
    line = one_error_line(r.stderr, "simulate")
    assert "read-only" in line and f"{ro}/x.csv" in line


# ----------------------------------------------------------------------------- rotor files
@pytest.mark.parametrize("case", ["dev-zero", "fifo", "binary", "nested-array", "nested-table", "dotted-key",
                                  "too-large", "directory"])
def test_hostile_rotor_files(capsys, tmp_path, case):
    path = tmp_path / f"{case}.toml"
    why = {"dev-zero": "device", "fifo": "FIFO", "binary": "not UTF-8", "nested-array": "nested deeper",
           "nested-table": "nested deeper", "dotted-key": "dotted key", "too-large": "too large",
           "directory": "directory"}[case]
    if case == "dev-zero":
        path = Path("/dev/zero")
    elif case == "fifo":
        os.mkfifo(path)
    elif case == "binary":
        path.write_bytes(bytes(range(256)) * 4)
    elif case == "nested-array":
        path.write_text("x = " + "[" * 5000 + "]" * 5000 + "\n")
    elif case == "nested-table":
        path.write_text("x = " + "{a = " * 3000 + "1" + "}" * 3000 + "\n")
    elif case == "dotted-key":
        path.write_text("a" + ".a" * 20_000 + " = 1\n")  # 40 kB: the parser would take ~2 GB
    elif case == "too-large":
        path.write_text(PRESET_TEXT + "#" * (1 << 20))
    elif case == "directory":
        path = tmp_path
    t0 = time.perf_counter()
    rc, out, err = run_cli(capsys, "rotor", "--rotor", str(path))
    assert time.perf_counter() - t0 < 5.0
    assert rc == 2 and out == ""
    line = one_error_line(err, "rotor")
    assert str(path) in line and why in line, line


@pytest.mark.parametrize("name", ["../../tmp/x", "x" * 256, "mccutcheon.toml", "/etc/passwd", ""])
def test_preset_must_name_a_preset(capsys, tmp_path, name):
    rc, out, err = run_cli(capsys, "rotor", "--preset", name)
    assert rc == 2
    line = one_error_line(err, "rotor")
    assert "choose one of mccutcheon, paper-boundary" in line


WRONG_ACCEPTS = [
    ("name-number", ('name = "mccutcheon"', "name = 5"), "name = 5"),
    ("name-date", ('name = "mccutcheon"', "name = 1979-05-27"), "name = datetime.date(1979, 5, 27)"),
    ("name-table", ('name = "mccutcheon"', "name = {a = 1}"), "name = {'a': 1}"),
    ("airfoil-number", ('airfoil = "naca0012_critzos"', "airfoil = 5"), "airfoil = 5"),
    ("airfoil-unknown", ('airfoil = "naca0012_critzos"', 'airfoil = "naca9999"'), "naca0012_critzos, naca0012_sheldahl360k"),
    ("chord-over-radius", ("chord_m = 0.197", "chord_m = 4.0\ntorsional_inertia_kg_m = 100.0"), "blade.chord_m = 4.0 is not"),
    # as the file writes it: its [blade] table, and a value given once for the span has no station index
    ("chord-negative", ("chord_m = 0.197", "chord_m = -0.197"), "blade.chord_m = -0.197 is not allowed: must lie in (0.0, 12.5]"),
    ("mass-negative", ("mass_kg_m = [4.25,", "mass_kg_m = [-4.25,"), "blade.mass_kg_m[0] = -4.25 is not allowed"),
    ("twist-twice", ("twist_deg = 0.0", "twist_deg = 0.0\ntwist_rad = 0.1"), "both given"),
    ("n-blades-float", ("n_blades = 2", "n_blades = 2.0"), "n_blades = 2.0"),
    ("n-blades-bool", ("n_blades = 2", "n_blades = true"), "n_blades = True"),
    ("sources-number", ("\n[sources]\n", "\n[old_sources]\n"), "sources = 5"),
    # a [sources] entry that is not a text is named, not the whole table echoed
    ("sources-entry-number", ('airfoil = "the paper\'s choice', 'airfoil = 5\nx = "the paper\'s choice'),
     "sources.airfoil = 5 is not allowed"),
    ("point-mass-number", ("[blade]", "point_mass = 5\n[blade]"), "point_mass = 5"),
    ("inertia-too-small", ("torsional_inertia_kg_m = [0.010309,", "torsional_inertia_kg_m = [0.0001,"),
     "torsional_inertia_kg_m = 0.0001"),
]


@pytest.mark.parametrize("case, edit, fragment", WRONG_ACCEPTS, ids=[c[0] for c in WRONG_ACCEPTS])
def test_wrong_accepts_are_rejected(capsys, tmp_path, case, edit, fragment):
    text = PRESET_TEXT.replace(edit[0], edit[1], 1)
    assert text != PRESET_TEXT
    if case == "sources-number":  # the [sources] table replaced by a number
        text = "sources = 5\n" + text.split("[old_sources]")[0]
    if case == "chord-over-radius":  # drop the original inertia line (replaced by a uniform one above)
        text = re.sub(r"^torsional_inertia_kg_m = \[.*\n", "", text, flags=re.M)
    f = tmp_path / "r.toml"
    f.write_text(text)
    rc, out, err = run_cli(capsys, "rotor", "--rotor", str(f))
    assert rc == 2, (case, out)
    line = one_error_line(err, "rotor")
    assert fragment in line, line


# ----------------------------------------------------------------------------- impossible sections
def _bound_cg(rotor):
    """The CG interval of the parallel-axis bound at EA 0.32 on the paper-boundary blade."""
    st = rotor.stations
    d = min(math.sqrt(i / m) / c for i, m, c in zip(st.torsional_inertia_kg_m, st.mass_kg_m, st.chord_m))
    return d


@pytest.mark.parametrize("argv", [
    ["rotor", "--preset", "mccutcheon", "--cg", "0.0"],
    ["trim", "--preset", "mccutcheon", "--cg", "0.069"],
    ["trim", "--preset", "paper-boundary", "--cg", "0.02"],
    ["trim", "--preset", "paper-boundary", "--cg", "0.95"],
    ["trim", "--preset", "paper-boundary", "--ea", "1.0"],
    ["stability", "--preset", "paper-boundary", "--cg", "0.02"],
    ["simulate", "--preset", "paper-boundary", "--ea", "1.0", "--t-end", "0.1"],
    ["boundary", "--preset", "paper-boundary", "--cg", "0.0:0.5:3", "--workers", "1"],
    ["boundary", "--preset", "paper-boundary", "--ea", "1.0", "--cg", "0.3:0.5:3", "--workers", "1"],
])
def test_impossible_sections_are_named_not_lapack(capsys, argv):
    """Issue 8 §4 / 10 §3: `The leading minor of order 3 of B is not positive definite` becomes a
    message naming x_cg, x_ea, the torsional inertia and the bound."""
    rc, out, err = run_cli(capsys, *argv)
    assert rc == 2 and out == "", err
    line = one_error_line(err, argv[0])
    for frag in ("x_cg", "x_ea", "torsional_inertia_kg_m", "m ((x_cg - x_ea) c)^2", "|x_cg - x_ea| must be below"):
        assert frag in line, line
    assert "leading minor" not in line


def test_inside_the_bound_gives_an_answer(capsys, paper):
    d = _bound_cg(paper)
    assert d == pytest.approx(0.25, rel=1e-3)  # radius of gyration 0.25 c: the presets' estimate
    for cg in (0.32 - 0.99 * d, 0.32 + 0.99 * d):
        rc, out, err = run_cli(capsys, "trim", "--preset", "paper-boundary", "--cg", f"{cg:.4f}", "--json")
        assert rc == 0, err
        assert strict_json(out)["status"]


def test_slider_overrides_and_set_parameters_are_checked(paper):
    with pytest.raises(RotorError, match=r"x_cg = 0\.95 with x_ea = 0\.32"):
        paper.with_overrides(x_cg=0.95)
    with pytest.raises(RotorError, match=r"x_cg = 0\.4 with x_ea = 0\.9"):
        paper.with_overrides(x_ea=0.9)
    assert paper.with_overrides(x_ea=0.9, x_cg=0.8).stations.x_cg[0] == 0.8  # together: a valid section
    from amra_core.flight import SolverSettings
    from amra_core.simulation import Case, Simulation
    sim = Simulation(Case(paper, settings=SolverSettings(fidelity="rigid"), t_end_s=1.0))
    sim.advance(n_steps=5)
    with pytest.raises(RotorError, match="torsional inertia"):
        sim.set_parameters(x_cg=0.02)


# ----------------------------------------------------------------------------- strict JSON
def test_json_is_strict_everywhere():
    text = dumps_strict({"a": math.inf, "b": [math.nan, -math.inf, 1.5], "c": {"d": float("nan")}})
    assert json.loads(text) == {"a": None, "b": [None, None, 1.5], "c": {"d": None}}
    import numpy as np
    assert json.loads(dumps_strict({"x": np.float64("inf"), "y": np.arange(2.0), "z": np.int64(3)})) == \
        {"x": None, "y": [0.0, 1.0], "z": 3}


def test_boundary_json_has_no_infinity_token(capsys):
    """A column unstable at gj_max has critical_gj = inf internally: null in the JSON."""
    rc, out, err = run_cli(capsys, "boundary", "--preset", "paper-boundary", "--cg", "0.36:0.36:1", "--gj", "30:60",
                           "--coarse", "2", "--tol", "0.5", "--workers", "1", "--json", "--quiet")
    assert rc == 0, err
    assert "Infinity" not in out and "NaN" not in out
    d = strict_json(out)
    assert d["critical_gj"][0][0] == 0.36


def test_help_says_json_is_strict(capsys):
    with pytest.raises(SystemExit):
        from amra_core.cli import main
        main(["boundary", "--help"])
    assert "strict JSON" in " ".join(capsys.readouterr().out.split())


def test_rotor_file_loader_names_the_file_for_non_utf8(tmp_path):
    f = tmp_path / "latin1.toml"
    f.write_bytes(PRESET_TEXT.replace("mccutcheon", "m\xe9cutcheon").encode("latin-1"))
    with pytest.raises(RotorError, match=re.escape(str(f)) + r".*not UTF-8.*line 3"):
        load_rotor_file(f)
    assert load_preset("mccutcheon").name == "mccutcheon"
