"""The real server (``amra serve``) driven by headless Chromium: faults of the server and its disk,
sessions coming and going, a Dask cluster beside it, and many sessions at once.

Each case uses a small map (``?map_columns=2&map_coarse=3``) so that it completes in the test.
"""
from __future__ import annotations

import asyncio
import os
import re
import signal
import sqlite3
import subprocess
import sys
import time

import pytest

from server_helpers import REPO, free_port, start_amra_serve

pytestmark = pytest.mark.slow
sys.path.insert(0, str(REPO / "scripts"))
import load_test  # noqa: E402

run_async = load_test.run_async


SMALL_MAP = "map_columns=2&map_coarse=3"


async def _with_page(url, fn, launch):
    from playwright.async_api import async_playwright
    async with async_playwright() as p:
        browser = await p.chromium.launch(**launch)
        ctx = await browser.new_context(viewport={"width": 1400, "height": 1000})
        page = await ctx.new_page()
        errors = []
        page.on("pageerror", lambda e: errors.append(str(e)))
        await page.add_init_script(load_test._INIT_JS)
        await page.goto(url, timeout=120_000)
        await page.wait_for_selector(".amra-run button", timeout=120_000)
        try:
            return await fn(page), errors
        finally:
            await browser.close()


async def _text(page, pattern: str) -> str:
    """Text of the first element whose text matches ``pattern`` (Playwright pierces the shadow DOM
    Panel renders into), or ''."""
    loc = page.get_by_text(re.compile(pattern))
    try:
        return await loc.first.inner_text(timeout=1000) if await loc.count() else ""
    except Exception:  # noqa: BLE001 - re-rendered between count and read
        return ""


async def _map_status(page) -> str:
    return await _text(page, r"Map \(")


async def _wait_map(page, pattern, timeout_s, where=_map_status):
    deadline = time.monotonic() + timeout_s
    text = ""
    while time.monotonic() < deadline:
        text = await where(page)
        if re.search(pattern, text):
            return text
        await page.wait_for_timeout(500)
    raise AssertionError(f"map status never matched {pattern!r}; last: {text!r}")


async def _run_streams(page, timeout_s=120) -> float:
    t = await page.evaluate("() => performance.now()")
    await page.click(".amra-run button")
    ms = await page.evaluate(load_test._WAIT_FIRST_JS, [t, timeout_s * 1000])
    assert ms > 0, "no streamed point after Run"
    return ms / 1000


def _stored_columns(path) -> list:
    """Cell counts of the complete columns in the store: the map engine writes a finished column's
    record (``"column"``: its GJ points, intervals, critical GJ) into its top cell's row, written
    last (``boundary.MapRun._store_column``). (This helper used to look for rows keyed ``col-...``,
    a format the store no longer has, so it never saw a column: the cause of this test's failures.)"""
    if not os.path.exists(path):
        return []
    import json
    with sqlite3.connect(f"file:{path}?mode=ro", uri=True, timeout=30) as c:
        try:
            rows = c.execute("""SELECT result FROM cells WHERE result LIKE '%"column"%'""").fetchall()
        except sqlite3.OperationalError:
            return []
    out = []
    for (r,) in rows:
        try:
            out.append(len(json.loads(r)["column"]["gj"]))
        except (ValueError, KeyError, TypeError):
            pass
    return out


def test_store_on_read_only_disk_page_says_so_and_runs_work(amra_server, chromium_args, tmp_path):
    d = tmp_path / "ro"
    d.mkdir()
    subprocess.run(["mount", "-t", "tmpfs", "-o", "size=256k,ro", "tmpfs", str(d)], check=True)
    try:
        base, _ = amra_server(env_extra={"AMRA_STORE": str(d / "amra-store.sqlite"), "AMRA_MAP_WORKERS": "1"})

        async def check(page):
            text = await _wait_map(page, r"not kept", 90, where=lambda pg: _text(pg, r"not kept"))
            first = await _run_streams(page)
            return text, first
        (text, first), errors = run_async(_with_page(f"{base}/main?{SMALL_MAP}", check, chromium_args))
        assert "not kept" in text
        assert first > 0 and not errors
    finally:
        subprocess.run(["umount", "-l", str(d)], capture_output=True)


