"""Many users at once: N concurrent headless Chromium sessions against one AMRA server, with the
server pinned to its own CPUs (``--server-cpus``) and the browsers to the others, so what is
measured is the server, not the browsers it would share its cores with.

Each session opens the dashboard (``/main?run_s=...``), starts a run, and once points stream,
moves the GJ slider ``--moves`` times while the run goes on; meanwhile the boundary map of the
session's case fills (every session follows the map of its current case; sessions with the same
case share one map job). Measured, in each page with ``performance.now()``:

* **slider latency**: from the slider's release (``pointerup``) to the first streamed point that
  was computed with the new GJ (the live plot's data carries the GJ of every row);
* run start: from the Run click to the first streamed point;
* errors: page exceptions, console errors, an error alert in the page, a websocket that closed,
  timeouts;
* the server's share of the slider latency: from the change reaching the server to the first rows
  computed with it leaving the server (from the server's log), and the browsers' CPU share, since
  here the browsers run on the server's own cores.

The server (``amra serve``, fresh store per session count) is started by the script unless
``--url`` is given; its memory (RSS of the whole process tree) is sampled before the sessions and
while they run, giving the memory per session, and its CPU time while every session streams,
giving the server CPU per streaming session. ``page_build_s`` is the server's own time to build a
session's page (logged by app/main.py).

Per session count the JSON has ``errors``, ``p50_s``/``p95_s`` (slider release to the first point
with the new GJ on screen), ``server_p50_s``/``server_p95_s`` (the change received by the server to
the first rows computed with it sent), ``page_build_p50_s``/``page_build_p95_s``,
``server_cpu_per_session`` (cores) and ``mb_per_session``.

    python scripts/load_test.py --sessions 1 8 16 32 --server-cpus 0 --settled --json load.json

A benchmark, not a timed test (tests/server/test_load.py runs it at N = 8 and asserts no errors).
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
    """CPU time [s] used so far by ``pid`` and its descendants."""
    total = 0
    for p in _tree(pid):
        try:
            with open(f"/proc/{p}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            total += int(fields[11]) + int(fields[12])
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
        (logged by app.dashboard at info level)."""
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


def other_cpus(server_cpus: str) -> str:
    """The machine's CPUs not in ``server_cpus`` ("0", "0,1", "0-1")."""
    mine = set()
    for part in server_cpus.split(","):
        lo, _, hi = part.partition("-")
        mine.update(range(int(lo), int(hi or lo) + 1))
    rest = sorted(set(os.sched_getaffinity(0)) - mine)
    if not rest:
        raise SystemExit(f"--server-cpus {server_cpus} leaves no CPU for the browsers")
    return ",".join(map(str, rest))


# ---------------------------------------------------------------------------- one session
class Settled:
    """Holds the slider moves until every session streams (or has failed): ``--settled``. Without
    it, the first sessions move their sliders while the later ones still load their pages, and
    each page build holds the server's event loop (app.layout), so those moves measure arrival."""

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


async def session(browser, url: str, moves: int, timeout_s: float, index: int, stagger_s: float,
                  settled: "Settled | None" = None) -> dict:
    await asyncio.sleep(index * stagger_s)
    arrived = False

    def arrive():
        nonlocal arrived
        if settled is not None and not arrived:
            arrived = True
            settled.arrive()
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
        sep = "&" if "?" in url else "?"
        # each session starts from its own GJ (the map, GJ against CG, is the same case for all), so
        # the GJs the slider moves reach are unique to a session and the server's log lines match them
        gate = Settled(n) if settled else None
        marker = asyncio.create_task(mark_streaming())
        results = await asyncio.gather(*[session(browser, f"{url}{sep}run_s={run_s:g}&gj={1500 + 10 * i:g}", moves,
                                                 timeout_s, i, stagger_s, gate) for i in range(n)])
        if server and "cpu0" in streaming:
            streaming["cpu_s"] = server.cpu_s() - streaming["cpu0"]
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
    lat = [x for r in results for x in r["latencies_s"]]
    firsts = [r["run_first_s"] for r in results if r["run_first_s"] is not None]
    loads = [r["load_s"] for r in results if r["load_s"] is not None]
    errors = [e for r in results for e in r["errors"]]
    out = {"sessions": n, "moves": len(lat), "p50_s": _pct(lat, 0.5), "p95_s": _pct(lat, 0.95),
           "max_s": max(lat) if lat else None, "run_first_p50_s": _pct(firsts, 0.5),
           "run_first_p95_s": _pct(firsts, 0.95), "load_p50_s": _pct(loads, 0.5), "load_p95_s": _pct(loads, 0.95),
           "errors": len(errors), "error_samples": errors[:5], "settled": settled,
           "wall_s": round(wall, 1),
           # the browsers' share of this machine (they run beside the server on the same cores)
           "client_cpu_cores": round(client_cpu / wall, 2), "machine_cores": os.cpu_count()}
    if server:
        srv_lat = server.live_latencies_s()
        builds = server.page_builds_s()
        out.update({"server_side_moves": len(srv_lat), "server_p50_s": _pct(srv_lat, 0.5),
                    "server_p95_s": _pct(srv_lat, 0.95), "page_build_p50_s": _pct(builds, 0.5),
                    "page_build_p95_s": _pct(builds, 0.95), "page_build_s": _pct(builds, 0.5)})
        if streaming.get("wall_s"):
            out["server_cpu_per_session"] = round(streaming["cpu_s"] / streaming["wall_s"] / n, 3)
        out.update(split_latencies([m for r in results for m in r["moves"]], server.live_events()))
        out["move_log"] = [dict(m, session=i) for i, r in enumerate(results) for m in r["moves"]]  # epoch s
        out.update({"rss_base_mb": round(rss0, 1), "rss_peak_mb": round(peak[0], 1),
                    "rss_sessions_open_mb": round(rss_open, 1),
                    "server_rss_base_mb": round(main0, 1), "server_rss_peak_mb": round(peak_main[0], 1),
                    "mb_per_session": round((peak_main[0] - main0) / n, 1)})
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
                    help="CPUs for the server (taskset list, e.g. 0); the browsers get the others")
    ap.add_argument("--client-nice", type=int, default=0,
                    help="run the browsers at this niceness (e.g. 19: the server's cores go to the server first, "
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
            launch = None
            if a.client_nice or a.server_cpus:
                exe = wrapped_chromium(a.client_nice, other_cpus(a.server_cpus) if a.server_cpus else "")
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
    return 0 if all(r["errors"] == 0 for r in results) else 1


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
