"""Command-line contracts (issue 3): ``amra trim``, ``simulate``, ``modes`` and ``stability`` print
the documented JSON keys in SI units, ``--out`` writes a CSV whose header carries the units, and
out-of-range or malformed values exit with code 2 and one line naming the parameter and its range.
All calls are in-process (``amra_core.cli.main``)."""
from __future__ import annotations

import csv
import json
import math
import re

import numpy as np
import pytest

from amra_core.cli import main
from cli_helpers import run_cli, strict_json
from amra_core.kernels import HISTORY_COLUMNS

G = 9.80665
WEIGHT_N = 360.0 * G  # McCutcheon preset: vehicle mass 360 kg (model-notes §4)
RADIUS_M = 3.81
#: units a CSV/JSON column name may end with
UNIT_SUFFIX = re.compile(r"_(s|rad|rad_s|m|m_s|n|nm|hz|per_s|kg|kg_m|nm2)$")


def cli_json(capsys, *argv) -> dict:
    rc, out, err = run_cli(capsys, *argv, "--json")
    assert rc == 0, err
    assert "Traceback" not in err
    return strict_json(out)


# ---------------------------------------------------------------------------------------------
# trim
# ---------------------------------------------------------------------------------------------
def test_trim_axial_json(capsys):
    d = cli_json(capsys, "trim", "--preset", "mccutcheon")
    for k in ("omega_rad_s", "descent_rate_m_s", "disk_tilt_rad", "teeter_amplitude_rad", "thrust_n", "torque_nm"):
        assert k in d, k
        assert isinstance(d[k], (int, float)) and math.isfinite(d[k]), (k, d[k])
    assert d["status"] == "trimmed"
    assert d["thrust_n"] == pytest.approx(WEIGHT_N, rel=0.01)  # thrust balances the weight
    assert abs(d["torque_nm"]) < 1e-4 * WEIGHT_N * RADIUS_M  # steady autorotation: no net torque
    # axial autorotation: descending, rotor turning at a sensible tip speed, no tilt or teeter
    assert d["descent_rate_m_s"] > 0
    assert 80.0 < d["omega_rad_s"] * RADIUS_M < 250.0
    assert d["disk_tilt_rad"] == 0.0 and d["teeter_amplitude_rad"] == 0.0


def test_trim_table1_case_a(capsys):
    """Paper Table 1, case A: 14 m/s with the rotor speed held at 38 rad/s, level flight."""
    d = cli_json(capsys, "trim", "--airspeed", "14", "--omega-hold", "38")
    assert d["status"] in ("trimmed", "thrust-limited"), d
    if d["status"] == "thrust-limited":  # model-notes §6: report the largest thrust reached
        assert "reason" in d and "weight" in d["reason"]
    assert d["omega_rad_s"] == pytest.approx(38.0, abs=1e-12)
    assert d["airspeed_m_s"] == pytest.approx(14.0)
    assert d["descent_rate_m_s"] == pytest.approx(0.0, abs=1e-12)  # level flight
    assert 0.0 < d["teeter_amplitude_rad"] < 0.2
    assert d["thrust_n"] > 0.5 * WEIGHT_N
    # mu = V cos(tilt) / (Omega R)
    assert d["mu"] == pytest.approx(14.0 * math.cos(d["disk_tilt_rad"]) / (38.0 * RADIUS_M), rel=1e-9)


def test_trim_human_readable(capsys):
    rc, out, err = run_cli(capsys, "trim", "--preset", "mccutcheon")
    assert rc == 0
    assert re.search(r"^omega_rad_s\s+\d+\.\d+", out, re.M)
    assert re.search(r"^thrust_n\s+\d+", out, re.M)


def test_trim_without_autorotation_reports_why(capsys):
    """Paper Fig. 10 parameters: no steady autorotation; still exit 0 with the reason and where the
    trim branch ended (model-notes §7)."""
    d = cli_json(capsys, "trim", "--preset", "paper-boundary", "--gj", "100")
    assert d["status"] == "no-autorotation"
    assert d["reason"]
    assert d["branch_end"]["gj_mean_nm2"] > 100.0


