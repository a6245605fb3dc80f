"""Rotor descriptions through the command line: ``amra rotor`` prints the resolved rotor (SI, root
to tip), presets and a user's own TOML file load alike, overrides reach the stations, and every kind
of bad input is rejected with exit code 2 and one clear line naming the field, the value and what
is allowed (model-notes §4: "loadable from a user's own file, validated with clear errors")."""
from __future__ import annotations

import json
import math
import os
import re
import shutil
import subprocess
import tomllib
from pathlib import Path

import pytest

from cli_helpers import run_cli, strict_json

REPO = Path(__file__).resolve().parents[2]
PRESETS = REPO / "assets" / "rotors"
STATION_KEYS = ("r_m", "mass_kg_m", "torsional_inertia_kg_m", "gj_nm2", "ei_flap_nm2", "ei_lag_nm2",
                "x_ea", "x_cg", "x_ac", "twist_rad", "chord_m")
TOP_KEYS = ("radius_m", "root_cutout_m", "chord_m", "n_blades", "incidence_rad", "vehicle_mass_kg")


def rotor_json(capsys, *argv) -> dict:
    rc, out, err = run_cli(capsys, "rotor", *argv, "--json")
    assert rc == 0, err
    return strict_json(out)


def expected_from_toml(path: Path) -> dict:
    """What the resolved rotor must contain, read independently from the TOML file (degrees to
    radians, scalars broadcast to every station)."""
    data = tomllib.loads(path.read_text())
    blade = data["blade"]
    n = len(blade["r_m"])

    def stations(key, conv=lambda v: v):
        v = blade[key]
        return [conv(x) for x in v] if isinstance(v, list) else [conv(v)] * n

    st = {k: stations(k) for k in STATION_KEYS if k in blade}
    st["twist_rad"] = stations("twist_deg", math.radians) if "twist_deg" in blade else stations("twist_rad")
    top = {k: data[k] for k in ("radius_m", "root_cutout_m", "vehicle_mass_kg")}
    top["incidence_rad"] = math.radians(data["incidence_deg"])
    top["n_blades"] = data.get("n_blades", 2)
    return {"top": top, "stations": st}


# ---------------------------------------------------------------------------------------------
# the resolved rotor
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("preset", ["mccutcheon", "paper-boundary"])
def test_rotor_json_matches_preset_file(capsys, preset):
    got = rotor_json(capsys, "--preset", preset)
    for k in TOP_KEYS:
        assert k in got, f"missing key {k}"
    for k in STATION_KEYS:
        assert k in got["stations"], f"missing station key {k}"
    exp = expected_from_toml(PRESETS / f"{preset}.toml")
    for k, v in exp["top"].items():
        assert got[k] == pytest.approx(v, rel=1e-12), k
    n = len(exp["stations"]["r_m"])
    for k, v in exp["stations"].items():
        assert len(got["stations"][k]) == n, k
        assert got["stations"][k] == pytest.approx(v, rel=1e-12, abs=1e-15), k
    # root to tip, from the root cut-out to the tip radius
    r = got["stations"]["r_m"]
    assert all(b > a for a, b in zip(r, r[1:]))
    assert r[0] == pytest.approx(got["root_cutout_m"]) and r[-1] == pytest.approx(got["radius_m"])
    assert got["chord_m"] == pytest.approx(0.197)
    assert got["n_blades"] == 2


def test_mccutcheon_measured_values_in_si(capsys):
    """The seed's measured McCutcheon values (model-notes §4) arrive unchanged and in SI."""
    st = rotor_json(capsys, "--preset", "mccutcheon")["stations"]
    assert st["x_ea"][0] == pytest.approx(0.355) and st["x_ea"][-1] == pytest.approx(0.2724)
    assert st["x_cg"][0] == pytest.approx(0.30) and st["x_cg"][-1] == pytest.approx(0.36)
    assert st["mass_kg_m"][0] == pytest.approx(4.25) and st["mass_kg_m"][-1] == pytest.approx(2.7)
    assert st["gj_nm2"][0] == pytest.approx(1534.0) and st["gj_nm2"][-1] == pytest.approx(1409.0)
    assert set(st["ei_flap_nm2"]) == {1166.0}
    # chord fractions, not percent
    assert all(0.0 <= x <= 1.0 for k in ("x_ea", "x_cg", "x_ac") for x in st[k])