def test_server_killed_mid_map_resumes_from_the_store(chromium_args, tmp_path):
    store = tmp_path / "store.sqlite"
    env = {"AMRA_STORE": str(store), "AMRA_MAP_WORKERS": "1"}
    from app.app import map_columns
    n_cols = len(map_columns(3))  # 3 asked for, and the paper's 40 % column: 4
    # a fem-coupled map (seconds per column), so the kill lands mid-map: a rigid one finishes in about
    # a second on the warm map workers, before the page has loaded (all four columns were stored at
    # the kill, CI 2026-12-04)
    url_q = "main?map_columns=3&map_coarse=3&fidelity=fem-coupled"
    port = free_port()
    srv = start_amra_serve(tmp_path, port, env_extra=env)
    seen = {}
    try:
        async def until_a_column(page):
            deadline = time.monotonic() + 400
            while not _stored_columns(store) and time.monotonic() < deadline:
                await page.wait_for_timeout(50)
            srv.kill(signal.SIGKILL)  # mid-map, no clean shutdown; at once: the next column is
            # a fraction of a second away (the diagnostics were once read first, and the map
            # finished meanwhile: CI 2026-12-02 00:01 stored all three columns before the kill)
            seen["processes at the kill"] = _processes()
            seen["server log at the kill"] = srv.log_text()[-6000:]
            seen["map status in the page at the kill"] = await _map_status(page)
        run_async(_with_page(f"http://127.0.0.1:{port}/{url_q}", until_a_column, chromium_args))
        srv.proc.wait(10)
    finally:
        srv.stop()
    kept = _stored_columns(store)
    if not 1 <= len(kept) < n_cols:
        _keep_diagnostics(f"columns stored at the kill: {kept}", seen)
    assert 1 <= len(kept) < n_cols, f"columns stored at the kill: {kept} (the kill must come mid-map)"
    port2 = free_port()
    srv2 = start_amra_serve(tmp_path, port2, env_extra=env)
    try:
        async def until_complete(page):
            return await _wait_map(page, r"complete", 600)
        text, errors = run_async(_with_page(f"http://127.0.0.1:{port2}/{url_q}", until_complete, chromium_args))
    except BaseException as exc:
        _keep_diagnostics(f"{type(exc).__name__}: {exc}; stored columns: {_stored_columns(store)}",
                          {"restarted server's log": srv2.log_text()[-6000:], "processes": _processes()})
        raise
    finally:
        srv2.stop()
    m = re.search(r"(\d+) cells \((\d+) from the store\)", text)
    assert m, text
    total, cached = int(m.group(1)), int(m.group(2))
    assert cached >= sum(kept)  # the columns finished before the kill are reused, not recomputed
    assert total > cached  # and the rest was computed after the restart
    assert len(_stored_columns(store)) == n_cols


def _processes() -> str:
    return subprocess.run(["ps", "-eo", "pid,ppid,ni,pcpu,etime,args"], capture_output=True, text=True).stdout[-6000:]


def _keep_diagnostics(what: str, texts: dict) -> None:
    """An expected failure hides its message: keep what the servers did as an artifact
    (test-results/server-killed-mid-map.txt) for the cause still open in issue 11."""
    out = REPO / "test-results" / "server-killed-mid-map.txt"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(what + "\n" + "".join(f"\n--- {k}\n{v}\n" for k, v in texts.items()))


def _threads(pid) -> int:
    return len(os.listdir(f"/proc/{pid}/task"))


def _panel_pid(srv) -> int:
    """The ``panel serve`` process (``amra serve`` execs into it: the same pid)."""
    return srv.pid


def test_fifty_sessions_opened_and_closed_mid_run(amra_server, chromium_args):
    """No leaked threads; memory growth bounded (measured: see the printed figures)."""
    base, srv = amra_server(env_extra={"AMRA_MAP_WORKERS": "1"})
    pid = _panel_pid(srv)

    async def cycle(n):
        from playwright.async_api import async_playwright
        async with async_playwright() as p:
            browser = await p.chromium.launch(**chromium_args)
            firsts = []
            for i in range(n):
                ctx = await browser.new_context()
                page = await ctx.new_page()
                await page.add_init_script(load_test._INIT_JS)
                await page.goto(f"{base}/main?run_s=60", timeout=120_000)
                await page.wait_for_selector(".amra-run button", timeout=120_000)
                t = await page.evaluate("() => performance.now()")
                await page.click(".amra-run button")
                # close mid-run: at the first streamed point, or after 5 s (trimming or streaming)
                firsts.append(await page.evaluate(load_test._WAIT_FIRST_JS, [t, 5000]) / 1000)
                await ctx.close()
            await browser.close()
            return firsts

    def settle(baseline_threads, timeout_s=90):
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if _threads(pid) <= baseline_threads:
                break
            time.sleep(1)
        return _threads(pid)

    threads0 = _threads(pid)
    run_async(cycle(5))  # warm: first sessions load modules, caches, the map registry
    threads_warm = settle(threads0 + 8)
    rss_warm = load_test.tree_rss_mb(pid)
    firsts = run_async(cycle(50))
    threads_end = settle(threads_warm)
    rss_end = load_test.tree_rss_mb(pid)
    streamed = [f for f in firsts if f > 0]
    print(f"\n50 sessions: threads {threads0} -> {threads_warm} (warm) -> {threads_end}; "
          f"RSS {rss_warm:.0f} -> {rss_end:.0f} MB ({rss_end - rss_warm:+.0f} MB); "
          f"{len(streamed)} had streamed before they were closed")
    assert threads_end <= threads_warm, "run or analysis threads of closed sessions were left behind"
    assert rss_end - rss_warm < 200, "memory grew by more than 200 MB over 50 closed sessions"


