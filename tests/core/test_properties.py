"""Property-based tests (hypothesis, issue 10 §5): every generated case -- a rotor file that is
mutated, retyped, truncated, nested, huge or not UTF-8; an ``amra`` command line; a Python API run
with extreme but valid parameters at every fidelity -- ends in a result or a clear error of the
project's own type (:data:`PROJECT_ERRORS`, or exit code 2 with one message line), within a time
bound (:data:`TIME_BOUND_S`), never a traceback, a hang or memory growth beyond
:data:`RSS_GROWTH_BOUND_MIB` (peak resident size over one test).

Profiles: ``AMRA_HYPOTHESIS_PROFILE=ci`` (default, derandomised, about 2 100 examples in all, most of
them on the cheap loader) or ``nightly`` (10x the examples, random seeds). Outcome counts per area
go to ``properties-<normal|bc>.json`` (``python tests/core/report_helpers.py`` prints them).
"""
from __future__ import annotations

import contextlib
import io
import json
import math
import os
import re
import resource
import signal
import tempfile
import time
import tomllib
from datetime import date, datetime, time as dtime
from pathlib import Path

import pytest
from hypothesis import HealthCheck, assume, given, settings, strategies as st

from amra_core.boundary import MapSpecError
from amra_core.flight import FlightCondition, SettingsError, SolverSettings
from amra_core.rotor import Rotor, RotorError
from amra_core.rotor_io import MAX_FILE_BYTES, load_rotor_file
from amra_core.store import StoreError
from report_helpers import count

REPO = Path(__file__).resolve().parents[2]
PRESET = REPO / "assets" / "rotors" / "mccutcheon.toml"
PRESET_TEXT = PRESET.read_text()
PRESET_DATA = tomllib.loads(PRESET_TEXT)

PROJECT_ERRORS = (RotorError, SettingsError, MapSpecError, StoreError)
#: seconds one generated case may take (loader, CLI, API)
TIME_BOUND_S = {"loader": 5.0, "cli": 60.0, "api": 120.0}
#: growth of the peak resident set size allowed over one property test [MiB]
RSS_GROWTH_BOUND_MIB = 300

_COMMON = dict(deadline=None, suppress_health_check=list(HealthCheck), print_blob=True)
settings.register_profile("ci", derandomize=True, database=None, **_COMMON)
settings.register_profile("nightly", **_COMMON)
PROFILE = os.environ.get("AMRA_HYPOTHESIS_PROFILE", "ci")
if PROFILE not in ("ci", "nightly"):
    raise ValueError(f"AMRA_HYPOTHESIS_PROFILE = {PROFILE!r} is not allowed: ci or nightly")
settings.load_profile(PROFILE)
SCALE = 10 if PROFILE == "nightly" else 1

#: examples per test in the ci profile (x SCALE in nightly)
EXAMPLES = {"loader-retyped": 500, "loader-structure": 200, "loader-truncated": 250, "loader-bytes": 250,
            "loader-nested": 120, "loader-huge": 12, "loader-text": 150, "cli-arguments": 600, "cli-full": 60,
            "api": 6}


def n(area):
    return EXAMPLES[area] * SCALE


class Hang(Exception):
    pass


class KnownOpen(Exception):
    """A traceback already pinned by a strict-xfail regression test: counted, not re-raised."""


