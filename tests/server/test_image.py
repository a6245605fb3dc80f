"""The Docker image, built and run without a Docker engine (buildah, chroot isolation): it builds
from the project's Dockerfile on a locally made Debian base, runs as a non-root user, loads its
Numba cache instead of compiling, and serves the app page, the liveness endpoint, the image's
own HEALTHCHECK and a streaming session, with the store on the /data volume.

Needs root, buildah and debootstrap (scripts/test.sh installs them). The first run makes the base
(~3 min, cached under /var/tmp/amra-base) and the dependency layer (~1.5 min, cached by buildah
until pyproject.toml changes); later runs rebuild only the project layers.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import time
import uuid

import pytest

from server_helpers import REPO, ServerProcess, free_port, http_get, wait_for_http

pytestmark = pytest.mark.slow
TAG = "localhost/amra:test"


#: where Debian installs the tools (debootstrap is in /usr/sbin, often missing from a user's PATH)
TOOL_PATH = os.pathsep.join([os.environ.get("PATH", ""), "/usr/local/sbin", "/usr/sbin", "/sbin"])


@pytest.fixture(scope="module", autouse=True)
def _sbin_on_path():
    """The build script and buildah's helpers find the tools in /usr/sbin even when PATH lacks it."""
    old = os.environ.get("PATH", "")
    os.environ["PATH"] = TOOL_PATH
    yield
    os.environ["PATH"] = old


def _need_tools():
    missing = [t for t in ("buildah", "debootstrap") if shutil.which(t, path=TOOL_PATH) is None]
    if missing:
        pytest.fail(f"missing {', '.join(missing)}: scripts/test.sh installs them (apt-get install buildah debootstrap)")
    if os.geteuid() != 0:
        pytest.fail("the image tests build with buildah as root (chroot isolation); run them as root")


@pytest.fixture(scope="module")
def image():
    _need_tools()
    t0 = time.monotonic()
    out = subprocess.run(["bash", "scripts/build_image.sh", TAG], cwd=REPO, capture_output=True, text=True,
                         timeout=1800)
    elapsed = time.monotonic() - t0
    assert out.returncode == 0, f"image build failed:\n{out.stderr[-4000:]}"
    print(f"\nimage build: {elapsed:.0f} s ({out.stdout.strip().splitlines()[-1]})")
    return TAG


@pytest.fixture
def container(image, tmp_path):
    name = f"amra-test-{uuid.uuid4().hex[:8]}"
    subprocess.run(["buildah", "from", "--name", name, image], check=True, capture_output=True)
    data = tmp_path / "data"
    data.mkdir()
    os.chown(data, 1000, 1000)  # the image's user amra (uid 1000) owns its volume
    try:
        yield name, data
    finally:
        subprocess.run(["buildah", "rm", name], capture_output=True)


def run_in(name, *cmd, env=None, volumes=(), timeout=120):
    argv = ["buildah", "run", "--isolation", "chroot"]
    for k, v in (env or {}).items():
        argv += ["-e", f"{k}={v}"]
    for v in volumes:
        argv += ["-v", v]
    return subprocess.run([*argv, name, *cmd], capture_output=True, text=True, timeout=timeout)


def test_image_config(image):
    info = json.loads(subprocess.run(["buildah", "inspect", "--type", "image", image], capture_output=True,
                                     text=True, check=True).stdout)
    cfg = info["Docker"]["config"]
    env = dict(e.split("=", 1) for e in cfg["Env"])
    assert cfg["User"] == "amra"
    assert env["AMRA_STORE"] == "/data/amra-store.sqlite" and "/data" in cfg["Volumes"]
    assert env["NUMBA_CPU_NAME"] == "generic" and env["NUMBA_CACHE_DIR"].startswith("/var/cache/amra")
    assert cfg["Cmd"] == ["amra", "serve"]
    assert "liveness" in " ".join(cfg["Healthcheck"]["Test"])
    assert "*" not in env.get("AMRA_ALLOW_WEBSOCKET_ORIGIN", "")


def test_runs_as_non_root_and_uses_the_build_cache(container):
    name, _ = container
    r = run_in(name, "id", "-u")
    assert r.stdout.strip() == "1000"
    # the code is not the runtime user's to change
    r = run_in(name, "sh", "-c", "touch /opt/amra/amra_core/x 2>&1; echo rc=$?")
    assert "rc=0" not in r.stdout
    # a fresh process: every kernel is loaded from the build-time cache, none compiled and saved
    r = run_in(name, "python3", "-m", "app.warmup", env={"NUMBA_DEBUG_CACHE": "1", "AMRA_STORE": "/tmp/s.sqlite"},
               timeout=300)
    assert r.returncode == 0, r.stderr
    assert "data loaded from" in r.stdout
    assert "data saved to" not in r.stdout, "kernels were recompiled at run time: the build's cache was not used"


def test_serves_page_liveness_healthcheck_and_stream(container, chromium_args):
    name, data = container
    port = free_port()
    # (buildah run shadows a bind mount onto a VOLUME path with the container's own volume, so the
    # store is looked for in that volume afterwards, not in a host directory)
    argv = ["buildah", "run", "--isolation", "chroot", "-e", f"AMRA_PORT={port}", name, "amra", "serve"]
    srv = ServerProcess(argv, log=data.parent / "container.log")
    base = f"http://127.0.0.1:{port}"
    try:
        t0 = time.monotonic()
        wait_for_http(f"{base}/liveness", 180, srv.proc)
        startup = time.monotonic() - t0
        status, body, _ = http_get(f"{base}/main")
        assert status == 200 and b"bokeh" in body.lower()
        assert json.loads(http_get(f"{base}/liveness")[1]) == {"/liveness": True}
        # the image's own HEALTHCHECK command, run inside the container against the server
        info = json.loads(subprocess.run(["buildah", "inspect", "--type", "image", TAG], capture_output=True,
                                         text=True, check=True).stdout)
        test = info["Docker"]["config"]["Healthcheck"]["Test"]
        assert test[0] == "CMD-SHELL"
        hc = run_in(name, "sh", "-c", test[1], env={"AMRA_PORT": str(port)})
        assert hc.returncode == 0, hc.stderr
        # a browser session streams points from a run
        from load_test import first_stream_seconds
        first = first_stream_seconds(f"{base}/main", chromium_args)
        assert first < 60
        print(f"\ncontainer: liveness after {startup:.1f} s; first streamed point {first:.2f} s after Run")
    finally:
        srv.stop()
        log = srv.log_text()
    assert "AMRA dashboard at http://localhost:" in log
    r = run_in(name, "python3", "-c", "import sqlite3; c = sqlite3.connect('file:/data/amra-store.sqlite?mode=ro', "
               "uri=True); print(hex(c.execute('PRAGMA application_id').fetchone()[0]))")
    assert r.stdout.strip() == "0x414d5241", f"no AMRA store on the /data volume: {r.stderr}\n{log[-2000:]}"
