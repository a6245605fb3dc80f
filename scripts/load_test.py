"""Many users at once: N concurrent sessions against one AMRA server, with the server pinned to its
own CPUs (``--server-cpus``) and the clients to the others, so what is measured is the server, not
the clients it would share its cores with.

Two clients (``--client``):

* ``protocol``: each session speaks Bokeh's websocket protocol (:class:`ProtocolSession`, built
  from ``bokeh.protocol`` as ``bokeh.client`` is) and renders nothing. The server does exactly the
  work it does for a browser: it builds the page, sends the document and every patch, the streamed
  rows included; the client receives them all and sends what a page sends (the document is ready,
  Run's ``ButtonClick``, the GJ slider's ``value``/``value_throttled``). A session costs its client
  about 0.03 of a core while it streams, so this machine's second core holds the clients of 32.
  Sessions run on one asyncio loop per client process (``--client-procs``, default one per 8).
* ``browser`` (default): headless Chromium pages. A streaming page costs its browser 0.71 of a core,
  so beyond two sessions the browsers need machines of their own (``--url``).

Each session opens the dashboard (``/main?run_s=...&gj=...``, each its own GJ), presses Run, and
once rows stream (and, with ``--settled``, once every session streams) moves the GJ slider
``--moves`` times, 0.8 s apart, each about +0.13 decade stiffer so the run goes on; meanwhile the
boundary map of the sessions' case fills (one shared map job). Measured in each client:

* **slider latency**: from the slider's release (set by the protocol client; ``pointerup`` in a
  browser) to the first streamed row computed with the new GJ in the client (the live plot's data
  carries the GJ of every row); a browser's includes drawing it, the protocol client's does not;
* ``load_s``: connect to the document received (protocol), or page load to the Run button shown;
* run start: from Run to the first streamed row;
* errors: a websocket that closed, timeouts, no rows, an error alert in the page (the "messages"
  alert pane visible with text), and for browsers page exceptions and console errors;
* the server's share of the slider latency: from the change reaching the server to the first rows
  computed with it leaving the server (from the server's log).

The server (``amra serve``, fresh store per session count) is started by the script unless
``--url`` is given; its memory (RSS of the whole process tree) is sampled before the sessions and
while they run, giving the memory per session, and its CPU time while every session streams,
giving the server CPU per streaming session (the process tree, whose boundary map at nice 10 takes
whatever is left of its cores, and the server process alone). ``page_build_s`` is the server's own
time to build a session's page (logged by app/main.py).

Per session count the JSON has ``errors``, ``p50_s``/``p95_s`` (slider release to the first row
with the new GJ in the client), ``server_p50_s``/``server_p95_s`` (the change received by the server
to the first rows computed with it sent), ``page_build_p50_s``/``page_build_p95_s``,
``run_first_p50_s``/``p95_s``, ``load_p50_s``/``p95_s``, ``server_cpu_per_session`` and
``server_main_cpu_per_session`` (cores), ``mb_per_session``, ``client`` and ``client_cpu_cores``
(the clients' own CPU use; ``client_cpu_streaming_cores`` while every session streams).

    python scripts/load_test.py --client protocol --sessions 1 8 16 32 --server-cpus 0 --settled \
        --timeout 300 --json load.json

A benchmark, not a timed test: tests/server/test_load.py runs the protocol client at N = 2 and
asserts no errors and every move seen; tests/server/test_sessions.py runs the browser client at N = 2.
"""
from __future__ import annotations

import argparse
import asyncio
import json
import os
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import time
import urllib.parse
import urllib.request
from pathlib import Path

#: as in tests/browser/conftest.py (Debian's Chromium, headless in a container)
CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
                 "--no-first-run", "--disable-sync"]
CHROMIUM = "/usr/bin/chromium"
REPO = Path(__file__).resolve().parents[1]

#: in-page helpers: the live plot's data source (columns t_s and gj_nm2), release time, errors
_INIT_JS = """
window.__amra = {release: null, wsClosed: 0};
document.addEventListener('pointerup', () => { window.__amra.release = performance.now(); }, true);
window.__amraSource = () => {
  // the live plots' source, found once (the probe runs every 10 ms: it must not load a busy page)
  const m = window.__amra.model;
  if (m) return m.data;
  for (const doc of (window.Bokeh ? Bokeh.documents : [])) {
    for (const m of doc.all_models) {
      const d = m.data;
      if (d === undefined || d === null || typeof d !== 'object' || d instanceof Map) continue;
      if (d.t_s !== undefined && d.gj_nm2 !== undefined) { window.__amra.model = m; return d; }
    }
  }
  return null;
};
window.__amraLast = () => {
  const d = window.__amraSource();
  if (!d || !d.t_s.length) return null;
  return {n: d.t_s.length, t: d.t_s[d.t_s.length - 1], gj: d.gj_nm2[d.gj_nm2.length - 1]};
};
"""

_WAIT_FIRST_JS = """([t0, timeout_ms]) => new Promise((resolve) => {
  const iv = setInterval(() => {
    const last = window.__amraLast();
    if (last) { clearInterval(iv); resolve(performance.now() - t0); }
  }, 10);
  setTimeout(() => { clearInterval(iv); resolve(-1); }, timeout_ms);
})"""

_WAIT_NEW_GJ_JS = """([old, timeout_ms]) => new Promise((resolve) => {
  const iv = setInterval(() => {
    const last = window.__amraLast();
    const t0 = window.__amra.release;
    if (last && t0 !== null && Math.abs(last.gj - old) > 1e-6 * Math.abs(old)) {
      clearInterval(iv);
      const now = performance.now();
      resolve([now - t0, (performance.timeOrigin + t0) / 1000, (performance.timeOrigin + now) / 1000, last.gj]);
    }
  }, 10);
  setTimeout(() => { clearInterval(iv); resolve([-1, 0, 0, 0]); }, timeout_ms);
})"""


# ---------------------------------------------------------------------------- server
def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def tree_rss_mb(pid: int) -> float:
    """Resident memory of ``pid`` and all its descendants [MB] (from /proc)."""
    children: dict = {}
    for d in os.listdir("/proc"):
        if d.isdigit():
            try:
                with open(f"/proc/{d}/stat") as f:
                    ppid = int(f.read().rsplit(")", 1)[1].split()[1])
                children.setdefault(ppid, []).append(int(d))
            except (OSError, ValueError, IndexError):
                pass
    total, todo = 0, [pid]
    while todo:
        p = todo.pop()
        todo += children.get(p, [])
        try:
            with open(f"/proc/{p}/statm") as f:
                total += int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
        except (OSError, ValueError):
            pass
    return total / 1e6


