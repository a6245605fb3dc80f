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


# The local pool's fault cases (a worker killed mid-map: the map completes, identical, nothing failed
# stored; a call that always kills its worker ends as WorkerDied) are tested against the executor
# kept in main by tests/core/test_faults.py and tests/core/test_executor.py.


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
