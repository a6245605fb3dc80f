"""A sweep worker killed mid-map -- a local pool process or a dask.distributed worker -- and the map
still completes, with exactly the cells and verdicts of an undisturbed run: the dead worker's
calls are run again (``LocalPoolExecutor`` retries them on a fresh pool; Dask reschedules them),
never recorded as failed."""
from __future__ import annotations

import os
import signal
import threading
import time

import pytest

from amra_core.boundary import MapSpec, run_map
from amra_core.executor import LocalPoolExecutor
from amra_core.store import CellStore

pytestmark = pytest.mark.slow

SPEC = MapSpec(fidelity="rigid", cg_values=(0.3, 0.4), n_coarse=4, gj_rel_tol=0.2)


def signature(m):
    return sorted((round(c.cg, 6), round(c.gj_nm2, 6), c.verdict) for c in m.cells)


@pytest.fixture(scope="module")
def reference():
    with LocalPoolExecutor(2) as ex:
        m = run_map(SPEC, executor=ex)
    assert m.verdict_counts()["failed"] == 0 and len(m.cells) >= 8
    return signature(m)


def _kill_after_first_cell(first_cell: threading.Event, pids, killed: list, delay_s=0.3):
    def killer():
        if not first_cell.wait(120):
            return
        time.sleep(delay_s)
        for pid in pids():
            try:
                os.kill(pid, signal.SIGKILL)
                killed.append(pid)
                return
            except ProcessLookupError:
                continue
    t = threading.Thread(target=killer, daemon=True)
    t.start()
    return t


def test_pool_worker_killed_mid_map(reference, tmp_path):
    first, killed = threading.Event(), []
    store = CellStore(tmp_path / "store.sqlite")
    with LocalPoolExecutor(2) as ex:
        t = _kill_after_first_cell(first, lambda: list(ex._pool._processes), killed)
        m = run_map(SPEC, executor=ex, store=store, on_cell=lambda c: first.set())
        t.join(5)
        restarts = ex.restarts
    assert killed, "no worker was killed: the test did not exercise the fault"
    assert restarts >= 1
    assert m.verdict_counts()["failed"] == 0
    assert signature(m) == reference  # nothing lost, nothing changed
    # and nothing wrong stored: every stored cell is a real result
    stored = [store.get(k) for k in store.keys()]
    assert stored and not any(str(d.get("verdict")) == "failed" for d in stored)
    store.close()


def test_pool_call_that_always_kills_its_worker_ends_as_failure():
    with LocalPoolExecutor(1, max_retries=2) as ex:
        ex.submit(os._exit, 3, "suicide")
        ex.submit(abs, -4, "fine")
        outs = []
        deadline = time.monotonic() + 120
        while len(outs) < 2 and time.monotonic() < deadline:
            outs += ex.wait(timeout=1)
    by_tag = {o.tag: o for o in outs}
    assert by_tag["fine"].ok and by_tag["fine"].value == 4
    assert not by_tag["suicide"].ok and "WorkerDied" in by_tag["suicide"].reason and "3 tries" in by_tag["suicide"].reason


def test_dask_worker_killed_mid_map(reference):
    distributed = pytest.importorskip("distributed")
    from amra_core.executor import DaskExecutor
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                  silence_logs=40) as cluster, distributed.Client(cluster) as client:
        pids = list(client.run(os.getpid).values())
        first, killed = threading.Event(), []
        ex = DaskExecutor(client=client)
        t = _kill_after_first_cell(first, lambda: pids, killed)
        m = run_map(SPEC, executor=ex, on_cell=lambda c: first.set())
        t.join(5)
        ex.close()
    assert killed
    assert m.verdict_counts()["failed"] == 0
    assert signature(m) == reference