@contextlib.contextmanager
def time_bound(seconds):
    """Raise :class:`Hang` in the main thread after ``seconds`` (a real hang would never return)."""
    def fire(signum, frame):
        raise Hang(f"no answer within {seconds} s")
    old = signal.signal(signal.SIGALRM, fire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def peak_rss_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


@pytest.fixture
def rss_bound():
    before = peak_rss_mib()
    yield
    grown = peak_rss_mib() - before
    assert grown < RSS_GROWTH_BOUND_MIB, f"peak resident set grew by {grown:.0f} MiB (bound {RSS_GROWTH_BOUND_MIB})"


#: ``AMRA_PROPERTIES_SURVEY=1``: count tracebacks and hangs (listed in the report) instead of failing
SURVEY = os.environ.get("AMRA_PROPERTIES_SURVEY") == "1"


def outcome_of(area, kind, fn, count_result=True):
    """Run ``fn``; count and return "result" / "clean error"; fail on a traceback or a hang.
    ``count_result=False``: the caller counts a normal return itself (it knows better)."""
    try:
        with time_bound(TIME_BOUND_S[kind]):
            fn()
    except PROJECT_ERRORS as exc:
        msg = str(exc)
        assert msg and "Traceback" not in msg, msg
        count(area, "clean error")
        return "clean error"
    except KnownOpen:
        count(area, "traceback")
        return "traceback"
    except Hang as exc:
        count(area, "hang")
        if SURVEY:
            count(f"{area}: hang: {exc}"[:150], "hang")
            return "hang"
        raise
    except Exception as exc:
        count(area, "traceback")
        if SURVEY:
            count(f"{area}: {type(exc).__name__}: {exc}"[:150], "traceback")
            return "traceback"
        raise
    if count_result:
        count(area, "result")
    return "result"


# ============================================================================ rotor-file loader
_DIR = Path(tempfile.mkdtemp(prefix="amra-props-"))


def load_text(data) -> Rotor:
    path = _DIR / "rotor.toml"
    path.write_bytes(data if isinstance(data, bytes) else data.encode("utf-8", "surrogatepass"))
    return load_rotor_file(path)


def toml_key(k: str) -> str:
    return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else json.dumps(k)


def toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return "nan" if math.isnan(v) else ("inf" if v == math.inf else "-inf" if v == -math.inf else repr(v))
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, (datetime, date, dtime)):
        return v.isoformat()
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{toml_key(k)} = {toml_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(type(v))


def to_toml(data: dict) -> str:
    """A TOML document of ``data``: top-level scalars first, then one table per dict."""
    lines = [f"{toml_key(k)} = {toml_value(v)}" for k, v in data.items() if not isinstance(v, dict)]
    for k, v in data.items():
        if isinstance(v, dict):
            lines.append(f"[{toml_key(k)}]")
            lines += [f"{toml_key(kk)} = {toml_value(vv)}" for kk, vv in v.items()]
    return "\n".join(lines) + "\n"


def test_toml_writer_round_trips_the_preset():
    assert tomllib.loads(to_toml(PRESET_DATA)) == PRESET_DATA
    assert load_text(to_toml(PRESET_DATA)) == load_rotor_file(PRESET)


scalars = st.one_of(
    st.integers(min_value=-2**63, max_value=2**63 - 1), st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=30), st.booleans(), st.dates(), st.datetimes(), st.times(),
    st.sampled_from([0, 1, 2, -1, 2.0, 0.0, 1e-300, 1e300, 0.5, 3.81, 0.381, "", "naca0012_critzos", "x"]))
values = st.recursive(scalars, lambda inner: st.lists(inner, max_size=12) |
                      st.dictionaries(st.text(min_size=1, max_size=8), inner, max_size=4), max_leaves=20)
FIELDS = [(None, k) for k in PRESET_DATA if not isinstance(PRESET_DATA[k], dict)] + \
         [(t, k) for t in ("blade", "sources") for k in PRESET_DATA[t]] + [(None, "blade"), (None, "sources"),
                                                                          (None, "point_mass")]


def _retype(data, where, value):
    d = json.loads(json.dumps(PRESET_DATA))
    table, key = where
    (d if table is None else d[table])[key] = value
    return d


@settings(max_examples=n("loader-retyped"))
@given(where=st.sampled_from(FIELDS), value=values, n_more=st.integers(0, 2), data=st.data())
def test_loader_retyped_fields(rss_bound, where, value, n_more, data):
    d = _retype(None, where, value)
    for _ in range(n_more):  # sometimes more than one field at once
        t, k = data.draw(st.sampled_from(FIELDS))
        target = d if t is None else d.get(t)
        if isinstance(target, dict):
            target[k] = data.draw(values)
    outcome_of("loader: retyped fields", "loader", lambda: load_text(to_toml(d)))


@settings(max_examples=n("loader-structure"))
@given(drop=st.lists(st.sampled_from(FIELDS), max_size=4),
       add=st.dictionaries(st.sampled_from(["", "blade", "point_mass"]), st.tuples(st.text(min_size=1, max_size=10),
                                                                                  scalars), max_size=3))
def test_loader_missing_and_unknown_fields(rss_bound, drop, add):
    d = json.loads(json.dumps(PRESET_DATA))
    for t, k in drop:
        (d if t is None else d.get(t, {})).pop(k, None)
    for table, (k, v) in add.items():
        (d.setdefault(table, {}) if table else d)[k] = v
    outcome_of("loader: missing/unknown fields", "loader", lambda: load_text(to_toml(d)))


