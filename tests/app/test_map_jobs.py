"""Server-wide map jobs: one job per MapSpec however many sessions ask; stored cells come back at once;
jobs nobody follows are cancelled; the number computing at once is bounded."""
from __future__ import annotations

import time

from amra_core.boundary import MapSpec, run_map
from app.server.map_jobs import MapRegistry, get_registry

SMALL = dict(cg_values=(0.3, 0.45), n_coarse=3, gj_min=100.0, gj_max=2000.0, gj_rel_tol=0.5)


def test_two_sessions_share_one_job_and_the_cells_match_the_core_map(server_settings, wait):
    reg = MapRegistry(server_settings)
    spec = MapSpec(**SMALL)
    a, b = reg.subscribe(spec, "session-a"), reg.subscribe(MapSpec(**SMALL), "session-b")
    assert a is b and reg.jobs_started == 1 and set(a.subscribers) == {"session-a", "session-b"}
    wait(lambda: a.state == "done", 120, what="the map")
    snap = a.snapshot()
    assert snap["n"] == len(snap["cells"]) >= 6 and snap["total"] == snap["n"] and snap["cached"] == 0
    ref = run_map(spec, workers=1)
    got = {(c.cg, c.gj_nm2): c.verdict for c in a.all_cells()}
    assert got == {(c.cg, c.gj_nm2): c.verdict for c in ref.cells}
    # a third session asking later gets the finished job, no recomputation
    assert reg.subscribe(spec, "session-c") is a and reg.jobs_started == 1
    reg.close()


def test_stored_cells_show_at_once_in_a_new_process(server_settings, wait):
    spec = MapSpec(**SMALL)
    first = MapRegistry(server_settings)
    job = first.subscribe(spec, "s")
    wait(lambda: job.state == "done", 120, what="the first map")
    n = job.snapshot()["n"]
    first.close()
    second = MapRegistry(server_settings)  # e.g. another server process: same SQLite store
    t0 = time.perf_counter()
    again = second.subscribe(spec, "s2")
    wait(lambda: again.state == "done", 30, what="the stored map")
    snap = again.snapshot()
    assert snap["n"] == n and snap["cached"] == n
    assert time.perf_counter() - t0 < 5.0
    second.close()


def test_a_job_nobody_follows_is_cancelled_and_a_new_request_restarts_it(server_settings, wait):
    reg = MapRegistry(server_settings)
    spec = MapSpec(cg_values=(0.25, 0.3, 0.35, 0.4, 0.45), n_coarse=6)
    job = reg.subscribe(spec, "s")
    wait(lambda: job.state == "running", 30, what="the job to start")
    reg.unsubscribe(job, "s")
    wait(lambda: job.state == "cancelled", 30, what="the cancellation")
    again = reg.subscribe(spec, "s")
    assert again is not job and reg.jobs_started == 2
    reg.unsubscribe(again, "s")
    reg.close()


def test_the_map_workers_stay_between_jobs_and_a_cancelled_job_leaves_nothing_behind(server_settings, wait):
    """One warmed pool for every job (a new one per map cost 0.6-0.9 s of process start): the warm-up
    columns and a cancelled job's late columns come back from the shared pool, and must not end the
    next job early nor enter its map."""
    reg = MapRegistry(server_settings)
    reg.warm_map_pool()
    pool = reg.map_pool()
    big = reg.subscribe(MapSpec(cg_values=(0.25, 0.3, 0.35, 0.4, 0.45), n_coarse=6), "s")
    wait(lambda: big.state == "running", 30, what="the job to start")
    reg.unsubscribe(big, "s")
    wait(lambda: big.state == "cancelled", 30, what="the cancellation")
    spec = MapSpec(**{**SMALL, "ea": 0.30})
    job = reg.subscribe(spec, "s")
    wait(lambda: job.state == "done", 240, what="the next job")
    assert reg.map_pool() is pool
    ref = run_map(spec, workers=1)
    assert {(c.cg, c.gj_nm2): c.verdict for c in job.all_cells()} == {(c.cg, c.gj_nm2): c.verdict for c in ref.cells}
    reg.close()


def test_only_max_running_jobs_compute_at_once(server_settings, wait):
    reg = MapRegistry(server_settings, max_running=1)
    j1 = reg.subscribe(MapSpec(**SMALL), "s")
    j2 = reg.subscribe(MapSpec(**{**SMALL, "ea": 0.30}), "s")
    wait(lambda: j1.state == "running" or j1.state == "done", 30, what="the first job")
    if j1.state == "running":
        assert j2.state == "queued"
    wait(lambda: j2.state == "done", 240, what="the second job")
    assert j1.state == "done"
    assert set(reg.related(MapSpec(**SMALL))) == {"rigid"}
    cols = j1.columns()  # every finished column with its fold and strong-flutter GJ
    assert [c["cg"] for c in cols] == list(MapSpec(**SMALL).cg_values)
    assert all(c["fold_gj"] is None or 100.0 <= c["fold_gj"] <= 2000.0 for c in cols)
    assert all(c["critical_gj"] == max(g for g in (c["fold_gj"], c["flutter_gj"]) if g is not None)
               for c in cols if c["critical_gj"] is not None)
    reg.close()


def test_the_registry_is_created_once_per_process(server_settings):
    import panel as pn
    a = get_registry(server_settings)
    b = get_registry(server_settings)
    assert a is b and pn.state.cache[("amra-map-registry",)][0] is a  # pn.state.as_cached's entry