def test_map_through_a_dask_cluster_beside_the_server(amra_server, chromium_args):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                  silence_logs=40) as cluster, distributed.Client(cluster) as client:
        base, _ = amra_server(env_extra={"AMRA_DASK_SCHEDULER": cluster.scheduler_address})

        async def until_complete(page):
            return await _wait_map(page, r"complete", 600)
        text, errors = run_async(_with_page(f"{base}/main?{SMALL_MAP}", until_complete, chromium_args))
        # the scheduler's record of what ran: compute seconds per task prefix (function name)
        ran = client.run_on_scheduler(lambda dask_scheduler: {
            k: dict(v.all_durations) for k, v in dask_scheduler.task_prefixes.items()})
    assert not errors
    assert re.search(r"(\d+) cells \(0 from the store\)", text), text
    assert ran.get("compute_column", {}).get("compute", 0) > 0, f"no map task ran on the cluster: {ran}"


#: Concurrent sessions this test drives with real browsers on the CI machine. A streaming page costs
#: its browser 0.71 of a core (4 live plots at 10 updates/s, measured with the page alone: 0.38 at
#: 4 updates/s, 0.003 idle), so the two cores hold about two streaming pages beside the server; with
#: eight the pages fall minutes behind and the script's clicks time out in the browsers, not in the
#: server (2026-12-03: 8 sessions, server_p95 0.19 s, page receipt p50 46 s). The server's capacity
#: at 8-32 sessions is measured with clients that render nothing (load_test.py --client protocol,
#: tests/server/test_load.py, README "Scaling the web tier").
CONCURRENT_SESSIONS = 2


def test_load_concurrent_sessions_no_errors(tmp_path):
    """scripts/load_test.py with concurrent sessions: no errors, every slider move seen in its page
    (the figures are printed, not asserted: they are this machine's, browsers included)."""
    n = CONCURRENT_SESSIONS
    rc = subprocess.run([sys.executable, "scripts/load_test.py", "--sessions", str(n), "--moves", "2", "--settled",
                         "--json", str(tmp_path / "load.json")], cwd=REPO, timeout=1500).returncode
    import json
    r = json.loads((tmp_path / "load.json").read_text())[0]
    print(f"\nload N={n}: p50 {r['p50_s']} s, p95 {r['p95_s']} s, server p95 {r.get('server_p95_s')} s, "
          f"errors {r['errors']}, {r.get('mb_per_session')} MB/session, browsers {r.get('client_cpu_cores')} cores")
    assert r["errors"] == 0 and rc == 0, r["error_samples"]
    assert r["moves"] == 2 * n


def test_a_run_stops_when_its_browser_goes(amra_server, chromium_args):
    """A tab closed (or crashed) mid-run: its run went on computing and pushing rows to the closed
    socket until Bokeh destroyed the session, 15 s and more later (tab closed at t = 4.15 s, "run 1
    ended at t = 25.25 s"). It stops at the first delivery with nobody watching."""
    base, srv = amra_server(env_extra={"AMRA_MAP_WORKERS": "1"})

    async def run_then_vanish():
        from playwright.async_api import async_playwright
        async with async_playwright() as p:
            browser = await p.chromium.launch(**chromium_args)
            page = await (await browser.new_context()).new_page()
            await page.add_init_script(load_test._INIT_JS)
            await page.goto(f"{base}/main?run_s=60&speed=1&{SMALL_MAP}", timeout=120_000)
            await page.wait_for_selector(".amra-run button", timeout=120_000)
            t = await page.evaluate("() => performance.now()")
            await page.click(".amra-run button")
            assert await page.evaluate(load_test._WAIT_FIRST_JS, [t, 60_000]) > 0, "the run never streamed"
            await browser.close()  # the browser process ends: the socket drops without a close frame
        return time.monotonic()

    closed_at = run_async(run_then_vanish())
    ended = None
    while ended is None and time.monotonic() < closed_at + 60:
        ended = re.search(r"run 1 ended at t = ([0-9.]+) s", srv.log_text())
        time.sleep(0.2)
    assert ended is not None, srv.log_text()[-3000:]
    waited_s = time.monotonic() - closed_at
    # Bokeh's unused-session lifetime (15 s) is the old bound; nobody watching is seen within a delivery
    assert waited_s < 10.0, f"the run ended {waited_s:.1f} s after its browser went (t = {ended.group(1)} s)"
    assert float(ended.group(1)) < 30.0