# ---------------------------------------------------------------------------------------------
# simulate
# ---------------------------------------------------------------------------------------------
SIM_KEYS = ("verdict", "rotor_speed", "outcome", "growth_rate_per_s", "frequency_hz", "omega_trim_rad_s", "descent_rate_trim_m_s",
            "omega_final_rad_s", "teeter_amplitude_rad", "sim_time_s", "wall_time_s")


@pytest.fixture(scope="module")
def simulate_run(tmp_path_factory):
    """One ``amra simulate --preset mccutcheon --t-end 1 --json --out FILE.csv`` run."""
    import contextlib
    import io
    path = tmp_path_factory.mktemp("sim") / "run.csv"
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main(["simulate", "--preset", "mccutcheon", "--t-end", "1", "--json", "--quiet", "--out", str(path)])
    assert rc == 0, err.getvalue()
    return strict_json(out.getvalue()), path


def test_simulate_json_keys(simulate_run):
    d, _ = simulate_run
    for k in SIM_KEYS:
        assert k in d, k
    # a 1 s run cannot be called stable (issue 21 §7): too short to see a slow growth
    assert d["verdict"] == "undetermined" and "run too short" in d["explanation"], d
    assert d["outcome"] == "undetermined" and d["rotor_speed"].startswith("rotor speed kept")
    for k in SIM_KEYS[3:]:
        assert isinstance(d[k], (int, float)) and math.isfinite(d[k]), (k, d[k])
    assert d["sim_time_s"] == pytest.approx(1.0, abs=0.01)
    assert d["wall_time_s"] > 0
    assert d["omega_final_rad_s"] == pytest.approx(d["omega_trim_rad_s"], rel=0.02)
    assert d["descent_rate_trim_m_s"] > 0
    assert 0.0 < d["teeter_amplitude_rad"] < 0.05  # the 0.01 rad teeter kick, decaying


def test_a_numerical_failure_names_a_step_the_cli_can_set_and_the_cli_sets_it(capsys):
    """McCutcheon at mu 0.5 (EA 32 %, CG 40 %) stops non-finite at 0.12 s: the message advised 'a
    shorter SolverSettings.dt_s, in the Python API', which neither the CLI nor the page offered. The
    CLI takes --dt-s; at a fifth of the step the run stops at the same time (the motion itself leaves
    the model's range), which is what the option is for."""
    runs = []
    for dt in (None, "0.0002"):
        argv = ["simulate", "--preset", "mccutcheon", "--mu", "0.5", "--ea", "0.32", "--cg", "0.40", "--t-end", "0.5",
                "--json", "--quiet"] + ([] if dt is None else ["--dt-s", dt])
        rc, out, err = run_cli(capsys, *argv)
        assert rc == 0, err
        runs.append(strict_json(out))
    default, short = runs
    assert default["verdict"] == "numerical-failure" and "amra simulate --dt-s" in default["explanation"]
    assert short["dt_s"] == pytest.approx(2e-4) and default["dt_s"] > 2 * short["dt_s"]
    assert short["verdict"] == "numerical-failure" and short["sim_time_s"] == pytest.approx(default["sim_time_s"], abs=0.01)


def test_simulate_matches_trim(capsys, simulate_run):
    d, _ = simulate_run
    t = cli_json(capsys, "trim", "--preset", "mccutcheon")
    assert d["omega_trim_rad_s"] == pytest.approx(t["omega_rad_s"], rel=1e-9)
    assert d["descent_rate_trim_m_s"] == pytest.approx(t["descent_rate_m_s"], rel=1e-9)


