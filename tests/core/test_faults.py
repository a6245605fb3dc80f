"""Fault tests (issue 10 §1, §2, §5): a map that is disturbed -- a pool worker killed, the whole
process killed or terminated, its store on a read-only mount, two writers on one store, a damaged
row -- must end in the same map as an uninterrupted run, and never leave a wrong cell in the store
or orphaned worker processes behind.

Every case runs the real CLI (``python -m amra_core.cli boundary``) on a small rigid axial map (3 CG
columns, GJ 100-1500 to 20 %: ~25 cells, seconds on an idle machine). The map engine stores a
column when it is finished, so the faults strike while at least one column is still running. Each case writes a row (case, finished,
identical map, message) to ``faults.json`` in the report folder (:func:`report_dir`).
"""
from __future__ import annotations

import json
import os
import shutil
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest

from report_helpers import record_fault

REPO = Path(__file__).resolve().parents[2]
MAP = ["boundary", "--preset", "paper-boundary", "--fidelity", "rigid", "--mu", "0", "--ea", "0.32",
       "--cg", "0.36:0.48:3", "--coarse", "3", "--tol", "0.2", "--gj", "100:1500", "--json", "--quiet"]
COMPARED = ("critical_gj", "columns", "boundaries", "cells")

pytestmark = [
    pytest.mark.timeout(600), pytest.mark.slow,
    pytest.mark.skipif(os.environ.get("NUMBA_BOUNDSCHECK") == "1",
                       reason="process and store faults, not kernel memory: run once, in the normal pass"),
]


