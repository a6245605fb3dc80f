"""The session: its run thread streams full-resolution rows, applies live changes without a restart,
stops and starts without waiting on a thread, and hands typed events to their subscribers."""
from __future__ import annotations

import threading

import numpy as np
import pytest

from amra_core.simulation import COL
from app.controls import Controls
from app.events import Applied, Disc, Finished, Rows, RunStatus, VerdictNews
from app.session import Session


class Recorder:
    def __init__(self, session):
        self.events = []
        for kind in (Rows, Applied, Disc, Finished, RunStatus, VerdictNews):
            session.subscribe(kind, self.events.append)

    def of(self, kind):
        return [e for e in self.events if isinstance(e, kind)]


def _case(**kw):
    return Controls(**{"run_s": 2.0, **kw}).case()


def run_until(session, pred, wait, timeout_s=60, what="condition"):
    def step():
        session.delivery.run_due()
        return pred()
    wait(step, timeout_s, what=what)


def test_a_run_streams_every_row_in_chunks_and_finishes(wait):
    s = Session()
    rec = Recorder(s)
    s.start(_case(run_s=1.0), speed=10.0)
    run_until(s, lambda: rec.of(Finished), wait, what="the run to finish")
    t = np.concatenate([e.rows[:, COL["t_s"]] for e in rec.of(Rows)])
    assert np.all(np.diff(t) > 0) and t[-1] == pytest.approx(1.0, abs=0.01)
    fin = rec.of(Finished)[0]
    assert len(t) == len(fin.history)  # full resolution: every recorded row reaches the views
    assert fin.status == "completed" and not fin.stopped
    finals = [v for v in rec.of(VerdictNews) if v.final]
    # 1 s is too short to call a decaying run stable (issue 21 §7): the verdict says so
    assert finals and finals[0].verdict.verdict == "undetermined"
    assert "run too short" in finals[0].verdict.explanation and finals[0].verdict.growth_rate_per_s < 0
    assert rec.of(Disc)[-1].data["r_m"]
    assert not s.running


class BlockedTrim:
    """A run pool whose trims wait until released: a run thread stuck in its trim."""

    def __init__(self):
        self.release = threading.Event()
        self.futures = []

    def submit(self, fn, *args):
        from concurrent.futures import Future
        fut = Future()
        self.futures.append(fut)

        def later():
            self.release.wait(60)
            fut.set_result(fn(*args))
        threading.Thread(target=later, daemon=True).start()
        return fut


def test_stop_start_and_close_never_wait_for_the_run_thread(wait):
    """With the run thread stuck in its trim, Stop, Run and close return (a join would hang here)."""
    pool = BlockedTrim()
    s = Session(run_pool=pool)
    rec = Recorder(s)
    first = s.start(_case(run_s=30.0), speed=1.0)
    wait(lambda: pool.futures, 30, what="the first trim to be submitted")
    s.stop()
    second = s.start(_case(run_s=0.5), speed=10.0)
    assert not pool.futures[0].done() and second == first + 1  # returned while the first trim is stuck
    pool.release.set()
    run_until(s, lambda: [f for f in rec.of(Finished) if f.run_id == second], wait, what="the second run")
    assert {f.run_id for f in rec.of(Finished)} == {second}  # the first run's news was dropped
    third = s.start(_case(run_s=30.0), speed=1.0)
    s.close()
    assert third == second + 1
    wait(lambda: sum(t.name.startswith("amra-run") for t in threading.enumerate()) == 0, 60, what="threads")