def test_simulate_csv_header_carries_units(simulate_run):
    d, path = simulate_run
    assert d["csv"] == str(path)
    with open(path, newline="") as fh:
        lines = fh.read().splitlines()
    meta = [ln for ln in lines if ln.startswith("#")]
    assert lines[:len(meta)] == meta  # the case's parameters first, as "# key: value" lines
    assert meta[0].startswith("# AMRA ") and "# rotor: mccutcheon" in "\n".join(meta)
    assert any(ln.startswith("# fidelity: rigid") for ln in meta) and any(ln.startswith("# verdict: ") for ln in meta)
    assert any(ln.startswith("# start: ") for ln in meta) and any(ln.startswith("# outcome: ") for ln in meta)
    header = next(csv.reader([lines[len(meta)]]))
    assert tuple(header) == HISTORY_COLUMNS
    for name in header:
        assert UNIT_SUFFIX.search(name), f"column {name!r} does not carry a unit"
    data = np.loadtxt(path, delimiter=",", skiprows=len(meta) + 1)
    assert max(len(v) for v in lines[-1].split(",")) <= 15  # 8 significant digits, no 17-digit noise
    assert data.shape[1] == len(header) and data.shape[0] > 100
    assert np.isfinite(data).all()
    t = data[:, header.index("t_s")]
    assert t[0] == 0.0 and np.all(np.diff(t) > 0) and t[-1] <= d["sim_time_s"] + 1e-9
    om = data[:, header.index("omega_rad_s")]
    assert om[0] == pytest.approx(d["omega_trim_rad_s"], rel=5e-8)  # written to 8 significant digits


# ---------------------------------------------------------------------------------------------
# bad values: exit 2, one line naming the parameter and its range
# ---------------------------------------------------------------------------------------------
BAD_ARGS = [
    (["simulate", "--mu", "2"], ["--mu", "2", "[0.0, 0.5]"]),
    (["simulate", "--mu", "-0.1"], ["--mu", "-0.1", "[0.0, 0.5]"]),
    (["simulate", "--gj", "-5"], ["--gj", "-5", "[1.0, 1000000.0]"]),
    (["simulate", "--t-end", "abc"], ["--t-end", "abc", "[0.01, 600.0]"]),
    (["simulate", "--t-end", "0"], ["--t-end", "0", "[0.01, 600.0]"]),
    (["simulate", "--t-end", "nan"], ["--t-end", "nan", "[0.01, 600.0]"]),
    (["simulate", "--fidelity", "foo"], ["--fidelity", "foo", "rigid", "fem-torsion", "fem-coupled"]),
    (["simulate", "--aero", "potential"], ["--aero", "potential", "quasi-steady", "theodorsen"]),
    (["simulate", "--cg", "1.5"], ["--cg", "1.5", "[0.0, 1.0]"]),
    (["simulate", "--elements", "0"], ["--elements", "0", "[1, 60]"]),
    (["simulate", "--elements", "2.5"], ["--elements", "2.5", "[1, 60]"]),
    (["trim", "--airspeed", "100"], ["--airspeed", "100", "[0.0, 80.0]"]),
    (["trim", "--omega-hold", "-3"], ["--omega-hold", "-3", "[1.0, 200.0]"]),
    (["trim", "--ea", "x"], ["--ea", "x", "[0.0, 1.0]"]),
    # a position typed in % chord, as the dashboard shows it: the message gives the fraction meant
    (["simulate", "--cg", "40"], ["--cg", "40", "[0.0, 1.0]", "40 % chord is --cg 0.4"]),
    (["trim", "--ea", "32.5"], ["--ea", "32.5", "[0.0, 1.0]", "32.5 % chord is --ea 0.325"]),
    (["sensitivity", "--preset", "paper-boundary", "--cg", "35"], ["--cg", "35", "35 % chord is --cg 0.35"]),
    (["modes", "--omega", "1e9"], ["--omega", "1e9", "[0.0, 200.0]"]),
    (["simulate", "--dt-s", "0.5"], ["--dt-s", "0.5", "[1e-06, 0.01]"]),
    (["stability", "--mu", "0.9"], ["--mu", "0.9", "[0.0, 0.5]"]),
    (["stability", "--preset", "nosuch"], ["preset", "nosuch", "mccutcheon"]),
]


@pytest.mark.parametrize("argv, fragments", BAD_ARGS, ids=[" ".join(a) for a, _ in BAD_ARGS])
def test_bad_values_exit_2_with_the_range(capsys, argv, fragments):
    rc, out, err = run_cli(capsys, *argv)
    assert rc == 2, (rc, err)
    assert out == ""
    assert "Traceback" not in err
    last = err.strip().splitlines()[-1]
    assert last.startswith(f"amra {argv[0]}: error:"), err
    for frag in fragments:
        assert frag in last, f"{frag!r} not in {last!r}"