def _env():
    return dict(os.environ, PYTHONPATH=str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", ""))


def cli(*args, timeout=300):
    return subprocess.run([sys.executable, "-m", "amra_core.cli", *MAP, *args], capture_output=True, text=True,
                          timeout=timeout, env=_env(), cwd=REPO)


def start(*args):
    return subprocess.Popen([sys.executable, "-m", "amra_core.cli", *MAP, *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=_env(), cwd=REPO)


def the_map(stdout: str) -> dict:
    d = json.loads(stdout)
    return {k: d[k] for k in COMPARED}


@pytest.fixture(scope="module")
def reference():
    """The uninterrupted map, without a store."""
    r = cli("--workers", "2")
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    assert d["complete"] and d["verdict_counts"]["failed"] == 0
    return {k: d[k] for k in COMPARED}


def stored_rows(path, columns=False, cells=False) -> int:
    """Rows in the store; ``columns``: only those carrying a finished column's record (the map
    engine's unit); ``cells``: only cell results (rows with a verdict)."""
    where = (" WHERE result LIKE '%\"intervals\"%'" if columns else
             " WHERE result LIKE '%\"verdict\"%'" if cells else "")
    try:
        conn = sqlite3.connect(f"file:{path}?mode=ro", uri=True, timeout=5)
        try:
            return conn.execute("SELECT count(*) FROM cells" + where).fetchone()[0]
        finally:
            conn.close()
    except sqlite3.Error:
        return 0


def wait_rows(path, n, proc, timeout=120):
    t_end = time.monotonic() + timeout
    while time.monotonic() < t_end:
        if stored_rows(path, columns=True) >= n:
            return True
        if proc.poll() is not None:
            return False
        time.sleep(0.05)
    return False


def children(pid) -> list[int]:
    try:
        with open(f"/proc/{pid}/task/{pid}/children") as f:
            return [int(x) for x in f.read().split()]
    except OSError:
        return []


def cmdline(pid) -> str:
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            return f.read().replace(b"\0", b" ").decode(errors="replace")
    except OSError:
        return ""


def alive(pid) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"  # a zombie has exited
    except OSError:
        return False


def pool_workers(pid) -> list[int]:
    """The map's pool workers: every child but multiprocessing's resource tracker (spawned workers
    run ``spawn_main``; forked ones, ``amra map`` on Linux, the parent's own command line)."""
    return [c for c in children(pid) if "resource_tracker" not in cmdline(c)]


def wait_gone(pids, timeout=15.0) -> list[int]:
    t_end = time.monotonic() + timeout
    while time.monotonic() < t_end:
        left = [p for p in pids if alive(p)]
        if not left:
            return []
        time.sleep(0.1)
    return [p for p in pids if alive(p)]


def no_worker_deaths_stored(path) -> bool:
    conn = sqlite3.connect(path)
    try:
        rows = [json.loads(r) for (r,) in conn.execute("SELECT result FROM cells")]
        return all("worker" not in str(d.get("reason", "")).lower() and d.get("verdict") != "failed" for d in rows)
    finally:
        conn.close()


# ----------------------------------------------------------------------------- the cases
def test_kill_a_pool_worker_mid_map(tmp_path, reference):
    store = tmp_path / "s.db"
    proc = start("--workers", "2", "--store", str(store))
    killed = 0
    for n in (1, 1):  # twice, once at least one column is stored (the other columns are in flight)
        if wait_rows(store, n, proc):
            ws = pool_workers(proc.pid)
            if ws:
                os.kill(ws[0], signal.SIGKILL)
                killed += 1
    out, err = proc.communicate(timeout=300)
    finished = proc.returncode == 0
    same = finished and the_map(out) == reference
    record_fault("kill a pool worker mid-map (kill -9, twice)", finished, same,
                 f"exit {proc.returncode}; {killed} workers killed; dead workers' cells retried on a fresh pool")
    assert killed >= 1, "the map ended before a worker could be killed"
    assert finished, err
    assert same
    assert no_worker_deaths_stored(store)
    again = cli("--workers", "1", "--store", str(store))
    assert again.returncode == 0 and the_map(again.stdout) == reference
    assert json.loads(again.stdout)["computed_cases"] == 0


@pytest.mark.parametrize("how", ["SIGKILL", "SIGTERM"])
def test_kill_the_whole_process_then_rerun(tmp_path, reference, how):
    store = tmp_path / "s.db"
    proc = start("--workers", "2", "--store", str(store))
    assert wait_rows(store, 1, proc), proc.communicate()[1]
    kids = children(proc.pid)
    assert pool_workers(proc.pid), "no pool workers seen"
    os.kill(proc.pid, getattr(signal, how))
    out, err = proc.communicate(timeout=60)
    left = wait_gone(kids, timeout=15)
    n_kept = stored_rows(store)
    again = cli("--workers", "2", "--store", str(store))
    finished = again.returncode == 0
    same = finished and the_map(again.stdout) == reference
    msg = (err.strip().splitlines()[-1] if how == "SIGTERM" and err.strip()
           else f"killed (exit {proc.returncode}), nothing to report")
    record_fault(f"{how} of the whole process, then rerun on its store", finished, same,
                 f"first run exit {proc.returncode}: {msg}; {n_kept} cells kept; "
                 f"{len(left)} of {len(kids)} child processes left after 15 s")
    assert not left, f"orphaned processes after {how}: {[cmdline(p) for p in left]}"
    if how == "SIGTERM":
        assert proc.returncode == 143, err
        assert "interrupted (SIGTERM)" in err and "rerun with the same --store" in err and "Traceback" not in err
        assert f"holds {n_kept} cells" in err
    assert finished, again.stderr
    assert same
    d = json.loads(again.stdout)
    assert d["cached_cases"] >= 1 and d["cached_cases"] + d["computed_cases"] == d["cases"]
    assert no_worker_deaths_stored(store)


def _unshare_ok() -> str:
    if shutil.which("unshare") is None:
        return "unshare is not installed"
    r = subprocess.run(["unshare", "-m", "true"], capture_output=True, text=True)
    return "" if r.returncode == 0 else f"unshare -m is not permitted here: {r.stderr.strip()}"


@pytest.mark.parametrize("partial", [False, True], ids=["full-store", "partial-store"])
def test_store_on_a_read_only_mount(tmp_path, reference, partial):
    why = _unshare_ok()
    if why:
        pytest.skip(f"needs a private mount namespace for the read-only mount: {why}")
    folder = tmp_path / "ro"
    folder.mkdir()
    store = folder / "s.db"
    if partial:
        proc = start("--workers", "1", "--store", str(store))
        assert wait_rows(store, 1, proc)
        proc.send_signal(signal.SIGINT)
        proc.communicate(timeout=60)
    else:
        assert cli("--workers", "2", "--store", str(store)).returncode == 0
    n0 = stored_rows(store, cells=True)
    before = {p.name: p.read_bytes() for p in folder.iterdir()}
    cmd = " ".join([f"mount --bind {folder} {folder} && mount -o remount,ro,bind {folder} && exec",
                    sys.executable, "-m", "amra_core.cli", *MAP, "--workers", "2", "--store", str(store)])
    r = subprocess.run(["unshare", "-m", "sh", "-c", cmd], capture_output=True, text=True, timeout=300, env=_env(),
                       cwd=REPO)
    finished = r.returncode == 0
    same = finished and the_map(r.stdout) == reference
    warn = next((ln for ln in r.stderr.splitlines() if "read-only" in ln), "")
    record_fault(f"store on a read-only mount ({'partial' if partial else 'complete'} store)",
                 finished, same, f"{n0} cells stored; " + (warn[:160] or r.stderr.strip()[-160:]))
    assert finished, r.stderr
    assert "Traceback" not in r.stderr and "read-only" in warn
    assert same
    d = json.loads(r.stdout)
    assert 0 < d["cached_cases"] <= n0 and (partial or d["cached_cases"] == n0)
    assert {p.name: p.read_bytes() for p in folder.iterdir()} == before  # nothing moved, nothing written


def test_two_writers_on_one_store(tmp_path, reference):
    store = tmp_path / "s.db"
    a = start("--workers", "1", "--store", str(store))
    b = start("--workers", "1", "--store", str(store))
    oa, ea = a.communicate(timeout=300)
    ob, eb = b.communicate(timeout=300)
    finished = a.returncode == 0 and b.returncode == 0
    same = finished and the_map(oa) == reference and the_map(ob) == reference
    again = cli("--workers", "1", "--store", str(store))
    record_fault("two writers on one store (two processes at once)", finished, same,
                 f"exits {a.returncode}, {b.returncode}; then {json.loads(again.stdout)['cached_cases']} of "
                 f"{json.loads(again.stdout)['cases']} cells served from the store")
    assert finished, ea + eb
    assert same
    assert again.returncode == 0 and the_map(again.stdout) == reference
    assert json.loads(again.stdout)["computed_cases"] == 0


def test_a_damaged_row(tmp_path, reference):
    store = tmp_path / "s.db"
    assert cli("--workers", "2", "--store", str(store)).returncode == 0
    conn = sqlite3.connect(store)
    # two plain cells of two different columns: a column whose own record (the row carrying its
    # "column" summary) is damaged is recomputed whole, and its other rows are then never read, so
    # two damages in one column give one warning (which rows those are depends on the key hashes)
    cells = [(k, json.loads(r)) for (k, r) in conn.execute("SELECT key, result FROM cells ORDER BY key")
             if '"verdict"' in r and '"column"' not in r]
    first = cells[0]
    second = next(c for c in cells if c[1]["cg"] != first[1]["cg"])
    keys = [first[0], second[0]]
    r0 = conn.execute("SELECT result FROM cells WHERE key = ?", (keys[0],)).fetchone()[0]
    d0 = json.loads(r0)
    d0["stable"] = not d0["stable"]  # a plausible lie: valid JSON, the opposite verdict
    d0["verdict"] = "stable" if d0["stable"] else "flutter"
    conn.execute("UPDATE cells SET result = ? WHERE key = ?", (json.dumps(d0), keys[0]))
    conn.execute("UPDATE cells SET result = ? WHERE key = ?", ('{"cg": 0.3, "gj_nm2" 1', keys[1]))  # broken JSON
    conn.commit()
    conn.close()
    r = cli("--workers", "2", "--store", str(store))
    finished = r.returncode == 0
    same = finished and the_map(r.stdout) == reference
    warn = [ln for ln in r.stderr.splitlines() if "skipped" in ln]
    record_fault("a damaged row (one edited verdict, one broken JSON)", finished, same,
                 (warn[0][:160] if warn else r.stderr.strip()[-160:]))
    assert finished, r.stderr
    assert "Traceback" not in r.stderr and len(warn) == 2
    assert same
    d = json.loads(r.stdout)
    assert 0 < d["computed_cases"] < d["cases"]  # the damaged rows' columns, not the whole map
    again = cli("--workers", "1", "--store", str(store))  # repaired: served whole, no warning
    assert again.returncode == 0 and "skipped" not in again.stderr
    assert json.loads(again.stdout)["computed_cases"] == 0 and the_map(again.stdout) == reference