def _tree(pid: int) -> list:
    children: dict = {}
    for d in os.listdir("/proc"):
        if d.isdigit():
            try:
                with open(f"/proc/{d}/stat") as f:
                    children.setdefault(int(f.read().rsplit(")", 1)[1].split()[1]), []).append(int(d))
            except (OSError, ValueError, IndexError):
                pass
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        out.append(p)
        todo += children.get(p, [])
    return out


def tree_cpu_s(pid: int) -> float:
    """CPU time [s] used so far by ``pid`` and its descendants, those that have exited included
    (a process's reaped children count in its cutime/cstime: without them, a pool process ending
    inside the window took its CPU time out of the sum)."""
    total = 0
    for p in _tree(pid):
        try:
            with open(f"/proc/{p}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            total += int(fields[11]) + int(fields[12]) + int(fields[13]) + int(fields[14])
        except (OSError, ValueError, IndexError):
            pass
    return total / os.sysconf("SC_CLK_TCK")


def cpu_seconds_of(match: str) -> float:
    """CPU time [s] used so far by every process whose command line contains ``match``."""
    total = 0
    for d in os.listdir("/proc"):
        if not d.isdigit():
            continue
        try:
            with open(f"/proc/{d}/cmdline", "rb") as f:
                if match.encode() not in f.read():
                    continue
            with open(f"/proc/{d}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            total += int(fields[11]) + int(fields[12])  # utime + stime [clock ticks]
        except (OSError, ValueError, IndexError):
            pass
    return total / os.sysconf("SC_CLK_TCK")


class Server:
    """``amra serve`` in its own process group on a free port, with a fresh store."""

    def __init__(self, extra_env=None, args=(), cpus: str = ""):
        self.port = free_port()
        self.dir = tempfile.mkdtemp(prefix="amra-load-")
        env = dict(os.environ, AMRA_STORE=f"{self.dir}/store.sqlite", **(extra_env or {}))
        self.log = open(f"{self.dir}/serve.log", "wb")
        pin = ["taskset", "-c", cpus] if cpus else []  # the server and its pool processes on these CPUs
        self.proc = subprocess.Popen([*pin, sys.executable, "-m", "amra_core.cli", "serve", "--address", "127.0.0.1",
                                      "--port", str(self.port), *args], cwd=REPO, env=env, stdout=self.log,
                                     stderr=subprocess.STDOUT, start_new_session=True)
        self.url = f"http://127.0.0.1:{self.port}/main"
        deadline = time.monotonic() + 180
        try:
            while True:
                if self.proc.poll() is not None:
                    raise RuntimeError(f"amra serve exited: {Path(self.dir, 'serve.log').read_text()[-2000:]}")
                try:
                    with urllib.request.urlopen(f"http://127.0.0.1:{self.port}/liveness", timeout=5):
                        break
                except OSError:
                    if time.monotonic() > deadline:
                        raise TimeoutError("amra serve did not answer within 180 s")
                    time.sleep(0.5)
        except BaseException:  # not started, or the script stopped meanwhile (SIGTERM): no orphan server
            self.stop()
            raise

    def rss_mb(self) -> float:
        """The whole tree: the server and its map worker processes [MB]."""
        return tree_rss_mb(self.proc.pid)

    def main_rss_mb(self) -> float:
        """The server process alone (where the sessions live) [MB]."""
        try:
            with open(f"/proc/{self.proc.pid}/statm") as f:
                return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 1e6
        except OSError:
            return 0.0

    def cpu_s(self) -> float:
        """CPU time used so far by the server process tree [s]."""
        return tree_cpu_s(self.proc.pid)

    def main_cpu_s(self) -> float:
        """CPU time used so far by the server process alone [s]: the sessions, their event loop and
        run threads, without the pool and map processes."""
        try:
            with open(f"/proc/{self.proc.pid}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
        except (OSError, ValueError, IndexError):
            return 0.0

    def page_builds_s(self) -> list:
        """Server time of each page build [s] (logged by app/main.py)."""
        import re
        text = Path(self.dir, "serve.log").read_text(errors="replace")
        return [float(x) for x in re.findall(r"page built in ([0-9.]+) s", text)]

    def live_events(self) -> list:
        """Each live change logged by the server: (received, sent) as epoch seconds, and its GJ."""
        import re
        from datetime import datetime
        text = Path(self.dir, "serve.log").read_text(errors="replace")
        out = []
        for stamp, gj, lat in re.findall(r"^(\d{4}-\d\d-\d\d \d\d:\d\d:\d\d,\d{3}) live change to GJ (\S+) "
                                         r".*first rows with it sent ([0-9.]+) s after", text, re.M):
            sent = datetime.strptime(stamp, "%Y-%m-%d %H:%M:%S,%f").timestamp()
            out.append((sent - float(lat), sent, float(gj)))
        return out

    def live_latencies_s(self) -> list:
        """Server side of each slider move: the change received -> first rows with it sent [s]
        (logged by app.session at info level)."""
        import re
        text = Path(self.dir, "serve.log").read_text(errors="replace")
        return [float(x) for x in re.findall(r"first rows with it sent ([0-9.]+) s after", text)]

    def stop(self) -> None:
        for sig in (signal.SIGTERM, signal.SIGKILL):
            try:
                os.killpg(self.proc.pid, sig)
            except ProcessLookupError:
                break
            try:
                self.proc.wait(15)
                break
            except subprocess.TimeoutExpired:
                continue
        try:
            os.killpg(self.proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        self.log.close()


def wrapped_chromium(niceness: int = 0, cpus: str = "") -> str:
    """An executable that starts Chromium at ``niceness`` on ``cpus`` (taskset): the browsers then
    stay off the server's CPUs, as clients on their own machines would (the wrapper goes in a
    temporary directory, never beside a user's files)."""
    path = Path(tempfile.mkdtemp(prefix="amra-load-chromium-"), "chromium")
    pin = f"taskset -c {cpus} " if cpus else ""
    path.write_text(f'#!/bin/sh\nexec {pin}nice -n {int(niceness)} {CHROMIUM} "$@"\n')
    path.chmod(0o755)
    return str(path)


def _cpu_set(cpus: str) -> set:
    """The CPUs of a taskset list ("0", "0,1", "0-1")."""
    out = set()
    for part in cpus.split(","):
        lo, _, hi = part.partition("-")
        out.update(range(int(lo), int(hi or lo) + 1))
    return out


def other_cpus(server_cpus: str) -> str:
    """The machine's CPUs not in ``server_cpus`` ("0", "0,1", "0-1")."""
    rest = sorted(set(os.sched_getaffinity(0)) - _cpu_set(server_cpus))
    if not rest:
        raise SystemExit(f"--server-cpus {server_cpus} leaves no CPU for the clients")
    return ",".join(map(str, rest))


# ---------------------------------------------------------------------------- one session
class Settled:
    """Holds the slider moves until every session streams (or has failed): ``--settled``. Without
    it, the first sessions move their sliders while the later ones still load their pages, and
    each page build holds the server's event loop (app.app), so those moves measure arrival."""

    def __init__(self, sessions: int):
        self.left = sessions
        self.event = asyncio.Event()

    def arrive(self) -> None:
        self.left -= 1
        if self.left <= 0:
            self.event.set()

    async def wait(self, timeout_s: float) -> None:
        try:
            await asyncio.wait_for(self.event.wait(), timeout_s)
        except asyncio.TimeoutError:
            pass


def arrive_once(gate):
    """A callable that marks one session arrived at ``gate`` (None: no gate) at most once: a session
    arrives when it streams, or when it fails, so that it never holds the others."""
    done = []

    def arrive():
        if gate is not None and not done:
            done.append(True)
            gate.arrive()
    return arrive


async def session(browser, url: str, moves: int, timeout_s: float, index: int, stagger_s: float,
                  settled: "Settled | None" = None) -> dict:
    await asyncio.sleep(index * stagger_s)
    arrive = arrive_once(settled)
    out = {"latencies_s": [], "moves": [], "run_first_s": None, "load_s": None, "errors": []}
    ctx = await browser.new_context(viewport={"width": 1400, "height": 1000})
    page = await ctx.new_page()
    page.set_default_timeout(timeout_s * 1000)  # the script's own actions too (Playwright's default: 30 s)
    page.on("pageerror", lambda e: out["errors"].append(f"page error: {e}"))
    page.on("console", lambda m: m.type == "error" and out["errors"].append(f"console: {m.text[:200]}"))
    page.on("requestfailed", lambda r: out["errors"].append(f"request failed: {r.url[:120]} ({r.failure})"))
    page.on("websocket", lambda ws: ws.on("close", lambda _ws: out.setdefault("ws_closed", True)))
    await page.add_init_script(_INIT_JS)
    try:
        t0 = time.monotonic()
        await page.goto(url, timeout=timeout_s * 1000)
        await page.wait_for_selector(".amra-run button", timeout=timeout_s * 1000)
        out["load_s"] = time.monotonic() - t0
        t_click = await page.evaluate("() => performance.now()")
        await page.click(".amra-run button")
        first = await page.evaluate(_WAIT_FIRST_JS, [t_click, timeout_s * 1000])
        if first < 0:
            out["errors"].append("no streamed point after Run")
            return out
        out["run_first_s"] = first / 1000
        arrive()
        if settled is not None:
            await settled.wait(timeout_s)
        handle = page.locator(".amra-gj-slider .noUi-handle").first
        for k in range(moves):
            await page.wait_for_timeout(800)
            last = await page.evaluate("() => window.__amraLast()")
            await handle.scroll_into_view_if_needed()
            box = await handle.bounding_box()
            x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
            dx = 12  # stiffer each time (about +0.13 decade of GJ): the run stays stable and goes on
            await page.mouse.move(x, y)
            await page.mouse.down()
            await page.mouse.move(x + dx, y, steps=4)
            await page.mouse.up()
            lat, released, seen, gj = await page.evaluate(_WAIT_NEW_GJ_JS, [last["gj"], timeout_s * 1000])
            if lat >= 0:
                out["moves"].append({"released": released, "seen": seen, "gj": gj})
            if lat < 0:
                out["errors"].append(f"move {k}: no point with the new GJ within {timeout_s:.0f} s")
            else:
                out["latencies_s"].append(lat / 1000)
        alert = page.locator(".alert-danger")
        if await alert.count() and await alert.first.is_visible():
            text = (await alert.first.inner_text()).strip()
            if text:  # an empty, hidden message pane is not a message
                out["errors"].append(f"alert: {text[:200]}")
    except Exception as exc:  # noqa: BLE001 - a timeout or a crashed page is an error of the session
        out["errors"].append(f"{type(exc).__name__}: {str(exc).splitlines()[0][:200]}")
    finally:
        arrive()  # a failed session must not hold the others
        if out.pop("ws_closed", False):
            out["errors"].append("websocket closed during the session")
        out["page"] = page
        out["ctx"] = ctx
    return out


def split_latencies(moves: list, events: list) -> dict:
    """Where each slider move's latency went: release -> the server has the change, -> the server
    sends the first rows with it, -> those rows are in the page (the log's times are to 1 ms; each
    move is matched to the logged change of its GJ, to the log's 4 digits, sent between its release
    and its arrival)."""
    to_server, in_server, to_page = [], [], []
    for m in moves:
        match = [e for e in events if m["released"] - 0.01 <= e[0] and e[1] <= m["seen"] + 0.01
                 and abs(e[2] - m["gj"]) <= 1e-3 * abs(m["gj"])]
        if len(match) == 1:
            received, sent, _ = match[0]
            to_server.append(received - m["released"])
            in_server.append(sent - received)
            to_page.append(m["seen"] - sent)
    return {"split_moves": len(to_server),
            "release_to_server_p50_s": _pct(to_server, 0.5), "release_to_server_p95_s": _pct(to_server, 0.95),
            "in_server_p50_s": _pct(in_server, 0.5), "in_server_p95_s": _pct(in_server, 0.95),
            "sent_to_page_p50_s": _pct(to_page, 0.5), "sent_to_page_p95_s": _pct(to_page, 0.95)}


def _pct(xs, q):
    if not xs:
        return None
    xs = sorted(xs)
    k = (len(xs) - 1) * q
    lo, hi = int(k), min(int(k) + 1, len(xs) - 1)
    return xs[lo] + (xs[hi] - xs[lo]) * (k - lo)


async def run_level(n: int, url: str, moves: int, timeout_s: float, server=None, run_s: float = 60.0,
                    stagger_s: float = 0.25, launch=None, settled: bool = False) -> dict:
    from playwright.async_api import async_playwright
    launch = launch or {"executable_path": CHROMIUM, "args": CHROMIUM_ARGS, "headless": True}
    rss0 = server.rss_mb() if server else None
    main0 = server.main_rss_mb() if server else None
    peak = [rss0 or 0.0]
    peak_main = [main0 or 0.0]
    stop = asyncio.Event()

    async def sample():
        while not stop.is_set():
            if server:
                peak[0] = max(peak[0], server.rss_mb())
                peak_main[0] = max(peak_main[0], server.main_rss_mb())
            await asyncio.sleep(0.5)

    async with async_playwright() as p:
        browser = await p.chromium.launch(**launch)
        sampler = asyncio.create_task(sample())
        t0 = time.monotonic()
        client_cpu0 = cpu_seconds_of("chromium")
        streaming = {}  # server CPU [s] and time while every session streams (from the gate to the end)

        async def mark_streaming():
            if gate is None:
                return
            await gate.wait(timeout_s * 4)
            if server:
                streaming["cpu0"], streaming["t0"] = server.cpu_s(), time.monotonic()
                streaming["main_cpu0"] = server.main_cpu_s()
        sep = "&" if "?" in url else "?"
        # each session starts from its own GJ (the map, GJ against CG, is the same case for all), so
        # the GJs the slider moves reach are unique to a session and the server's log lines match them
        gate = Settled(n) if settled else None
        marker = asyncio.create_task(mark_streaming())
        results = await asyncio.gather(*[session(browser, f"{url}{sep}run_s={run_s:g}&gj={1500 + 10 * i:g}", moves,
                                                 timeout_s, i, stagger_s, gate) for i in range(n)])
        if server and "cpu0" in streaming:
            streaming["cpu_s"] = server.cpu_s() - streaming["cpu0"]
            streaming["main_cpu_s"] = server.main_cpu_s() - streaming["main_cpu0"]
            streaming["wall_s"] = time.monotonic() - streaming["t0"]
        marker.cancel()
        wall = time.monotonic() - t0
        client_cpu = cpu_seconds_of("chromium") - client_cpu0
        rss_open = server.rss_mb() if server else None
        for r in results:
            try:
                await r.pop("ctx").close()
            except Exception:  # noqa: BLE001
                pass
            r.pop("page", None)
        stop.set()
        await sampler
        await browser.close()
    out = summarize(n, results, wall, settled, server, streaming, (rss0, main0, peak[0], peak_main[0], rss_open))
    # the browsers' share of this machine (they run beside the server on the same cores)
    out.update({"client": "browser", "client_cpu_cores": round(client_cpu / wall, 2)})
    return out


def summarize(n: int, results: list, wall: float, settled: bool, server, streaming: dict, rss: tuple) -> dict:
    """The figures of one session count from its sessions' results (both clients)."""
    rss0, main0, peak, peak_main, rss_open = rss
    lat = [x for r in results for x in r["latencies_s"]]
    firsts = [r["run_first_s"] for r in results if r["run_first_s"] is not None]
    loads = [r["load_s"] for r in results if r["load_s"] is not None]
    errors = [e for r in results for e in r["errors"]]
    out = {"sessions": n, "moves": len(lat), "p50_s": _pct(lat, 0.5), "p95_s": _pct(lat, 0.95),
           "max_s": max(lat) if lat else None, "run_first_p50_s": _pct(firsts, 0.5),
           "run_first_p95_s": _pct(firsts, 0.95), "load_p50_s": _pct(loads, 0.5), "load_p95_s": _pct(loads, 0.95),
           "errors": len(errors), "error_samples": errors[:5], "settled": settled,
           "streamed_sessions": len(firsts), "wall_s": round(wall, 1), "machine_cores": os.cpu_count()}
    if server:
        srv_lat = server.live_latencies_s()
        builds = server.page_builds_s()
        out.update({"server_side_moves": len(srv_lat), "server_p50_s": _pct(srv_lat, 0.5),
                    "server_p95_s": _pct(srv_lat, 0.95), "page_build_p50_s": _pct(builds, 0.5),
                    "page_build_p95_s": _pct(builds, 0.95), "page_build_s": _pct(builds, 0.5)})
        if streaming.get("wall_s"):
            # the whole tree (with the shared boundary map filling at nice 10, it takes what is left of
            # the server's cores), and the server process alone (the sessions' runs and their event loop)
            out["server_cpu_per_session"] = round(streaming["cpu_s"] / streaming["wall_s"] / n, 3)
            out["server_main_cpu_per_session"] = round(streaming["main_cpu_s"] / streaming["wall_s"] / n, 3)
            out["streaming_wall_s"] = round(streaming["wall_s"], 1)
        out.update(split_latencies([m for r in results for m in r["moves"]], server.live_events()))
        out["move_log"] = [dict(m, session=i) for i, r in enumerate(results) for m in r["moves"]]  # epoch s
        out.update({"rss_base_mb": round(rss0, 1), "rss_peak_mb": round(peak, 1),
                    "rss_sessions_open_mb": round(rss_open, 1),
                    "server_rss_base_mb": round(main0, 1), "server_rss_peak_mb": round(peak_main, 1),
                    "mb_per_session": round((peak_main - main0) / n, 1)})
    return out


# ---------------------------------------------------------------------------- protocol client
class ProtocolSession:
    """One dashboard session over Bokeh's websocket protocol, rendering nothing: the server builds
    the page and sends the document and every patch (the streamed rows) exactly as to a browser;
    this client applies them to its own ``bokeh.document.Document`` and sends its own changes and UI
    events (a button click, the page's "document ready") back as PATCH-DOC messages, as BokehJS does.

    It is ``bokeh.client.ClientSession`` on an asyncio loop shared by many sessions, built from the
    same public pieces (``bokeh.protocol``, ``bokeh.util.token``, ``bokeh.client.websocket``): a
    ClientSession runs a blocking IOLoop of its own per session, and the only call that keeps it
    receiving patches after ``pull()`` is its private, test-only ``_loop_until_closed``.

    Rows are most of what a running page receives (four live sources, 10 times a second). Applying
    them to the document is client work only, and the larger part of it, so by default
    (``apply_streams=False``) a patch made only of rows (streamed, or a source's data replaced) is
    received but not applied: the rows of the sources the session follows (:meth:`follow`) are
    decoded and counted, the others skipped. Any other patch (new models, texts) is applied."""

    def __init__(self, url: str, arguments: dict, max_message_size: int = 20 * 1024 * 1024,
                 apply_streams: bool = False):
        from bokeh.client.util import websocket_url_for_server_url
        from bokeh.util.strings import format_url_query_arguments
        self.ws_url = format_url_query_arguments(websocket_url_for_server_url(url),
                                                 {k: str(v) for k, v in arguments.items()})
        self.max_message_size = max_message_size
        self.apply_streams = apply_streams
        self.doc = None
        self._tails: dict = {}  # id of a followed source -> {"rows": n, "last": {column: value}}
        self.closed = False  # the connection ended (by either side)
        self.closing = False  # ... because this client closed it
        self.errors: list = []  # ERROR messages of the server, patches this client could not apply
        self._waiters: list = []
        self._ws = None

    async def open(self, timeout_s: float) -> None:
        """Connect, wait for the server's ACK, pull the document (as ``bokeh.client.pull_session``)."""
        from bokeh.client.websocket import WebSocketClientConnectionWrapper
        from bokeh.document import Document
        from bokeh.protocol import Protocol
        from bokeh.protocol.receiver import Receiver
        from bokeh.util.token import generate_jwt_token, generate_session_id
        from tornado.websocket import websocket_connect
        self.protocol = Protocol()
        self._receiver = Receiver(self.protocol)
        self.id = generate_session_id()
        token = generate_jwt_token(self.id)  # unsigned, as bokeh.client's (amra serve does not sign sessions)
        sock = await asyncio.wait_for(websocket_connect(self.ws_url, subprotocols=["bokeh", token],
                                                        max_message_size=self.max_message_size), timeout_s)
        self._ws = WebSocketClientConnectionWrapper(sock)
        ack = await asyncio.wait_for(self._pop(), timeout_s)
        if ack is None or ack.msgtype != "ACK":
            raise ConnectionError(f"no ACK from the server ({ack.msgtype if ack else 'connection closed'})")
        req = self.protocol.create("PULL-DOC-REQ")
        await req.send(self._ws)
        while True:
            reply = await asyncio.wait_for(self._pop(), timeout_s)
            if reply is None:
                raise ConnectionError("connection closed before the document arrived")
            if reply.header.get("reqid") == req.header["msgid"]:
                break
        if reply.msgtype == "ERROR":
            raise RuntimeError(f"the server refused the document: {reply.content.get('text', '')[:200]}")
        self.doc = Document()
        reply.push_to_document(self.doc)
        self._out: asyncio.Queue = asyncio.Queue()
        self.doc.on_change(self._changed)
        self._tasks = [asyncio.ensure_future(self._read()), asyncio.ensure_future(self._write())]

    # -- the wire
    async def _pop(self):
        """The next whole message from the server (None: the connection closed)."""
        while True:
            fragment = await self._ws.read_message()
            if fragment is None:
                return None
            message = await self._receiver.consume(fragment)
            if message is not None:
                return message

    async def _read(self) -> None:
        try:
            while True:
                msg = await self._pop()
                if msg is None:
                    break
                if msg.msgtype == "PATCH-DOC":
                    try:
                        events = msg.content.get("events") or []
                        if not self.apply_streams and events and all(map(self._rows_only, events)):
                            for e in events:
                                if e["model"]["id"] not in self._tails:
                                    continue
                                if e["kind"] == "ColumnsStreamed":
                                    self._streamed(e["model"]["id"], self._decode(e["data"], msg.buffers))
                                else:  # the data replaced (a decimated window)
                                    new = e["data"] if e["kind"] == "ColumnDataChanged" else e["new"]
                                    self._tails[e["model"]["id"]] = self._tail_of(self._decode(new, msg.buffers))
                        else:
                            msg.apply_to_document(self.doc, self)  # setter: not echoed back (_changed)
                    except Exception as exc:  # noqa: BLE001 - a patch the document cannot take is an error
                        self.errors.append(f"patch not applied: {type(exc).__name__}: {str(exc)[:200]}")
                elif msg.msgtype == "ERROR":
                    self.errors.append(f"server error: {msg.content.get('text', '')[:200]}")
                self._check_waiters()
        except Exception as exc:  # noqa: BLE001
            if not self.closing:
                self.errors.append(f"reading the websocket: {type(exc).__name__}: {str(exc)[:200]}")
        finally:
            self.closed = True
            self._check_waiters()

    async def _write(self) -> None:
        while True:
            msg = await self._out.get()
            await msg.send(self._ws)

    def _changed(self, event) -> None:
        """A change of this client's document: sent to the server unless the server made it."""
        from bokeh.document.events import ColumnsStreamedEvent, DocumentPatchedEvent
        if isinstance(event, DocumentPatchedEvent) and event.setter is not self:
            self._out.put_nowait(self.protocol.create("PATCH-DOC", [event]))
        model = getattr(event, "model", None)
        if model is not None and model.id in self._tails:
            if isinstance(event, ColumnsStreamedEvent):
                self._streamed(model.id, event.data)
            elif getattr(event, "attr", None) == "data":  # replaced (or patched) in the document
                self.follow(model)

    def _rows_only(self, event: dict) -> bool:
        """Is this patch event rows of a data source (streamed, or its data replaced)?"""
        from bokeh.models import ColumnDataSource
        kind = event.get("kind")
        if kind in ("ColumnsStreamed", "ColumnDataChanged"):
            return True
        return (kind == "ModelChanged" and event.get("attr") == "data"
                and isinstance(self.doc.get_model_by_id(event["model"]["id"]), ColumnDataSource))

    @staticmethod
    def _decode(rep, buffers) -> dict:
        from bokeh.core.serialization import Deserializer, Serialized
        return Deserializer().deserialize(Serialized(rep, buffers))

    def _streamed(self, model_id: str, data: dict) -> None:
        tail = self._tails[model_id]
        for column, values in data.items():
            if len(values):
                tail["last"][column] = values[-1]
        tail["rows"] += len(next(iter(data.values()), ()))

    @staticmethod
    def _tail_of(data: dict) -> dict:
        n = len(next(iter(data.values()), ()))
        return {"rows": n, "last": {c: v[-1] for c, v in data.items() if len(v)}}

    def follow(self, source) -> None:
        """Count the rows of ``source`` (a ColumnDataSource) from now on: :meth:`tail`."""
        self._tails[source.id] = self._tail_of(source.data)

    def tail(self, source, column: str):
        """(rows, last value of ``column``) of a followed ``source``, streamed rows included."""
        tail = self._tails[source.id]
        return tail["rows"], tail["last"].get(column)

    # -- what a page does
    def send_event(self, event) -> None:
        """A UI event (``bokeh.events``), e.g. ``ButtonClick(model)``: BokehJS sends it as a
        "MessageSent" document patch (msg_type "bokeh_event"), which ``Document.callbacks.send_event``
        makes, and the server triggers the model's ``on_event`` callbacks with it."""
        self.doc.callbacks.send_event(event)

    def model_with_class(self, css_class: str):
        for m in self.doc.models:
            if css_class in (getattr(m, "css_classes", None) or ()):
                return m
        return None

    def source_with(self, *columns: str):
        """The first ColumnDataSource whose data has all ``columns`` (None if none)."""
        from bokeh.models import ColumnDataSource
        for m in self.doc.models:
            if isinstance(m, ColumnDataSource) and all(c in m.data for c in columns):
                return m
        return None

    def alert_text(self) -> str:
        """The text of a visible danger alert (Panel's Alert pane), '' if none."""
        import html
        import re
        for m in self.doc.models:
            classes = getattr(m, "css_classes", None) or ()
            if "alert-danger" in classes and getattr(m, "visible", True):
                # Panel sends the pane's HTML escaped
                text = re.sub(r"<[^>]*>", " ", html.unescape(getattr(m, "text", "") or "")).strip()
                if text:
                    return text
        return ""

    async def until(self, predicate, timeout_s: float):
        """``time.monotonic()`` when ``predicate()`` first held after a message from the server was
        applied (at once if it holds now); None after ``timeout_s`` or if the connection closed."""
        if predicate():
            return time.monotonic()
        if self.closed:
            return None
        fut = asyncio.get_running_loop().create_future()
        item = (predicate, fut)
        self._waiters.append(item)
        try:
            return await asyncio.wait_for(fut, timeout_s)
        except asyncio.TimeoutError:
            return None
        finally:
            if item in self._waiters:
                self._waiters.remove(item)

    def _check_waiters(self) -> None:
        now = time.monotonic()
        for predicate, fut in list(self._waiters):
            if fut.done():
                continue
            if self.closed:
                fut.set_result(None)
                continue
            try:
                if predicate():
                    fut.set_result(now)
            except Exception as exc:  # noqa: BLE001
                fut.set_exception(exc)

    async def close(self) -> None:
        self.closing = True
        if self._ws is not None:
            self._ws.close(1000, "done")
        for t in getattr(self, "_tasks", []):
            if t is self._tasks[0]:
                try:
                    await asyncio.wait_for(asyncio.shield(t), 5)
                except (asyncio.TimeoutError, Exception):  # noqa: BLE001
                    t.cancel()
            else:
                t.cancel()


class SharedSettled:
    """:class:`Settled` across client processes (a shared counter and event)."""

    def __init__(self, left, event):
        self.left, self.event = left, event

    def arrive(self) -> None:
        with self.left.get_lock():
            self.left.value -= 1
            if self.left.value <= 0:
                self.event.set()

    async def wait(self, timeout_s: float) -> None:
        deadline = time.monotonic() + timeout_s
        while not self.event.is_set() and time.monotonic() < deadline:
            await asyncio.sleep(0.05)


async def protocol_session(url: str, arguments: dict, moves: int, timeout_s: float, start_at: float,
                           gate=None, settled: bool = False) -> dict:
    """One session as :func:`session` drives a browser, over the protocol (:class:`ProtocolSession`):
    open the page, press Run, wait for streamed rows, then (after every session streams, with
    ``settled``) move the GJ slider ``moves`` times, each time waiting for the first row computed
    with the new GJ. ``start_at``: when to connect (epoch s)."""
    from bokeh.events import ButtonClick, DocumentReady
    await asyncio.sleep(max(0.0, start_at - time.time()))
    arrive = arrive_once(gate)
    out = {"latencies_s": [], "moves": [], "run_first_s": None, "load_s": None, "errors": []}
    s = ProtocolSession(url, arguments)
    try:
        t0 = time.monotonic()
        await s.open(timeout_s)
        out["load_s"] = time.monotonic() - t0
        # BokehJS says so once the page is rendered: Panel then runs the page's onload callbacks and
        # sends the plots it defers (defer_load), and holds nothing back any more
        s.send_event(DocumentReady())
        live = {}

        def plots_ready():
            live["src"] = live.get("src") or s.source_with("t_s", "gj_nm2")
            return live["src"] is not None
        if await s.until(plots_ready, timeout_s) is None:
            raise TimeoutError("the live plots did not arrive" + (" (connection closed)" if s.closed else ""))
        out["ready_s"] = time.monotonic() - t0
        src, run, slider = live["src"], s.model_with_class("amra-run"), s.model_with_class("amra-gj-slider")
        s.follow(src)
        if run is None or slider is None:
            raise LookupError(f"no {'Run button' if run is None else 'GJ slider'} in the document")
        text = s.alert_text()  # the page opened with a message (Run clears them)
        if text:
            out["errors"].append(f"alert at load: {text[:200]}")
        t_click = time.monotonic()
        s.send_event(ButtonClick(run))
        first = await s.until(lambda: s.tail(src, "t_s")[0] > 0, timeout_s)
        if first is None:
            out["errors"].append("no streamed row after Run" + (" (connection closed)" if s.closed else ""))
            return out
        out["run_first_s"] = first - t_click
        arrive()
        if settled and gate is not None:
            await gate.wait(timeout_s)
        lo, hi = 10 ** slider.start, 10 ** slider.end
        for k in range(moves):
            await asyncio.sleep(0.8)
            # stiffer each time (about +0.13 decade of GJ, on the slider's step): the run stays stable
            value = min(round((slider.value + 0.13) / slider.step) * slider.step, slider.end)
            gj = min(max(float(f"{10 ** value:.4g}"), lo), hi)  # what app.inputs.gj_slider makes of it
            released, t_set = time.time(), time.monotonic()
            # a release of the handle, as BokehJS reports it: the value, then the throttled value
            # (read-only in Python: set "from JSON", as the server applies a browser's patch)
            slider.value = value
            slider.set_from_json("value_throttled", value)
            def has_gj(gj=gj):
                last = s.tail(src, "gj_nm2")[1]
                return last is not None and abs(last - gj) <= 1e-3 * gj
            seen = await s.until(has_gj, timeout_s)
            if seen is None:
                out["errors"].append(f"move {k}: no row with GJ {gj:g} within {timeout_s:.0f} s"
                                     + (" (connection closed)" if s.closed else ""))
                break
            out["latencies_s"].append(seen - t_set)
            out["moves"].append({"released": released, "seen": released + (seen - t_set), "gj": gj})
        text = s.alert_text()
        if text:
            out["errors"].append(f"alert: {text[:200]}")
    except Exception as exc:  # noqa: BLE001 - a timeout or a lost connection is an error of the session
        out["errors"].append(f"{type(exc).__name__}: {(str(exc).splitlines() or [''])[0][:200]}")
    finally:
        arrive()  # a failed session must not hold the others
        if s.closed and not s.closing:
            out["errors"].append("websocket closed during the session")
        out["errors"] += s.errors
        await s.close()
    return out


def _protocol_worker(k: int, jobs: list, url: str, moves: int, timeout_s: float, settled: bool, cpus: list,
                     nice: int, start, start_at, gate_left, gate_event, results) -> None:
    """A client process: its share of the sessions on one asyncio loop, on ``cpus`` at ``nice``."""
    import traceback
    try:
        if cpus:
            os.sched_setaffinity(0, cpus)
        if nice:
            os.nice(nice)
        import panel.models  # noqa: F401 - Panel's Bokeh models, so the document can be read
        import bokeh.client  # noqa: F401
        results.put(("ready", k, None))
        start.wait()
        gate = SharedSettled(gate_left, gate_event)
        cpu = {}

        async def all_sessions():
            async def mark():  # this process's CPU from the moment every session streams
                while not gate_event.is_set():
                    await asyncio.sleep(0.05)
                cpu["gate"] = (time.process_time(), time.monotonic())
            marker = asyncio.ensure_future(mark())
            out = await asyncio.gather(*[protocol_session(url, args, moves, timeout_s, start_at.value + delay,
                                                          gate, settled) for _, args, delay in jobs])
            marker.cancel()
            return out
        cpu0, t0 = time.process_time(), time.monotonic()
        out = asyncio.run(all_sessions())
        cpu1, t1 = time.process_time(), time.monotonic()
        results.put(("done", k, {"sessions": [(i, r) for (i, _, _), r in zip(jobs, out)],
                                 "cpu_s": cpu1 - cpu0, "wall_s": t1 - t0,
                                 "streaming_cpu_s": cpu1 - cpu["gate"][0] if "gate" in cpu else None,
                                 "streaming_wall_s": t1 - cpu["gate"][1] if "gate" in cpu else None}))
    except BaseException:  # noqa: BLE001 - reported to the parent, which counts the sessions as failed
        results.put(("failed", k, traceback.format_exc()[-2000:]))


def run_level_protocol(n: int, url: str, moves: int, timeout_s: float, server=None, run_s: float = 60.0,
                       stagger_s: float = 0.25, settled: bool = False, client_cpus: str = "",
                       client_procs: int = 0, client_nice: int = 0) -> dict:
    """N protocol sessions (:func:`protocol_session`) from ``client_procs`` processes (0: one per 8
    sessions) on ``client_cpus``; the same figures as :func:`run_level`."""
    import math
    import multiprocessing as mp
    ctx = mp.get_context("spawn")  # a fresh interpreter: no threads or loops of the caller's
    procs = max(1, min(n, client_procs or math.ceil(n / 8)))
    cpus = sorted(_cpu_set(client_cpus)) if client_cpus else []
    base, _, query = url.partition("?")
    extra = dict(urllib.parse.parse_qsl(query))
    # each session starts from its own GJ (see run_level): the log's live changes match its moves
    jobs = [(i, dict(extra, run_s=f"{run_s:g}", gj=f"{1500 + 10 * i:g}"), i * stagger_s) for i in range(n)]
    start, gate_event = ctx.Event(), ctx.Event()
    start_at, gate_left = ctx.Value("d", 0.0), ctx.Value("i", n)
    results = ctx.Queue()
    workers = [ctx.Process(target=_protocol_worker, name=f"amra-load-client-{k}", daemon=True,
                           args=(k, jobs[k::procs], base, moves, timeout_s, settled, cpus, client_nice, start,
                                 start_at, gate_left, gate_event, results)) for k in range(procs)]
    for w in workers:
        w.start()
    import queue as _queue
    done, failed, ready = {}, {}, set()
    deadline = time.monotonic() + 180
    while len(ready) + len(failed) < procs:
        try:
            kind, k, payload = results.get(timeout=1)
        except _queue.Empty:
            if time.monotonic() > deadline or not any(w.is_alive() for w in workers):
                break
            continue
        (ready.add(k) if kind == "ready" else failed.__setitem__(k, payload))
    rss0 = server.rss_mb() if server else None
    main0 = server.main_rss_mb() if server else None
    peak, peak_main = rss0 or 0.0, main0 or 0.0
    streaming = {}
    start_at.value = time.time() + 0.2
    t0 = time.monotonic()
    start.set()
    # the longest a level can take: every step's timeout, the staggered starts, the moves
    limit = t0 + n * stagger_s + timeout_s * (5 + moves) + moves * 1 + 60
    while len(done) + len(failed) < procs:
        if server:
            peak, peak_main = max(peak, server.rss_mb()), max(peak_main, server.main_rss_mb())
        if server and gate_event.is_set() and "cpu0" not in streaming:
            streaming["cpu0"], streaming["t0"] = server.cpu_s(), time.monotonic()
            streaming["main_cpu0"] = server.main_cpu_s()
        try:
            kind, k, payload = results.get(timeout=0.5)
            (done.__setitem__(k, payload) if kind == "done" else failed.__setitem__(k, payload))
        except _queue.Empty:
            lost = [w for w in workers if not w.is_alive() and int(w.name.rsplit("-", 1)[1]) not in done | failed]
            for w in lost:
                failed[int(w.name.rsplit("-", 1)[1])] = f"client process exited with code {w.exitcode}"
            if time.monotonic() > limit:
                for w in workers:
                    k = int(w.name.rsplit("-", 1)[1])
                    if k not in done and k not in failed:
                        failed[k] = "client process did not finish in time"
                break
    if server and "cpu0" in streaming:
        streaming["cpu_s"] = server.cpu_s() - streaming["cpu0"]
        streaming["main_cpu_s"] = server.main_cpu_s() - streaming["main_cpu0"]
        streaming["wall_s"] = time.monotonic() - streaming["t0"]
    wall = time.monotonic() - t0
    rss_open = server.rss_mb() if server else None
    for w in workers:
        w.join(10)
        if w.is_alive():
            w.kill()
    by_index = {}
    for payload in done.values():
        by_index.update(dict(payload["sessions"]))
    for k, why in failed.items():
        for i, _, _ in jobs[k::procs]:
            by_index.setdefault(i, {"latencies_s": [], "moves": [], "run_first_s": None, "load_s": None,
                                    "errors": [f"client process {k}: {why.strip().splitlines()[-1][:200]}"]})
    sessions = [by_index[i] for i in range(n)]
    out = summarize(n, sessions, wall, settled, server, streaming, (rss0, main0, peak, peak_main, rss_open))
    cpu_s = sum(p["cpu_s"] for p in done.values())
    out.update({"client": "protocol", "client_procs": procs, "client_cpus": client_cpus or "all",
                "client_cpu_cores": round(cpu_s / wall, 2),
                "ready_p50_s": _pct([r["ready_s"] for r in sessions if r.get("ready_s") is not None], 0.5)})
    st = [p for p in done.values() if p.get("streaming_wall_s")]
    if st:
        out["client_cpu_streaming_cores"] = round(sum(p["streaming_cpu_s"] for p in st)
                                                  / max(p["streaming_wall_s"] for p in st), 2)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sessions", type=int, nargs="+", default=[1, 8, 16, 32])
    ap.add_argument("--moves", type=int, default=3, help="GJ slider moves per session")
    ap.add_argument("--run-s", type=float, default=120.0, help="simulated run length per session [s]")
    ap.add_argument("--timeout", type=float, default=60.0, help="per-step timeout [s]")
    ap.add_argument("--stagger", type=float, default=0.25, help="delay between session starts [s]")
    ap.add_argument("--url", help="an already running dashboard (.../main); default: start amra serve")
    ap.add_argument("--serve-arg", action="append", default=[], help="extra amra serve argument (repeatable)")
    ap.add_argument("--server-cpus", default="",
                    help="CPUs for the server (taskset list, e.g. 0); the clients get the others")
    ap.add_argument("--client", choices=("browser", "protocol"), default="browser",
                    help="browser: headless Chromium pages (default); protocol: Bokeh's websocket protocol "
                         "without rendering (the server does the same work, a client costs a fraction)")
    ap.add_argument("--client-procs", type=int, default=0,
                    help="protocol client processes (default 0: one per 8 sessions)")
    ap.add_argument("--client-nice", type=int, default=0,
                    help="run the clients at this niceness (e.g. 19: the server's cores go to the server first, "
                         "as if the browsers ran on other machines); default 0, same priority as the server")
    ap.add_argument("--settled", action="store_true",
                    help="start the slider moves once every session streams (steady state); by default each "
                         "session moves as soon as its own run streams, while later sessions still load")
    ap.add_argument("--json", help="write the results here")
    a = ap.parse_args(argv)
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))  # so the server below is stopped too
    results = []
    for n in a.sessions:
        server = None if a.url else Server(args=a.serve_arg, cpus=a.server_cpus)
        try:
            client_cpus = other_cpus(a.server_cpus) if a.server_cpus else ""
            if a.client == "protocol":
                if client_cpus:  # this process too (it samples the server) stays off the server's CPUs
                    os.sched_setaffinity(0, _cpu_set(client_cpus))
                r = run_level_protocol(n, a.url or server.url, a.moves, a.timeout, server, a.run_s, a.stagger,
                                       settled=a.settled, client_cpus=client_cpus, client_procs=a.client_procs,
                                       client_nice=a.client_nice)
            else:
                launch = None
                if a.client_nice or a.server_cpus:
                    exe = wrapped_chromium(a.client_nice, client_cpus)
                    launch = {"executable_path": exe, "args": CHROMIUM_ARGS, "headless": True}
                r = asyncio.run(run_level(n, a.url or server.url, a.moves, a.timeout, server, a.run_s, a.stagger,
                                          launch=launch, settled=a.settled))
            r["client_nice"] = a.client_nice
            r["server_cpus"] = a.server_cpus or "all"
        finally:
            if server:
                server.stop()
        results.append(r)
        print(json.dumps(r), flush=True)
    if a.json:
        Path(a.json).write_text(json.dumps(results, indent=2))
    if a.server_cpus and not a.url:
        cores = len(_cpu_set(a.server_cpus))
        for key in ("server_p95_s", "p95_s"):
            n = capacity(results, key)
            found = f"{n / cores:g} (of the session counts measured)" if n else "none of the counts measured"
            print(f"sessions per server core at {key} <= 0.5 s: {found}", flush=True)
    return 0 if all(r["errors"] == 0 for r in results) else 1


def capacity(results: list, key: str = "server_p95_s", limit_s: float = 0.5):
    """The largest session count measured that, with every smaller one, had no errors and ``key``
    at most ``limit_s`` (None if none)."""
    best = None
    for r in sorted(results, key=lambda r: r["sessions"]):
        if r["errors"] or r.get(key) is None or r[key] > limit_s:
            break
        best = r["sessions"]
    return best


def run_async(coro):
    """``asyncio.run(coro)`` in a thread of its own, so it also works where an event loop is already
    running in the calling thread (a pytest session whose sync Playwright tests left one there)."""
    import threading
    out = {}

    def target():
        try:
            out["value"] = asyncio.run(coro)
        except BaseException as exc:  # noqa: BLE001 - re-raised in the caller's thread
            out["error"] = exc
    t = threading.Thread(target=target, name="amra-load-async")
    t.start()
    t.join()
    if "error" in out:
        raise out["error"]
    return out["value"]


def first_stream_seconds(url: str, launch=None, timeout_s: float = 120.0) -> float:
    """Open ``url`` in headless Chromium, click Run, return seconds to the first streamed point
    (raises if none arrives); used by the image test."""
    async def go():
        from playwright.async_api import async_playwright
        async with async_playwright() as p:
            browser = await p.chromium.launch(**(launch or {"executable_path": CHROMIUM, "args": CHROMIUM_ARGS}))
            r = await session(browser, url, 0, timeout_s, 0, 0.0)
            await r.pop("ctx").close()
            await browser.close()
            return r
    r = run_async(go())
    if r["run_first_s"] is None or r["errors"]:
        raise AssertionError(f"no streaming session: {r['errors']}")
    return r["run_first_s"]


if __name__ == "__main__":
    sys.exit(main())