def test_mu_and_airspeed_are_exclusive(capsys):
    rc, out, err = run_cli(capsys, "trim", "--mu", "0.1", "--airspeed", "10")
    assert rc == 2 and "not allowed with" in err and "Traceback" not in err


def test_unknown_command_exits_2(capsys):
    rc, out, err = run_cli(capsys, "fly")
    assert rc == 2 and "invalid choice" in err


# ---------------------------------------------------------------------------------------------
# modes and stability
# ---------------------------------------------------------------------------------------------
def test_modes_json_structure(capsys):
    d = cli_json(capsys, "modes", "--preset", "mccutcheon")
    assert d["rotor"] == "mccutcheon" and d["fidelity"] == "fem-coupled" and d["elements"] == 10
    assert d["omega_rad_s"] == 0.0
    modes = d["modes"]
    assert len(modes) >= 7
    for m in modes:
        assert set(m) == {"label", "frequency_hz", "per_rev"}
        assert isinstance(m["label"], str) and math.isfinite(m["frequency_hz"])
        assert m["per_rev"] is None  # no rotor speed, no per-rev value
    f = [m["frequency_hz"] for m in modes]
    assert f == sorted(f)
    labels = [m["label"] for m in modes]
    assert labels[0] == "teeter" and f[0] == 0.0  # free teeter at rest: rigid-body mode
    assert "torsion 1 (collective)" in labels and "flap 1 (collective)" in labels
    assert len(set(labels)) == len(labels)


def test_modes_rotating_per_rev(capsys):
    omega = 38.7
    d = cli_json(capsys, "modes", "--preset", "mccutcheon", "--omega", str(omega), "--fidelity", "rigid")
    by = {m["label"]: m for m in d["modes"]}
    assert by["teeter"]["per_rev"] == pytest.approx(1.0, abs=1e-3)  # rigid teeter exactly 1/rev
    for m in d["modes"]:
        assert m["per_rev"] == pytest.approx(m["frequency_hz"] * 2 * math.pi / omega, abs=2e-3)


@pytest.mark.parametrize("flight", [[], ["--mu", "0.1"]], ids=["axial", "mu0.1"])
def test_stability_json(capsys, flight):
    d = cli_json(capsys, "stability", "--preset", "mccutcheon", *flight)
    assert isinstance(d["stable"], bool)
    assert d["method"] == ("eigenvalues" if not flight else "floquet")
    assert d["trim"]["status"] == "trimmed"
    assert d["modes"]
    for m in d["modes"]:
        for k in ("label", "frequency_hz", "damping_ratio", "real_part_per_s"):
            assert k in m, k
        assert isinstance(m["label"], str)
        assert m["label"] != "aero lag"  # listed only with --all-modes
        assert m["frequency_hz"] >= 0.0
        # damping ratio is -Re(lambda)/|lambda|
        w = math.hypot(m["real_part_per_s"], 2 * math.pi * m["frequency_hz"])
        assert m["damping_ratio"] == pytest.approx(-m["real_part_per_s"] / w, rel=1e-6, abs=1e-12)
    assert d["stable"] == all(m["real_part_per_s"] < 1e-3 for m in d["modes"])
    assert d["stable"] is True  # nominal McCutcheon blade (model-notes §6)
    assert d["verdict"] == "stable"  # the word a map cell of this case uses


def test_stability_all_modes_adds_aero_lag(capsys):
    d = cli_json(capsys, "stability", "--preset", "mccutcheon", "--all-modes")
    labels = [m["label"] for m in d["modes"]]
    assert "aero lag" in labels
    lag = [m for m in d["modes"] if m["label"] == "aero lag"]
    assert all(m["real_part_per_s"] < 0 for m in lag)


def test_stability_no_trim(capsys):
    d = cli_json(capsys, "stability", "--preset", "paper-boundary", "--gj", "100")
    assert d["stable"] is False and d["modes"] == []
    assert d["trim"]["status"] == "no-autorotation" and d["reason"]
    assert d["verdict"] == "no-autorotation"


