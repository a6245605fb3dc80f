"""Executors: local process pool, in-process serial and dask.distributed behind one interface;
a map is the same whichever runs it."""
from __future__ import annotations

import json
import os

import pytest

from amra_core import cli
from amra_core.boundary import MapSpec, run_map
from amra_core.executor import (DaskExecutor, LocalPoolExecutor, SerialExecutor, make_executor)


def _square(x):
    if x == 3:
        raise ZeroDivisionError("three is bad")
    return x * x


def _die(x):
    if x == 0:
        os._exit(7)  # a worker crash (segfault, out of memory) seen from the pool
    return x


SPEC = MapSpec(cg_values=(0.38, 0.46))


@pytest.fixture(scope="module")
def pool_map():
    with LocalPoolExecutor(2) as ex:
        return run_map(SPEC, executor=ex)


@pytest.mark.parametrize("make", [SerialExecutor, lambda: LocalPoolExecutor(2)])
def test_batch_yields_every_result_and_failures_as_outcomes(make):
    with make() as ex:
        got = dict((a, out) for a, out in ex.map_unordered(_square, range(6)))
    assert sorted(got) == list(range(6))
    assert all(got[a].ok and got[a].value == a * a for a in got if a != 3)
    assert not got[3].ok and got[3].reason == "ZeroDivisionError: three is bad"


def test_pool_survives_a_dead_worker():
    with LocalPoolExecutor(2) as ex:
        outs = [o for _, o in ex.map_unordered(_die, [0])]
        assert not outs[0].ok and "BrokenProcessPool" in outs[0].reason
        again = dict(ex.map_unordered(_die, [1, 2, 3]))  # a fresh pool after the crash
        assert all(o.ok and o.value == a for a, o in again.items())


def test_make_executor_choices():
    assert isinstance(make_executor(workers=1), SerialExecutor)
    ex = make_executor(workers=2)
    assert isinstance(ex, LocalPoolExecutor) and ex.workers == 2
    ex.close()
    ex = make_executor()
    assert ex.workers == os.cpu_count()
    ex.close()
    for bad in (0, -1, 2.5):
        with pytest.raises(ValueError, match="workers"):
            make_executor(workers=bad)


def test_pool_map_equals_serial_map(pool_map):
    serial = run_map(SPEC, workers=1)
    assert pool_map.complete and "local (2 workers)" == pool_map.executor
    assert pool_map.critical_gj == serial.critical_gj
    assert [c.to_dict() for c in pool_map.cells] == [c.to_dict() for c in serial.cells]


def test_dask_local_cluster_gives_the_same_map(pool_map, capsys):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as cluster:
        with DaskExecutor(cluster.scheduler_address) as ex:
            assert ex.workers == 1 and ex.describe().startswith("dask (")
            outs = dict(ex.map_unordered(_square, range(5)))
            assert outs[2].value == 4 and not outs[3].ok and "three is bad" in outs[3].reason
            dmap = run_map(SPEC, executor=ex)
        assert dmap.complete and dmap.executor.startswith("dask")
        assert dmap.critical_gj == pool_map.critical_gj
        assert [c.to_dict() for c in dmap.cells] == [c.to_dict() for c in pool_map.cells]
        # the CLI's --scheduler path
        rc = cli.main(["boundary", "--cg", "0.38:0.46:2", "--scheduler", cluster.scheduler_address, "--json", "--quiet"])
        assert rc == 0
        d = json.loads(capsys.readouterr().out)
        assert d["critical_gj"] == [[cg, g] for cg, g in pool_map.critical_gj]
        assert d["executor"].startswith("dask")


def test_dask_bad_scheduler_is_a_clear_error():
    pytest.importorskip("distributed")
    with pytest.raises(ValueError, match="scheduler"):
        DaskExecutor("tcp://127.0.0.1:9", timeout_s=2)