def test_a_live_change_continues_the_run_with_the_new_gj(wait):
    s = Session()
    rec = Recorder(s)
    s.start(_case(run_s=4.0), speed=4.0)
    run_until(s, lambda: rec.of(Rows) and rec.of(Rows)[-1].t_s > 0.5, wait, what="0.5 s of run")
    s.set_live(gj_nm2=700.0, x_ea=0.32, x_cg=0.40)
    run_until(s, lambda: any(e.gj_nm2 == 700.0 for e in rec.of(Rows)), wait, what="rows with the new GJ")
    applied = rec.of(Applied)[0]
    assert applied.values["gj_nm2"] == 700.0
    for ev in rec.of(Rows):  # a batch carries the GJ its rows were computed with
        assert (ev.gj_nm2 == 700.0) == (ev.rows[0, COL["t_s"]] > applied.t_s - 1e-9), (ev.gj_nm2, ev.rows[0, 0])
    t = np.concatenate([e.rows[:, COL["t_s"]] for e in rec.of(Rows)])
    assert np.all(np.diff(t) > 0)  # one run, continuing
    assert len(s.live_latencies_s) == 1 and 0 < s.live_latencies_s[0] < 30
    s.stop()


def test_a_run_stopped_before_its_end_says_stopped_not_completed(wait):
    """A 20 s run stopped at a few seconds read "stopped at t = 6.19 s (completed)" and its card's
    solver status "completed"."""
    s = Session()
    rec = Recorder(s)
    s.start(_case(run_s=20.0), speed=1.0)
    run_until(s, lambda: rec.of(Rows) and rec.of(Rows)[-1].t_s > 0.3, wait, what="0.3 s of run")
    s.stop()
    run_until(s, lambda: rec.of(Finished), wait, what="the stopped run to end")
    fin = rec.of(Finished)[0]
    assert fin.stopped and fin.status == "stopped" and fin.t_s < 20.0
    finals = [v for v in rec.of(VerdictNews) if v.final]
    assert finals and finals[-1].status == "stopped"
    line = rec.of(RunStatus)[-1].text
    assert line.startswith("stopped at t = ") and line.endswith(" of 20 s") and "completed" not in line


def test_a_run_that_fails_to_start_says_why(wait):
    from app.events import Notice
    s = Session()
    notes = []
    s.subscribe(Notice, notes.append)
    s.start("not a case")  # type: ignore[arg-type]
    run_until(s, lambda: notes, wait, what="the message")
    assert "could not start" in notes[0].text


def test_the_trim_runs_in_the_run_pool(wait, analysis_pool):
    s = Session(run_pool=analysis_pool)
    rec = Recorder(s)
    s.start(_case(run_s=0.5), speed=10.0)
    run_until(s, lambda: rec.of(Finished), wait, 120, what="the run")
    assert rec.of(Finished)[0].status == "completed" and s.sim is not None


def test_a_stop_during_the_trim_says_so(wait):
    """Stopped while its trim is still computing (a pool whose trim never ends), the run line says it
    stopped; it said "finding the trimmed autorotation ... 1 s" for ever."""
    from concurrent.futures import Future

    from app.session import STOPPED_IN_TRIM

    class EndlessTrim:
        def submit(self, fn, *args):
            return Future()
    s = Session(run_pool=EndlessTrim())
    rec = Recorder(s)
    s.start(_case(), speed=1.0)
    run_until(s, lambda: rec.of(RunStatus), wait, what="the trim's status")
    assert rec.of(RunStatus)[0].text.startswith("finding the trimmed autorotation")
    s.stop()
    run_until(s, lambda: rec.of(RunStatus)[-1].text == STOPPED_IN_TRIM, wait, what="the stopped status")
    assert not rec.of(Finished) and s.sim is None


def test_a_long_run_judges_so_far_less_often_than_every_second():
    """The "so far" verdict reads the whole history: it may take VERDICT_CPU_SHARE of a core, so a
    verdict that took 37 ms (a 120 s run) comes every 1.85 s, a quick one every VIEWS_PERIOD_S."""
    from app.session import VERDICT_CPU_SHARE, VIEWS_PERIOD_S, next_verdict_in_s
    assert next_verdict_in_s(0.001) == VIEWS_PERIOD_S
    assert next_verdict_in_s(0.037) == pytest.approx(0.037 / VERDICT_CPU_SHARE)
    assert next_verdict_in_s(0.037) > VIEWS_PERIOD_S