def test_stability_human_readable(capsys):
    rc, out, err = run_cli(capsys, "stability", "--preset", "mccutcheon")
    assert rc == 0
    assert out.startswith("verdict: stable (a map cell's word; least damped: ")
    assert "\nstable: True  (eigenvalues; trim trimmed, branch normal)" in out
    assert "f [Hz]" in out and "zeta [-]" in out
    # the case it is about: rotor, fidelity, GJ, flight and the trim
    assert "case: mccutcheon, rigid, GJ 1471 N m^2/rad, axial; trim: rotor speed" in out


def test_stability_without_a_trim_says_why(capsys):
    rc, out, err = run_cli(capsys, "stability", "--preset", "paper-boundary", "--gj", "100")
    assert out.startswith("verdict: no-autorotation (a map cell's word)\nstable: False")
    assert "case: paper-boundary, rigid, GJ 100 N m^2/rad, axial\n" in out
    assert "reason: no steady autorotation" in out


def test_modes_human_readable_names_the_case(capsys):
    rc, out, err = run_cli(capsys, "modes", "--preset", "mccutcheon", "--fidelity", "rigid")
    assert rc == 0 and out.startswith("case: mccutcheon, rigid, in vacuo at rotor speed 0 rad/s (per rev: give --omega)")


def test_sigterm_after_the_last_cell_still_ends_in_the_report_and_143(capsys, monkeypatch, tmp_path):
    """A SIGTERM that arrives once every cell is in (the map assembled, the pool closing: on a fast
    machine a small map is there when the signal comes) is reported as one during the map, with the
    store's count and exit 143, not as an unhandled interrupt (exit 130, no report, as it was)."""
    import os
    import signal

    from amra_core import executor as executor_module
    real = executor_module.make_executor

    class ClosingWithSigterm:
        def __init__(self, inner):
            self.inner = inner

        def __getattr__(self, name):
            return getattr(self.inner, name)

        def close(self):
            # never SIGTERM the test runner itself: only with the command's own handler in place
            assert signal.getsignal(signal.SIGTERM) not in (signal.SIG_DFL, signal.SIG_IGN, before)
            os.kill(os.getpid(), signal.SIGTERM)  # delivered here, in the main thread, after the loop
            self.inner.close()

    before = signal.getsignal(signal.SIGTERM)
    monkeypatch.setattr(executor_module, "make_executor", lambda **kw: ClosingWithSigterm(real(**kw)))
    store = tmp_path / "s.db"
    rc = main(["boundary", "--preset", "paper-boundary", "--fidelity", "rigid", "--mu", "0", "--cg", "0.40:0.40:1",
               "--coarse", "3", "--tol", "0.2", "--gj", "100:1500", "--workers", "1", "--store", str(store),
               "--json", "--quiet"])
    out, err = capsys.readouterr()
    assert rc == 143
    assert "interrupted (SIGTERM)" in err and "rerun with the same --store" in err and "Traceback" not in err
    d = json.loads(out)
    assert d["cases"] >= 3 and not d["cancelled"]  # every cell was in: the map itself is complete
    assert f"holds {d['cases']} cells" in err
    assert signal.getsignal(signal.SIGTERM) == before  # the command's handler is gone again


def test_a_trim_that_finds_no_autorotation_reports_no_equilibrium_values(capsys):
    """No equilibrium: its tilt, airspeed, teeter and twist are null, not zeros that read as results."""
    d = cli_json(capsys, "trim", "--preset", "paper-boundary", "--gj", "100")
    assert d["status"] == "no-autorotation" and d["reason"]
    for k in ("omega_rad_s", "descent_rate_m_s", "disk_tilt_rad", "airspeed_m_s", "teeter_amplitude_rad",
              "tip_twist_rad"):
        assert d[k] is None, (k, d[k])
    assert d["branch_end"]["gj_mean_nm2"] > 100.0