def test_overrides_reach_every_station(capsys):
    got = rotor_json(capsys, "--preset", "mccutcheon", "--gj", "250", "--ea", "0.3", "--cg", "0.42")
    st = got["stations"]
    n = len(st["r_m"])
    assert st["gj_nm2"] == [250.0] * n
    assert st["x_ea"] == [0.3] * n
    assert st["x_cg"] == [0.42] * n
    # what was not overridden is untouched
    base = rotor_json(capsys, "--preset", "mccutcheon")["stations"]
    for k in ("r_m", "mass_kg_m", "ei_flap_nm2", "x_ac", "torsional_inertia_kg_m"):
        assert st[k] == base[k], k


def test_single_override_leaves_the_others(capsys):
    st = rotor_json(capsys, "--preset", "paper-boundary", "--gj", "100")["stations"]
    assert set(st["gj_nm2"]) == {100.0}
    assert set(st["x_ea"]) == {0.32} and set(st["x_cg"]) == {0.40}


def test_user_file_loads_like_the_preset(capsys, tmp_path):
    src = (PRESETS / "mccutcheon.toml").read_text()
    user = tmp_path / "my_rotor.toml"
    user.write_text(src.replace('name = "mccutcheon"', 'name = "my-rotor"'))
    a = rotor_json(capsys, "--preset", "mccutcheon")
    b = rotor_json(capsys, "--rotor", str(user))
    assert b["name"] == "my-rotor"
    a.pop("name"); b.pop("name")
    assert a == b
    # and the overrides work on a user's file too
    c = rotor_json(capsys, "--rotor", str(user), "--cg", "0.33")
    assert set(c["stations"]["x_cg"]) == {0.33}


MINIMAL = """\
name = "tiny"
radius_m = 4.0
root_cutout_m = 0.4
vehicle_mass_kg = 300.0
incidence_deg = 3.0

[blade]
r_m = [0.4, 2.0, 4.0]
chord_m = 0.2
twist_deg = [0.0, -1.0, -2.0]
mass_kg_m = 3.0
torsional_inertia_kg_m = 0.0075
gj_nm2 = [1600.0, 1500.0, 1400.0]
ei_flap_nm2 = 1200.0
ei_lag_nm2 = 90000.0
x_ea = 0.3
x_cg = 0.32
x_ac = 0.25
"""


def test_minimal_user_file_defaults_and_units(capsys, tmp_path):
    """A hand-written file with degrees and uniform scalars: converted to radians, broadcast to
    every station, and the optional fields take their documented defaults."""
    f = tmp_path / "tiny.toml"
    f.write_text(MINIMAL)
    got = rotor_json(capsys, "--rotor", str(f))
    assert got["incidence_rad"] == pytest.approx(math.radians(3.0))
    assert got["stations"]["twist_rad"] == pytest.approx([0.0, math.radians(-1.0), math.radians(-2.0)])
    assert got["stations"]["mass_kg_m"] == [3.0, 3.0, 3.0]
    assert got["stations"]["gj_nm2"] == [1600.0, 1500.0, 1400.0]
    assert got["n_blades"] == 2
    assert got["hub_teeter_inertia_kg_m2"] == 0.0 and got["hub_polar_inertia_kg_m2"] == 0.0
    expected = expected_from_toml(f)
    for k, v in expected["stations"].items():
        assert got["stations"][k] == pytest.approx(v), k


def test_human_readable_output(capsys):
    rc, out, err = run_cli(capsys, "rotor", "--preset", "mccutcheon")
    assert rc == 0 and err == ""
    assert re.search(r"^radius_m\s+3\.81$", out, re.M)
    assert re.search(r"^vehicle_mass_kg\s+360$", out, re.M)


# ---------------------------------------------------------------------------------------------
# bad input: exit 2, one clear line, no traceback
# ---------------------------------------------------------------------------------------------
def _mutate(pattern: str, repl: str) -> str:
    src = (PRESETS / "mccutcheon.toml").read_text()
    out, n = re.subn(pattern, repl, src, count=1, flags=re.M)
    assert n == 1, f"pattern {pattern!r} not in the preset"
    return out