@pytest.mark.parametrize("verdict_period_s, so_far", [(0.0, "at least 2"), (1000.0, "exactly 1")])
def test_the_run_loop_spaces_its_so_far_verdicts_by_their_cost(wait, monkeypatch, verdict_period_s, so_far):
    """A 3 s run at playback 1x passes the views' 1 s tick at least twice: when next_verdict_in_s
    allows it, each tick judges; when it asks for a long wait, the run judges once (the first tick)
    until its final verdict, while the clock still ticks. (The wait is set here: the real one
    follows the verdict's measured time, and a first verdict in a process can take over 20 ms.)"""
    import app.session as session_module
    costs = []

    def period(cost_s):
        costs.append(cost_s)
        return verdict_period_s
    monkeypatch.setattr(session_module, "next_verdict_in_s", period)
    s = Session()
    rec = Recorder(s)
    s.start(_case(run_s=3.0), speed=1.0)
    run_until(s, lambda: rec.of(Finished), wait, 120, what="the run")
    s.deliver()
    so_far_verdicts = [v for v in rec.of(VerdictNews) if not v.final]
    clock = [r for r in rec.of(RunStatus) if r.text.startswith("running, t =")]
    assert len(clock) >= 2  # the views' tick came at least twice
    assert any(v.final for v in rec.of(VerdictNews))
    assert len(costs) == len(so_far_verdicts) and all(c > 0 for c in costs)  # each verdict timed
    if so_far == "exactly 1":
        assert len(so_far_verdicts) == 1
    else:
        assert len(so_far_verdicts) >= 2


def _blas_threads_and_niceness():
    import os

    from threadpoolctl import threadpool_info
    return [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"], os.nice(0)


def test_the_server_pools_run_one_blas_thread_at_background_priority(analysis_pool):
    """The server's pools run beside the map workers: one BLAS thread each (no OpenBLAS threads
    spinning on every core), at the background niceness."""
    from app.server.pool import BACKGROUND_NICE
    threads, niceness = analysis_pool.submit(_blas_threads_and_niceness).result(timeout=120)
    assert threads and all(n == 1 for n in threads), threads
    assert niceness >= BACKGROUND_NICE


def test_an_empty_batch_of_rows_never_reaches_the_views():
    """A run's first batch is its history so far, which may hold no row; delivered alone (a slow
    machine delivers between two posts) it must not reach a view as a batch without rows."""
    s = Session()
    rec = Recorder(s)
    empty = np.zeros((0, len(COL)))
    s.post(Rows(s.run_id, empty, 900.0, 0.0))
    s.delivery.run_due()
    s.deliver()
    assert rec.of(Rows) == []
    s.post(Rows(s.run_id, empty, 900.0, 0.0))
    s.post(Rows(s.run_id, np.ones((2, len(COL))), 900.0, 0.1))
    s.deliver()
    assert [len(e.rows) for e in rec.of(Rows)] == [2]


def test_fig12_at_playback_10_is_softened_once(wait):
    """Fig. 12 (rigid, mu 0.1, softened to GJ 300 at 2 s) at playback 10x: the chunk that ended on the
    change stopped at 1.9999999999999998 s, so the next chunk applied it again at 2.6 s. The verdict
    then judged from 2.6 s and called the collapsing rotor stable ("rotor speed kept: 14.2 rad/s")."""
    c = Controls(preset="fig12")
    c.run_s = 3.0
    scenario = c.scenario()
    s = Session()
    rec = Recorder(s)
    s.start(scenario.case, 10.0, scenario.changes)
    run_until(s, lambda: rec.of(Finished), wait, what="the run to finish")
    scripted = [e for e in rec.of(Applied) if e.values.get("scripted")]
    assert len(scripted) == 1 and scripted[0].t_s == pytest.approx(2.0, abs=1e-9), [(e.t_s, e.values) for e in scripted]
    assert len(s.sim.changes) == 1