def test_the_boundary_table_says_how_its_gj_values_relate(capsys):
    """The critical GJ (a bracket's upper end) and an interval's edge (the bracket's geometric mean)
    differ by design; the table says so (it read as a contradiction: fold 350.2 but stable 347-3000)."""
    rc, out, err = run_cli(capsys, "boundary", "--preset", "paper-boundary", "--fidelity", "rigid", "--mu", "0",
                           "--cg", "0.40:0.40:1", "--coarse", "3", "--tol", "0.2", "--gj", "100:1500",
                           "--workers", "1", "--quiet")
    assert rc == 0
    assert "critical GJ are the upper ends of their brackets" in out and "geometric mean" in out
    row = next(line.split() for line in out.splitlines() if line.strip().startswith("0.400"))
    bracket_hi = float(row[-3].rstrip("]")) if row[-3].endswith("]") else None
    assert bracket_hi is not None and float(row[3]) == bracket_hi, row  # critical GJ = the bracket's upper end


def test_every_command_describes_itself_in_its_help(capsys):
    """`amra validate --help` printed its options and no word of what it does; `amra serve --help`
    showed the reST double backticks of its module docstring."""
    from amra_core.cli import COMMANDS
    for module in COMMANDS:
        name = module.__name__.rsplit(".", 1)[1]
        with pytest.raises(SystemExit):
            main([name, "--help"])
        out = capsys.readouterr().out
        description = out.split("\n\n")[1]
        assert not description.startswith("options:") and len(description.split()) >= 4, (name, out[:300])
        assert "``" not in out, name


def test_boundary_takes_one_cg_column_as_one_value(capsys):
    """Checking one cell's column, a user writes ``--cg 0.3125``: it was refused (only A:B:N)."""
    import argparse
    from amra_core.cli.common import value_range
    parse = value_range("--cg", 0.0, 1.0, True)
    assert parse("0.3125") == parse("0.3125:0.3125:1") == (0.3125, 0.3125, 1)
    with pytest.raises(argparse.ArgumentTypeError, match="out of range"):
        parse("40")
    with pytest.raises(argparse.ArgumentTypeError, match=r"give A:B:N \(or one value A\)"):
        parse("0.2:0.4")
    rc = main(["boundary", "--preset", "paper-boundary", "--fidelity", "rigid", "--mu", "0", "--cg", "0.40",
               "--coarse", "3", "--tol", "0.2", "--gj", "100:1500", "--workers", "1", "--json", "--quiet"])
    out, _ = capsys.readouterr()
    assert rc == 0 and [c["cg"] for c in json.loads(out)["columns"]] == [0.40]


def test_boundary_names_the_run_of_a_cell_and_that_run_agrees(capsys):
    """A map of the McCutcheon preset is at the map's uniform EA 0.32; ``amra simulate --preset
    mccutcheon`` without ``--ea`` runs the blade's tapered EA, another rotor (at CG 31.25 %, GJ 200 it
    trims at 28.34 rad/s against 27.57). The map's text says how to run one of its cells, and that
    command, at a cell inside a stable interval and one inside the windmill-brake interval, gives
    the cell's word."""
    import shlex
    rc = main(["boundary", "--preset", "mccutcheon", "--fidelity", "rigid", "--mu", "0", "--cg", "0.40",
               "--coarse", "3", "--tol", "0.2", "--workers", "1", "--quiet"])
    out, _ = capsys.readouterr()
    assert rc == 0
    line = next(ln for ln in out.splitlines() if ln.startswith("a cell is this rotor with EA 0.32"))
    command = shlex.split(line.split("run one with: amra ", 1)[1])
    assert command[:3] == ["simulate", "--preset", "mccutcheon"] and ["--ea", "0.32"] == command[-6:-4]
    kinds = {ln.split()[0]: ln.split()[1] for ln in out.splitlines() if ln.startswith("          ")}
    assert set(kinds) >= {"stable", "windmill-brake"}, out
    for kind, gj, word in (("stable", 2000.0, "stable"), ("windmill-brake", 100.0, "no-autorotation")):
        lo, hi = (float(x) for x in kinds[kind].split("-"))
        assert lo < gj < hi, (kind, kinds[kind])
        argv = [a.replace("CG", "0.4").replace("GJ", f"{gj:g}") for a in command]
        assert main(argv + ["--t-end", "20", "--json", "--quiet"]) == 0
        assert json.loads(capsys.readouterr().out)["verdict"] == word, (kind, gj)