@settings(max_examples=n("loader-truncated"))
@given(cut=st.integers(0, len(PRESET_TEXT)))
def test_loader_truncated_file(rss_bound, cut):
    outcome_of("loader: truncated", "loader", lambda: load_text(PRESET_TEXT[:cut]))


@settings(max_examples=n("loader-bytes"))
@given(edits=st.lists(st.tuples(st.integers(0, len(PRESET_TEXT)), st.binary(min_size=1, max_size=8),
                                st.booleans()), min_size=1, max_size=6))
def test_loader_byte_mutations_and_non_utf8(rss_bound, edits):
    b = bytearray(PRESET_TEXT.encode())
    for pos, chunk, insert in edits:
        pos = min(pos, len(b))
        b[pos:pos if insert else pos + len(chunk)] = chunk
    data = bytes(b)
    try:
        data.decode("utf-8")
        utf8 = True
    except UnicodeDecodeError:
        utf8 = False
    try:
        outcome_of("loader: byte mutations", "loader", lambda: load_text(data))
    except RotorError:
        raise
    if not utf8:
        with pytest.raises(RotorError, match=r"rotor\.toml.*not UTF-8"):
            load_text(data)


NEST_KINDS = ["array", "inline-table", "dotted-key", "table-header", "array-of-tables"]


def nested_doc(kind: str, depth: int, field: str) -> str:
    if kind == "array":
        return PRESET_TEXT.replace("x_ac = 0.25", f"x_ac = {'[' * depth}0.25{']' * depth}")
    if kind == "inline-table":
        return PRESET_TEXT.replace("x_ac = 0.25", f"x_ac = {'{a = ' * depth}1{'}' * depth}")
    key = ".".join([field] * depth)
    if kind == "dotted-key":
        return PRESET_TEXT + f"\n[blade2]\n{key} = 1\n"
    if kind == "table-header":
        return PRESET_TEXT + f"\n[{key}]\nx = 1\n"
    return PRESET_TEXT + f"\n[[{key}]]\nx = 1\n"


@settings(max_examples=n("loader-nested"))
@given(kind=st.sampled_from(NEST_KINDS), depth=st.one_of(st.integers(1, 40), st.integers(41, 20_000)),
       field=st.sampled_from(["a", "blade", "x_ac", '"q"']))
def test_loader_deeply_nested(rss_bound, kind, depth, field):
    outcome = outcome_of("loader: nested", "loader", lambda: load_text(nested_doc(kind, depth, field)))
    if depth > 40:
        assert outcome == "clean error"


@settings(max_examples=n("loader-huge"))
@given(size=st.sampled_from([MAX_FILE_BYTES - 200, MAX_FILE_BYTES + 1, 2 * MAX_FILE_BYTES, 3 * MAX_FILE_BYTES]),
       how=st.sampled_from(["comment", "string", "array"]))
