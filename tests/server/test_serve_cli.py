"""``amra serve``: settings from flags and AMRA_* variables, each checked, and the ``panel serve``
command they give (``--print-command``, no server started); then real servers for the HTTP side:
app page, liveness, prefix, basic authentication."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import urllib.parse
import urllib.request
from pathlib import Path
from http.cookiejar import CookieJar

import pytest

from amra_core.cli import main
from amra_core.cli.serve import build_command, resolve

from server_helpers import http_get


def printed(capsys, *argv, env=None, monkeypatch=None):
    for k in [k for k in os.environ if k.startswith("AMRA_")]:
        monkeypatch.delenv(k)
    for k, v in (env or {}).items():
        monkeypatch.setenv(k, v)
    rc = main(["serve", "--print-command", *argv])
    out = capsys.readouterr()
    return rc, (json.loads(out.out) if rc == 0 else None), out.err


def flag_values(argv, flag):
    return [argv[i + 1] for i, a in enumerate(argv) if a == flag]


def test_defaults_no_wildcard_origin(capsys, monkeypatch):
    rc, cmd, _ = printed(capsys, monkeypatch=monkeypatch)
    assert rc == 0
    argv = cmd["argv"]
    assert argv[1:4] == ["-m", "panel", "serve"] and argv[4].endswith("app/main.py")
    assert flag_values(argv, "--allow-websocket-origin") == ["localhost:5006", "127.0.0.1:5006"]
    assert "*" not in argv
    assert "--liveness" in argv and "--admin" not in argv
    assert flag_values(argv, "--setup")[0].endswith("app/warmup.py")
    assert flag_values(argv, "--address") == ["127.0.0.1"] and flag_values(argv, "--port") == ["5006"]
    assert cmd["env"]["AMRA_STORE"].endswith("amra-store.sqlite")
    assert float(cmd["env"]["AMRA_MAX_RUN_S"]) == 120.0
    assert cmd["env"]["BOKEH_RESOURCES"] == "server"  # no CDN (offline servers; Panel's resource-mode race)
    assert cmd["env"]["BOKEH_PERFORM_ERROR_DIAGNOSTICS"] == "false"  # Bokeh's setting for a faster page build


def test_environment_sets_everything(capsys, monkeypatch, tmp_path):
    env = {"AMRA_PORT": "8123", "AMRA_ADDRESS": "10.1.2.3", "AMRA_STORE": str(tmp_path / "s.sqlite"),
           "AMRA_NUM_PROCS": "2", "AMRA_NUM_THREADS": "4", "AMRA_PREFIX": "/team/amra/",
           "AMRA_ALLOW_WEBSOCKET_ORIGIN": "amra.example.org, proxy.local:8443", "AMRA_LIVENESS": "0",
           "AMRA_MAP_WORKERS": "3", "AMRA_DASK_SCHEDULER": "tcp://sched:8786", "AMRA_MAX_RUN_S": "30",
           "AMRA_ADMIN": "1"}
    rc, cmd, _ = printed(capsys, env=env, monkeypatch=monkeypatch)
    assert rc == 0
    argv, e = cmd["argv"], cmd["env"]
    assert flag_values(argv, "--port") == ["8123"] and flag_values(argv, "--address") == ["10.1.2.3"]
    assert flag_values(argv, "--num-procs") == ["2"] and flag_values(argv, "--num-threads") == ["4"]
    assert flag_values(argv, "--prefix") == ["/team/amra"]
    assert flag_values(argv, "--allow-websocket-origin") == ["amra.example.org", "proxy.local:8443"]
    assert "--liveness" not in argv and "--admin" in argv
    assert e["AMRA_STORE"] == env["AMRA_STORE"] and e["AMRA_MAP_WORKERS"] == "3"
    assert e["AMRA_DASK_SCHEDULER"] == "tcp://sched:8786" and float(e["AMRA_MAX_RUN_S"]) == 30.0


def test_flag_wins_over_environment(capsys, monkeypatch):
    rc, cmd, _ = printed(capsys, "--port", "9001", env={"AMRA_PORT": "8123"}, monkeypatch=monkeypatch)
    assert rc == 0 and flag_values(cmd["argv"], "--port") == ["9001"]
    assert flag_values(cmd["argv"], "--allow-websocket-origin") == ["localhost:9001", "127.0.0.1:9001"]


def test_specific_address_is_an_allowed_origin(capsys, monkeypatch):
    rc, cmd, _ = printed(capsys, "--address", "192.168.1.5", "--port", "7000", monkeypatch=monkeypatch)
    assert flag_values(cmd["argv"], "--allow-websocket-origin") == ["192.168.1.5:7000", "localhost:7000",
                                                                  "127.0.0.1:7000"]


@pytest.mark.parametrize("env, flag, fragment", [
    ({"AMRA_PORT": "abc"}, (), "AMRA_PORT = 'abc' is not an integer: allowed [1, 65535]"),
    ({"AMRA_PORT": "70000"}, (), "AMRA_PORT = 70000 is out of range"),
    ({}, ("--port", "0"), "--port = 0 is out of range"),
    ({"AMRA_NUM_PROCS": "-1"}, (), "AMRA_NUM_PROCS = -1 is out of range"),
    ({"AMRA_ALLOW_WEBSOCKET_ORIGIN": "http://evil.example/"}, (), "give HOST[:PORT]"),
    ({"AMRA_ALLOW_WEBSOCKET_ORIGIN": "host:99999"}, (), "give HOST[:PORT]"),
    ({"AMRA_LIVENESS": "maybe"}, (), "AMRA_LIVENESS = 'maybe' is not allowed: give 1 or 0"),
    ({"AMRA_PREFIX": "../etc"}, (), "AMRA_PREFIX = '../etc' is not allowed"),
    ({"AMRA_MAX_RUN_S": "nan"}, (), "AMRA_MAX_RUN_S = nan is out of range"),
    ({"AMRA_DASK_SCHEDULER": "sched:8786"}, (), "tcp://host:8786"),
    ({"AMRA_BASIC_AUTH": "/nonexistent/users.json"}, (), "AMRA_BASIC_AUTH = '/nonexistent/users.json': cannot read it"),
])
def test_bad_values_name_the_setting(capsys, monkeypatch, env, flag, fragment):
    rc, _, err = printed(capsys, *flag, env=env, monkeypatch=monkeypatch)
    assert rc == 2
    assert fragment in err and "Traceback" not in err


def test_basic_auth_file_checked_and_secrets_not_in_argv(capsys, monkeypatch, tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('["alice"]')
    rc, _, err = printed(capsys, "--basic-auth", str(bad), monkeypatch=monkeypatch)
    assert rc == 2 and "non-empty JSON object" in err
    users = tmp_path / "users.json"
    users.write_text('{"alice": "pw-1"}')
    args = type("A", (), {"basic_auth": str(users), "cookie_secret": "s3cret-cookie"})()
    s = resolve(args, {})
    argv, env = build_command(s, {})
    assert flag_values(argv, "--basic-auth") == [str(users.resolve())]
    assert "s3cret-cookie" not in " ".join(argv) and "pw-1" not in " ".join(argv)
    assert env["PANEL_COOKIE_SECRET"] == "s3cret-cookie"
    # no secret given: a random one per start, still only in the environment
    argv, env = build_command(resolve(type("A", (), {"basic_auth": str(users)})(), {}), {})
    assert len(env["PANEL_COOKIE_SECRET"]) >= 32 and env["PANEL_COOKIE_SECRET"] not in argv
    with pytest.raises(Exception, match="choose one authentication"):
        build_command(s, {"PANEL_OAUTH_PROVIDER": "github"})


def test_explicit_wildcard_is_accepted_with_warning(capsys, monkeypatch):
    rc, cmd, _ = printed(capsys, "--allow-websocket-origin", "*", monkeypatch=monkeypatch)
    assert rc == 0 and flag_values(cmd["argv"], "--allow-websocket-origin") == ["*"]


def test_dashboard_script_calls_amra_serve():
    text = open("scripts/dashboard.sh").read()
    assert "amra_venv" in text and "-m amra_core.cli serve" in text


@pytest.mark.slow
def test_served_page_liveness_and_prefix(amra_server):
    base, srv = amra_server("--prefix", "amra")
    status, body, _ = http_get(f"{base}/amra/main")
    assert status == 200 and b"bokeh" in body.lower()
    status, body, _ = http_get(f"{base}/amra/liveness")
    assert status == 200 and json.loads(body) == {"/amra/liveness": True}
    assert http_get(f"{base}/main")[0] == 404
    assert "AMRA dashboard at http://127.0.0.1:" in srv.log_text()


@pytest.mark.slow
def test_basic_auth_gate(amra_server, tmp_path):
    users = tmp_path / "users.json"
    users.write_text('{"alice": "Correct-Horse-1"}')
    base, _ = amra_server("--basic-auth", str(users))
    status, _, headers = http_get(f"{base}/main")
    assert status == 302 and "/login" in headers["Location"]
    assert http_get(f"{base}/liveness")[0] == 200  # the health check needs no login

    def login(password):
        jar = CookieJar()
        opener = urllib.request.build_opener(urllib.request.HTTPCookieProcessor(jar))
        data = urllib.parse.urlencode({"username": "alice", "password": password}).encode()
        with opener.open(f"{base}/login", data=data, timeout=10) as r:
            return r.geturl(), opener

    url, _ = login("wrong")
    assert "error=Invalid" in url
    url, opener = login("Correct-Horse-1")
    with opener.open(f"{base}/main", timeout=10) as r:
        assert r.status == 200 and r.geturl().endswith("/main")


def test_help_lists_the_variables():
    out = subprocess.run([sys.executable, "-m", "amra_core.cli", "serve", "--help"], capture_output=True,
                         text=True, check=True).stdout
    for var in ("AMRA_PORT", "AMRA_STORE", "AMRA_NUM_PROCS", "AMRA_ALLOW_WEBSOCKET_ORIGIN", "AMRA_BASIC_AUTH",
                "AMRA_DASK_SCHEDULER", "AMRA_MAX_RUN_S"):
        assert var in out


def test_the_validation_report_is_served_beside_the_app():
    """The page's help links validation/report.html: amra serve serves docs/validation there."""
    argv, _ = build_command(resolve(type("A", (), {})(), {}), {})
    (spec,) = flag_values(argv, "--static-dirs")
    name, folder = spec.split("=", 1)
    assert name == "validation" and (Path(folder) / "report.html").is_file()


def test_num_procs_zero_is_one_server_process_per_core(amra_server):
    """``--num-procs 0`` ("one per core") went to Panel as 0, whose ``--setup`` then ran once, before the
    fork: the pools were the parent's and no session's Run ever started. Now it is the core count,
    and each serving process warms up (builds its own pools) after the fork."""
    import time
    s = resolve(type("A", (), {"num_procs": "0"})(), {})
    argv, _ = build_command(s, {})
    cores = os.cpu_count() or 1
    assert flag_values(argv, "--num-procs") == [str(cores)]
    _, srv = amra_server("--num-procs", "0")
    t_end = time.monotonic() + 180
    while srv.log_text().count("AMRA warm-up: kernels ready") < cores and time.monotonic() < t_end:
        time.sleep(0.5)
    assert srv.log_text().count("AMRA warm-up: kernels ready") == cores, srv.log_text()[-3000:]