# (case id, mutation of the McCutcheon file, fragments the error message must contain)
BAD_FILES = [
    ("missing-top-field", (r"^vehicle_mass_kg = 360\.0\n", ""), ["vehicle_mass_kg", "missing", "required"]),
    ("missing-station-field", (r"^ei_flap_nm2 = 1166\.0\n", ""), ["ei_flap_nm2", "missing", "required"]),
    ("missing-incidence", (r"^incidence_deg = 2\.5\n", ""), ["incidence", "missing"]),
    ("negative-gj", (r"^gj_nm2 = \[1534\.0,", "gj_nm2 = [1534.0, -20.0,"), None),
    ("zero-ei-flap", (r"^ei_flap_nm2 = 1166\.0", "ei_flap_nm2 = 0.0"), ["ei_flap_nm2", "0.0", "(0.0, 10000000000.0]"]),
    ("negative-ei-lag", (r"^ei_lag_nm2 = 80000\.0", "ei_lag_nm2 = -8.0e4"), ["ei_lag_nm2", "-80000.0", "(0.0, 10000000000.0]"]),
    ("zero-mass", (r"^mass_kg_m = \[4\.25,", "mass_kg_m = [0.0,"), ["mass_kg_m[0]", "0.0", "(0.0, 10000.0]"]),
    ("cg-behind-trailing-edge", (r"^x_cg = \[0\.3,", "x_cg = [1.3,"), ["x_cg[0]", "1.3", "[0.0, 1.0]"]),
    ("cg-ahead-of-leading-edge", (r"^x_cg = \[0\.3,", "x_cg = [-0.1,"), ["x_cg[0]", "-0.1", "[0.0, 1.0]"]),
    ("ea-outside-chord", (r"^x_ea = \[0\.355,", "x_ea = [1.355,"), ["x_ea[0]", "1.355", "[0.0, 1.0]"]),
    ("nan-stiffness", (r"^ei_lag_nm2 = 80000\.0", "ei_lag_nm2 = nan"), ["ei_lag_nm2", "nan", "(0.0, 10000000000.0]"]),
    ("nan-radius", (r"^radius_m = 3\.81", "radius_m = nan"), ["radius_m", "nan", "(0.0, 50.0]"]),
    ("inf-cg", (r"^x_cg = \[0\.3,", "x_cg = [inf,"), ["x_cg[0]", "inf", "[0.0, 1.0]"]),
    ("stations-out-of-order", (r"^r_m = \[0\.381, 0\.6, 0\.8, 1\.0,", "r_m = [0.381, 0.6, 1.2, 1.0,"),
     ["r_m[3]", "1.0", "increasing"]),
    ("repeated-station", (r"^r_m = \[0\.381, 0\.6, 0\.8,", "r_m = [0.381, 0.6, 0.6,"), ["r_m[2]", "0.6", "increasing"]),
    ("wrong-station-count", (r"^mass_kg_m = \[4\.25, ", "mass_kg_m = ["), ["mass_kg_m", "10 values"]),
    ("text-for-number", (r"^radius_m = 3\.81", 'radius_m = "three"'), ["radius_m", "'three'", "number"]),
    ("unknown-field", (r"^airfoil = ", 'colour = "red"\nairfoil = '), ["colour", "unknown field"]),
    ("malformed-toml", (r"^radius_m = 3\.81", "radius_m = = 3.81"), ["not valid TOML", "line"]),
    ("unclosed-array", (r"^x_ac = 0\.25", "x_ac = [0.25, 0.25"), ["not valid TOML"]),
    ("tip-not-at-radius", (r"^radius_m = 3\.81", "radius_m = 4.0"), ["r_m[9]", "3.81", "tip radius"]),
    # absurd magnitudes are named, never an OverflowError in the section checks (1e308 squared)
    ("absurd-chord", (r"^chord_m = 0\.197", "chord_m = 1e308"), ["blade.chord_m = 1e+308", "(0.0, 12.5]"]),
    ("absurd-mass", (r"^mass_kg_m = \[4\.25,", "mass_kg_m = [1e300,"), ["mass_kg_m[0]", "1e+300", "(0.0, 10000.0]"]),
    ("absurd-gj", (r"^gj_nm2 = \[1534\.0,", "gj_nm2 = [1e200,"), ["gj_nm2[0]", "1e+200", "(0.0, 10000000000.0]"]),
    ("absurd-hub-inertia", (r"^hub_teeter_inertia_kg_m2 = [0-9.]+", "hub_teeter_inertia_kg_m2 = 1e300"),
     ["hub_teeter_inertia_kg_m2", "1e+300", "[0.0, 1000000.0]"]),
    # an angle the file gives in degrees is named and ranged in degrees (it read "incidence_rad =
    # 0.785... must lie in [-0.349..., 0.349...]" for a file that says incidence_deg = 45)
    ("incidence-too-large", (r"^incidence_deg = 2\.5", "incidence_deg = 45.0"),
     ["incidence_deg = 45 is not allowed: must lie in [-20, 20] deg"]),
    ("twist-too-large", (r"^twist_deg = 0\.0", "twist_deg = 400.0"),
     ["blade.twist_deg = 400 is not allowed: must lie in [-45, 45] deg"]),
    ("twist-nan", (r"^twist_deg = 0\.0", "twist_deg = nan"), ["blade.twist_deg = nan", "in [-45, 45] deg"]),
]