def test_loader_huge_files(rss_bound, size, how):
    pad = size - len(PRESET_TEXT.encode())
    if how == "comment":
        text = PRESET_TEXT + ("# " + "x" * 98 + "\n") * (pad // 101)
    elif how == "string":
        text = PRESET_TEXT.replace('name = "mccutcheon"', 'name = "' + "n" * pad + '"')
    else:
        text = PRESET_TEXT.replace("x_ac = 0.25", "x_ac = [" + "0.25, " * (pad // 6) + "0.25]")
    outcome = outcome_of("loader: huge", "loader", lambda: load_text(text))
    if len(text.encode()) > MAX_FILE_BYTES:
        assert outcome == "clean error"


@settings(max_examples=n("loader-text"))
@given(text=st.one_of(st.text(max_size=400), st.text(alphabet="[]{}=.,\"'#\n abc123", max_size=400)))
def test_loader_arbitrary_text(rss_bound, text):
    outcome_of("loader: arbitrary text", "loader", lambda: load_text(text))


@pytest.mark.parametrize("special", ["/dev/zero", "/dev/null", "fifo", "directory", "dangling"])
def test_loader_special_files(tmp_path, special):
    path = {"/dev/zero": "/dev/zero", "/dev/null": "/dev/null"}.get(special)
    if special == "fifo":
        path = tmp_path / "f.toml"
        os.mkfifo(path)
    elif special == "directory":
        path = tmp_path
    elif special == "dangling":
        path = tmp_path / "d.toml"
        os.symlink(tmp_path / "none", path)
    before = peak_rss_mib()
    with time_bound(5.0):
        with pytest.raises(RotorError, match=re.escape(str(path))):
            load_rotor_file(path)
    assert peak_rss_mib() - before < 50
    count("loader: special files", "clean error")


# ============================================================================ the command line
def _fresh_paths():
    d = Path(tempfile.mkdtemp(dir=_DIR))
    (d / "dir").mkdir()
    fifo = d / "fifo"
    os.mkfifo(fifo)
    (d / "rotor.toml").write_text(PRESET_TEXT)
    (d / "bad.toml").write_text(PRESET_TEXT.replace("x_cg = [0.3,", "x_cg = [1.3,"))
    return d


_P = _fresh_paths()
OUT_PATHS = [str(_P / "out.csv"), str(_P / "dir"), str(_P / "missing" / "x.csv"), "/dev/full", str(_P / "fifo"),
             str(_P / ("x" * 300)), str(_P / "rotor.toml" / "x"), ""]
ROTOR_PATHS = [str(_P / "rotor.toml"), str(_P / "bad.toml"), "/dev/zero", str(_P / "fifo"), str(_P / "dir"),
               str(_P / "nope.toml"), str(PRESET)]
PRESETS = ["mccutcheon", "paper-boundary", "../../tmp/x", "x" * 256, "", "mccutcheon.toml", "nope"]


def num_text(lo, hi):
    return st.one_of(st.floats(lo, hi).map(repr), st.integers(int(lo) - 2, int(hi) + 2).map(str),
                     st.sampled_from(["nan", "inf", "-inf", "1e400", "-0", "0x10", "", "one", "1,5", "1e-400"]))


def flag_strategies(cmd):
    common = {"--preset": st.sampled_from(PRESETS), "--rotor": st.sampled_from(ROTOR_PATHS),
              "--json": st.none()}
    over = {"--gj": num_text(0.5, 2e6), "--ea": num_text(-0.1, 1.1), "--cg": num_text(-0.1, 1.1)}
    flight = {"--mu": num_text(-0.1, 0.6), "--airspeed": num_text(-5, 90),
              "--fidelity": st.sampled_from(["rigid", "fem-torsion", "fem-coupled", "rigid2"]),
              "--elements": num_text(0, 70)}
    out = {"--out": st.sampled_from(OUT_PATHS)}
    per = {
        "rotor": {**common, **over},
        "modes": {**common, **over, "--omega": num_text(-1, 250), "--elements": num_text(0, 70),
                  "--fidelity": flight["--fidelity"]},
        "trim": {**common, **over, **flight, "--omega-hold": num_text(0, 250)},
        "stability": {**common, **over, **flight, "--aero": st.sampled_from(["theodorsen", "quasi-steady", "x"]),
                      "--all-modes": st.none()},
        "simulate": {**common, **over, **flight, **out, "--t-end": num_text(0, 700),
                     "--inflow": st.sampled_from(["uniform", "three-state", "none"]), "--quiet": st.none()},
        "boundary": {"--preset": st.sampled_from(PRESETS), "--rotor": st.sampled_from(ROTOR_PATHS),
                     "--ea": num_text(-0.1, 1.1), "--mu": num_text(-0.1, 0.6),
                     "--cg": st.one_of(st.tuples(st.floats(-0.1, 1.1), st.floats(-0.1, 1.1), st.integers(-1, 300))
                                       .map(lambda t: f"{t[0]}:{t[1]}:{t[2]}"), st.sampled_from(["0.3", "a:b:c", ""])),
                     "--gj": st.tuples(st.floats(0.1, 2e6), st.floats(0.1, 2e6)).map(lambda t: f"{t[0]}:{t[1]}"),
                     "--tol": num_text(0, 2), "--coarse": num_text(0, 300), "--workers": num_text(0, 600),
                     "--scheduler": st.sampled_from(["http://x:1", "tcp://127.0.0.1:9", ""]),
                     "--store": st.sampled_from(OUT_PATHS + ROTOR_PATHS + ["/dev/null"]),
                     **out, "--plot": st.sampled_from(OUT_PATHS), "--json": st.none(), "--quiet": st.none(),
                     "--fidelity": flight["--fidelity"], "--method": st.sampled_from(["eigen", "time", "x"])},
        "validate": {"--out": st.sampled_from(OUT_PATHS), "--quick": st.none()},
        "bench": {"--seconds": num_text(0, 100), "--json": st.none()},
        "serve": {"--port": num_text(-1, 70000)},
    }
    return per[cmd]


@st.composite
def argv_strategy(draw):
    cmd = draw(st.sampled_from(["rotor", "modes", "trim", "stability", "simulate", "boundary", "validate", "bench",
                                "serve", "nope"]))
    if cmd == "nope":
        return [draw(st.sampled_from(["nope", "", "--x", "-h"]))]
    flags = flag_strategies(cmd)
    names = draw(st.lists(st.sampled_from(sorted(flags)), max_size=6, unique=True))
    argv = [cmd]
    for name in names:
        v = draw(flags[name])
        argv += [name] if v is None else [name, v]
    if draw(st.integers(0, 20)) == 0:
        argv.append(draw(st.sampled_from(["--bogus", "extra", "--json=1"])))
    return argv


def _dry(command):
    """The command without its computation: everything that checks the input before it."""
    from amra_core.cli import boundary as b
    from amra_core.cli import common

    def run(args):
        if command == "boundary":
            from amra_core.executor import cap_workers
            b._spec(args)
            cap_workers(args.workers)
            if args.store:
                from amra_core.store import inspect_store_path
                inspect_store_path(args.store)
            if args.scheduler:
                from amra_core.executor import DASK_SCHEMES
                if "://" in args.scheduler and not args.scheduler.startswith(DASK_SCHEMES):
                    raise ValueError(f"--scheduler {args.scheduler!r}: bad scheme")
            return 0
        if command in ("rotor", "modes", "trim", "stability", "simulate"):
            common.load_rotor(args)
        if command in ("trim", "stability", "simulate"):
            common.flight(args)
            SolverSettings(fidelity=args.fidelity, n_elements=args.elements)
        return 0
    return run


def run_main(argv, dry):
    """(exit code, stdout, stderr) of ``amra argv`` in-process; ``dry``: commands do not compute."""
    import amra_core.cli as cli_pkg
    from amra_core.cli import bench, boundary, modes, serve, simulate, stability, trim, validate
    from amra_core.cli import rotor as rotor_cmd
    mods = {"rotor": (rotor_cmd, "cmd_rotor"), "modes": (modes, "cmd_modes"), "trim": (trim, "cmd_trim"),
            "stability": (stability, "cmd_stability"), "simulate": (simulate, "cmd_simulate"),
            "boundary": (boundary, "cmd_boundary"), "validate": (validate, "cmd_validate"),
            "bench": (bench, "cmd_bench"), "serve": (serve, "cmd_serve")}
    saved = {}
    out, err = io.StringIO(), io.StringIO()
    try:
        for cmd, (mod, name) in mods.items():
            if dry or cmd in ("validate", "bench", "serve", "simulate", "boundary"):
                saved[(mod, name)] = getattr(mod, name)
                setattr(mod, name, _dry(cmd))
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                rc = cli_pkg.main(argv)
            except SystemExit as exc:
                rc = exc.code
    finally:
        for (mod, name), fn in saved.items():
            setattr(mod, name, fn)
    return rc, out.getvalue(), err.getvalue()


def check_cli_case(area, argv, dry):
    got = {}

    def go():
        got["r"] = run_main(argv, dry)
    outcome_of(area, "cli", go, count_result=False)  # an exception escaping main() is a traceback
    rc, out, err = got["r"]
    assert "Traceback" not in err and "Traceback" not in out, (argv, err)
    if rc == 2:
        lines = [ln for ln in err.strip().splitlines() if ln.strip()]
        assert lines and (lines[-1].startswith("amra") or "error:" in lines[-1]), (argv, err)
        assert "error:" in err, (argv, err)
        count(area, "clean error")  # exit 2 with a message
    else:
        assert rc in (0, None), (argv, rc, err)
        if "--json" in argv and not dry and out.strip():
            json.loads(out, parse_constant=lambda t: pytest.fail(f"non-strict JSON constant {t} for {argv}"))
        count(area, "result")  # exit 0


@settings(max_examples=n("cli-arguments"))
@given(argv=argv_strategy())
def test_cli_argument_space(rss_bound, argv):
    """Any command line: the argument, path, rotor and override checks end in exit 0 or a clean
    exit 2 (the computation itself is replaced by a stub here; see test_cli_full_runs)."""
    check_cli_case("cli: arguments", argv, dry=True)


@st.composite
def full_argv(draw):
    cmd = draw(st.sampled_from(["rotor", "modes", "trim", "stability"]))
    argv = [cmd, "--preset", draw(st.sampled_from(["mccutcheon", "paper-boundary"])), "--json"]
    for flag, lo, hi in (("--gj", 1.0, 1e6), ("--ea", 0.0, 1.0), ("--cg", 0.0, 1.0)):
        if draw(st.booleans()):
            v = draw(st.floats(math.log(lo), math.log(hi)).map(math.exp)) if flag == "--gj" else draw(st.floats(lo, hi))
            argv += [flag, repr(v)]
    if cmd != "rotor":
        argv += ["--fidelity", draw(st.sampled_from(["rigid", "fem-torsion", "fem-coupled"])),
                 "--elements", str(draw(st.integers(1, 6)))]
    if cmd in ("trim", "stability") and draw(st.integers(0, 3)) == 0:
        argv += ["--mu", repr(draw(st.floats(0.0, 0.5)))]
    if cmd == "modes":
        argv += ["--omega", repr(draw(st.floats(0.0, 200.0)))]
    return argv


@settings(max_examples=n("cli-full"))
@given(argv=full_argv())
def test_cli_full_runs(rss_bound, argv):
    """Real runs of the cheap commands with valid, extreme values: an answer or a clean exit 2."""
    check_cli_case("cli: full runs", argv, dry=False)


# ============================================================================ the Python API
#: an open finding outside this branch's files (simulation.py, live-solver): counted as a traceback in
#: the report and pinned by test_api_no_trim_state_is_a_project_error (strict xfail), not hidden
KNOWN_OPEN = "no trimmed state to start from"


@st.composite
def api_case(draw):
    gj = math.exp(draw(st.floats(math.log(1.0), math.log(1e6))))
    ea = draw(st.floats(0.0, 1.0))
    # mostly physical sections (|x_cg - x_ea| below the inertia bound 0.25 of the presets), sometimes not
    off = draw(st.one_of(st.floats(-0.249, 0.249), st.floats(-0.249, 0.249), st.floats(-1.0, 1.0)))
    cg = min(1.0, max(0.0, ea + off))
    mu = draw(st.one_of(st.none(), st.none(), st.floats(0.0, 0.5)))
    s = dict(aero=draw(st.sampled_from(["theodorsen", "quasi-steady"])),
             inflow=draw(st.sampled_from(["uniform", "three-state"])), n_elements=draw(st.integers(1, 8)))
    change = draw(st.one_of(st.none(), st.tuples(st.floats(0.2, 0.45), st.floats(0.2, 0.45),
                                                st.floats(0.0, math.log(1e6)).map(math.exp))))
    return gj, ea, cg, mu, s, draw(st.integers(1, 30)), change


def _api_run(paper, fid, gj, ea, cg, mu, s, steps, change):
    from amra_core.simulation import Case, Simulation
    rotor = paper.with_overrides(gj_nm2=gj, x_ea=ea, x_cg=cg)
    sim = Simulation(Case(rotor, FlightCondition(mu=mu), SolverSettings(fidelity=fid, **s), t_end_s=1.0))
    sim.advance(n_steps=steps)
    if change is not None:
        sim.set_parameters(x_ea=change[0], x_cg=change[1], gj_nm2=change[2])
        sim.advance(n_steps=steps)
    v = sim.verdict()
    assert isinstance(v.verdict, str) and v.verdict


@pytest.mark.parametrize("fid", ["rigid", "fem-torsion", "fem-coupled"])
@settings(max_examples=n("api"))
@given(case=api_case())
def test_api_extreme_parameters(rss_bound, paper, fid, case):
    """Simulation at every fidelity: trim, a few steps, perhaps a mid-run change of GJ/EA/CG (which
    may alter the number of retained modes), a few more steps, a verdict."""
    def go():
        try:
            _api_run(paper, fid, *case)
        except RuntimeError as exc:
            if KNOWN_OPEN not in str(exc):
                raise
            raise KnownOpen(str(exc)) from None
    outcome_of(f"api: {fid}", "api", go)


@pytest.mark.xfail(strict=True, raises=RuntimeError,
                   reason="open (simulation.py, live-solver): Simulation raises a bare RuntimeError 'no trimmed "
                          "state to start from' instead of a verdict or a project error (found by hypothesis)")
def test_api_no_trim_state_is_a_project_error(paper):
    try:
        _api_run(paper, "rigid", 1.0, 0.0, 0.0, None, dict(aero="theodorsen", inflow="uniform", n_elements=1), 1,
                 None)
    except PROJECT_ERRORS:
        pass
