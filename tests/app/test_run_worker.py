"""The per-session run worker: start, stream, stop, apply-live continuing the run, stop on close."""
from __future__ import annotations

import queue
import threading

import numpy as np
import pytest

from amra_core.simulation import COL
from app.controls import Controls
from app.run_worker import RunWorker


class Inbox:
    def __init__(self):
        self.q = queue.SimpleQueue()
        self.seen = []

    def __call__(self, kind, payload):
        self.q.put((kind, payload))

    def drain(self):
        while True:
            try:
                self.seen.append(self.q.get_nowait())
            except queue.Empty:
                return self.seen

    def kinds(self):
        return [k for k, _ in self.drain()]

    def of(self, kind):
        return [p for k, p in self.drain() if k == kind]


def _case(**kw):
    return Controls(**{"run_s": 2.0, **kw}).case()


def test_run_streams_paced_chunks_and_finishes(wait):
    inbox = Inbox()
    w = RunWorker(inbox, tick_s=0.02)
    w.start(_case(run_s=1.0), speed=10.0)  # 0.2 s of simulated time per 20 ms chunk
    wait(lambda: "finished" in inbox.kinds(), 60, what="the run to finish")
    rows = inbox.of("rows")
    assert len(rows) >= 4  # paced in chunks, not one burst
    t = np.concatenate([p["rows"][:, COL["t_s"]] for p in rows])
    assert np.all(np.diff(t) > 0) and t[-1] == pytest.approx(1.0, abs=0.01)
    assert all(len(p["rows"]) <= 40 for p in rows)  # decimated for the browser: at most 40 rows per chunk
    fin = inbox.of("finished")[0]
    assert fin["status"] == "running" and not fin["stopped"] and fin["history"].shape[1] == len(COL)
    verdicts = [p for p in inbox.of("verdict") if p["final"]]
    # a 1 s run is too short to call stable (issue 21 §7)
    assert verdicts and verdicts[0]["verdict"].verdict == "undetermined"
    assert "run too short" in verdicts[0]["verdict"].explanation
    assert inbox.of("disc") and inbox.of("disc")[-1]["data"]["r_m"]
    assert not w.running


def test_stop_ends_the_run_between_chunks(wait):
    inbox = Inbox()
    w = RunWorker(inbox, tick_s=0.05)
    w.start(_case(run_s=60.0), speed=1.0)
    wait(lambda: "rows" in inbox.kinds(), 60, what="the first rows")
    w.stop(timeout=5.0)
    assert not w.running
    fin = inbox.of("finished")[0]
    assert fin["stopped"] and fin["t_s"] < 30.0
    assert threading.active_count() < 50


def test_apply_live_continues_the_run_with_the_new_gj(wait):
    inbox = Inbox()
    w = RunWorker(inbox, tick_s=0.02)
    w.start(_case(run_s=3.0), speed=5.0)
    wait(lambda: any(p["t_s"] > 0.5 for p in inbox.of("rows")), 60, what="0.5 s of run")
    sim = w.sim
    w.set_live(gj_nm2=600.0, x_ea=0.32, x_cg=0.40)
    wait(lambda: inbox.of("applied"), 30, what="the live change")
    wait(lambda: "finished" in inbox.kinds(), 60, what="the run to finish")
    assert w.sim is sim  # the same Simulation carried on
    applied = inbox.of("applied")[0]
    assert 0.5 <= applied["t_s"] < 3.0
    rows = inbox.of("rows")
    gj = np.array([p["gj_nm2"] for p in rows])
    t_first = np.array([p["rows"][0, COL["t_s"]] for p in rows if len(p["rows"])])
    assert gj[0] == 1500.0 and gj[-1] == 600.0
    assert np.all(np.diff(t_first) > 0)  # time never restarted
    assert set(sim.case.rotor.stations.gj_nm2) == {600.0}
    assert sim.history[-1, COL["t_s"]] == pytest.approx(3.0, abs=0.01)
    assert inbox.of("finished")[0]["history"].shape[0] == len(sim.history)
    # the run's twist responds: softer blade, larger steady nose-up twist
    h = sim.history
    before = h[h[:, COL["t_s"]] < applied["t_s"], COL["tip_twist_0_rad"]][-50:].mean()
    after = h[-50:, COL["tip_twist_0_rad"]].mean()
    assert after > 1.5 * before


def test_a_run_that_fails_numerically_is_reported(wait):
    """dt = 10 ms is a valid setting but outside the rigid blade's explicit step limit (~3 ms)."""
    from dataclasses import replace

    from amra_core.flight import SolverSettings
    inbox = Inbox()
    w = RunWorker(inbox, tick_s=0.02)
    w.start(replace(_case(run_s=5.0), settings=SolverSettings(dt_s=0.01)), speed=50.0)
    wait(lambda: "finished" in inbox.kinds(), 60, what="the run to end")
    assert inbox.of("finished")[0]["status"] == "numerical-failure"
    final = [p for p in inbox.of("verdict") if p["final"]][0]
    assert final["verdict"].verdict == "numerical-failure" and "time step" in final["verdict"].explanation