@pytest.mark.parametrize("case, mutation, fragments", BAD_FILES, ids=[c[0] for c in BAD_FILES])
def test_bad_rotor_file_is_rejected_clearly(capsys, tmp_path, case, mutation, fragments):
    if fragments is None:  # negative GJ: the inserted value sits at station 1
        fragments = ["gj_nm2[1]", "-20.0", "(0.0, 10000000000.0]"]
    f = tmp_path / f"{case}.toml"
    f.write_text(_mutate(*mutation))
    rc, out, err = run_cli(capsys, "rotor", "--rotor", str(f), "--json")
    assert rc == 2, (rc, out, err)
    assert out == ""
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("amra rotor: error:"), err
    for frag in fragments:
        assert frag in err, f"{frag!r} not in {err!r}"


def test_unknown_preset(capsys):
    rc, out, err = run_cli(capsys, "rotor", "--preset", "no-such-rotor")
    assert rc == 2 and out == "" and "Traceback" not in err
    assert "no-such-rotor" in err
    assert "mccutcheon" in err and "paper-boundary" in err  # the allowed choices


def test_missing_file(capsys, tmp_path):
    missing = tmp_path / "nope.toml"
    rc, out, err = run_cli(capsys, "rotor", "--rotor", str(missing))
    assert rc == 2 and out == "" and "Traceback" not in err
    assert "nope.toml" in err and "cannot be read" in err


def test_preset_and_file_are_exclusive(capsys, tmp_path):
    rc, out, err = run_cli(capsys, "rotor", "--preset", "mccutcheon", "--rotor", str(tmp_path / "x.toml"))
    assert rc == 2 and "not allowed with" in err and "Traceback" not in err


@pytest.mark.parametrize("flag, value, allowed", [
    ("--gj", "-5", "[1.0, 1000000.0]"),
    ("--gj", "0", "[1.0, 1000000.0]"),
    ("--gj", "nan", "[1.0, 1000000.0]"),
    ("--gj", "stiff", "[1.0, 1000000.0]"),
    ("--cg", "1.2", "[0.0, 1.0]"),
    ("--cg", "-0.01", "[0.0, 1.0]"),
    ("--ea", "inf", "[0.0, 1.0]"),
])
def test_bad_override_is_rejected(capsys, flag, value, allowed):
    rc, out, err = run_cli(capsys, "rotor", "--preset", "mccutcheon", flag, value)
    assert rc == 2 and out == "" and "Traceback" not in err
    assert flag in err and value in err and allowed in err, err


# ---------------------------------------------------------------------------------------------
# the installed console script
# ---------------------------------------------------------------------------------------------
def test_console_script_end_to_end(tmp_path):
    """The ``amra`` entry point of the installed package (pyproject ``[project.scripts]``), run as
    a separate process against this checkout."""
    exe = shutil.which("amra")
    if exe is None:
        pytest.skip("the amra console script is not installed (pip install -e .)")
    env = dict(os.environ, PYTHONPATH=str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    ok = subprocess.run([exe, "rotor", "--preset", "mccutcheon", "--json"], capture_output=True, text=True,
                        env=env, timeout=120, cwd=tmp_path)
    assert ok.returncode == 0, ok.stderr
    got = strict_json(ok.stdout)
    assert got["radius_m"] == pytest.approx(3.81) and got["vehicle_mass_kg"] == pytest.approx(360.0)
    assert len(got["stations"]["r_m"]) == len(got["stations"]["gj_nm2"]) >= 2

    bad = tmp_path / "bad.toml"
    bad.write_text(_mutate(r"^x_cg = \[0\.3,", "x_cg = [1.3,"))
    fail = subprocess.run([exe, "rotor", "--rotor", str(bad)], capture_output=True, text=True, env=env,
                          timeout=120, cwd=tmp_path)
    assert fail.returncode == 2
    assert fail.stdout == ""
    assert "Traceback" not in fail.stderr
    assert "x_cg[0]" in fail.stderr and "1.3" in fail.stderr and "[0.0, 1.0]" in fail.stderr
