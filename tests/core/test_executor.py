"""Executors: local process pool, in-process serial and dask.distributed behind one interface;
a map is the same whichever runs it."""
from __future__ import annotations

import json
import os

import pytest

from amra_core import cli
from amra_core.boundary import MapSpec, run_map
from amra_core.executor import (DaskExecutor, LocalPoolExecutor, SerialExecutor, WorkerDied, cap_workers,
                                 make_executor, start_method_for_pool, worker_cap)


def _square(x):
    if x == 3:
        raise ZeroDivisionError("three is bad")
    return x * x


def _niceness(_):
    return os.nice(0)


def test_pool_workers_can_run_at_lower_priority():
    """A server's map workers yield the CPU to its runs: ``nice`` is added to the workers' niceness."""
    with LocalPoolExecutor(1, nice=5) as ex:
        (_, out), = list(ex.map_unordered(_niceness, [0]))
    assert out.ok and out.value == min(os.nice(0) + 5, 19)


def _blas_threads(_):
    from threadpoolctl import threadpool_info
    return [(i["filepath"], i["num_threads"]) for i in threadpool_info() if i["user_api"] == "blas"]


def test_pool_workers_run_one_blas_thread_each():
    """A pool already runs a worker per core: OpenBLAS's own threads in every worker would take each
    other's cycles (fem-coupled mu 0.1 map: 72.5 s with them, 47.1 s without). NumPy's and SciPy's
    BLAS are both limited to one thread in the workers."""
    with LocalPoolExecutor(1) as ex:
        (_, out), = list(ex.map_unordered(_blas_threads, [0]))
    assert out.ok
    assert len(out.value) >= 1 and all(n == 1 for _, n in out.value), out.value


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


def test_close_leaves_no_worker_behind():
    """``close()`` of an idle pool waits for its workers to exit, so a program that exits right
    after it leaves nothing running (and its interpreter no pool shutting down)."""
    import multiprocessing as mp
    ex = LocalPoolExecutor(2)
    assert sorted(o.value for _, o in ex.map_unordered(_square, [1, 2, 4])) == [1, 4, 16]
    workers = list(ex._pool._processes.values())
    ex.close()
    assert workers and not any(p.is_alive() for p in workers)
    assert not [p for p in mp.active_children() if p in workers]


def test_pool_survives_a_dead_worker():
    """A call whose worker always dies is retried on fresh pools, then reported as WorkerDied
    (never as an answer); the pool keeps working afterwards."""
    with LocalPoolExecutor(2, max_retries=1) as ex:
        outs = [o for _, o in ex.map_unordered(_die, [0])]
        assert not outs[0].ok and outs[0].worker_died and isinstance(outs[0].value, WorkerDied)
        assert "died on each of 2 tries" in outs[0].reason and ex.restarts == 2
        again = dict(ex.map_unordered(_die, [1, 2, 3]))  # a fresh pool after the crash
        assert all(o.ok and o.value == a for a, o in again.items())


def _die_once(arg):
    """Kill the worker the first time ``arg`` (a marker path, value) is run, then answer."""
    marker, value = arg
    if not os.path.exists(marker):
        open(marker, "w").close()
        os._exit(9)
    return value * 10


def test_a_worker_killed_mid_batch_is_invisible(tmp_path):
    """Every call in flight when a worker dies is resubmitted on a new pool: all answers arrive,
    none is a failure."""
    with LocalPoolExecutor(2) as ex:
        args = [(str(tmp_path / "m"), i) for i in range(8)]
        got = dict((a[1], o) for a, o in ex.map_unordered(_die_once, args))
    assert sorted(got) == list(range(8))
    assert all(o.ok and o.value == 10 * i for i, o in got.items())
    assert ex.restarts >= 1


def test_worker_count_is_capped():
    cap = worker_cap()
    assert cap == 4 * (os.cpu_count() or 1)
    assert cap_workers(cap + 1)[0] == cap and "per CPU core" in cap_workers(cap + 1)[1]
    assert cap_workers(2) == (2, "") and cap_workers(None) == (None, "")
    with pytest.raises(ValueError, match="at most"):
        LocalPoolExecutor(cap + 1)
    with pytest.raises(ValueError, match="workers"):
        LocalPoolExecutor(True)


def test_cli_caps_workers_with_a_message(capsys):
    rc = cli.main(["boundary", "--cg", "0.46:0.46:1", "--coarse", "2", "--tol", "0.5", "--workers", "512",
                   "--quiet", "--json"])
    out, err = capsys.readouterr()
    assert rc == 0 and f"using {worker_cap()}" in err and "per CPU core" in err
    assert json.loads(out)["executor"] == f"local ({worker_cap()} workers)"


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


_IN_A_FRESH_INTERPRETER = """
import json, sys
from amra_core.boundary import MapSpec, run_map
from amra_core.executor import LocalPoolExecutor, start_method_for_pool
method = start_method_for_pool()
with LocalPoolExecutor(2) as ex:
    m = run_map(MapSpec(cg_values=(0.38, 0.46)), executor=ex)
print(json.dumps({"method": method, "critical_gj": m.critical_gj, "cells": [c.to_dict() for c in m.cells]}))
"""


def test_pool_starts_by_fork_only_from_a_single_threaded_parent():
    """Forked workers begin with the parent's imports and kernels (``amra map`` on Linux: a fresh
    interpreter, one thread); a parent with another thread running (a dashboard's, or this test
    process's after the app tests) gets spawned ones, which no lock held by that thread can block.
    The numbers are the same either way."""
    import subprocess
    import sys
    import threading
    out = subprocess.run([sys.executable, "-c", _IN_A_FRESH_INTERPRETER], capture_output=True, text=True,
                         timeout=600, check=True)
    forked = json.loads(out.stdout)
    assert forked["method"] == ("fork" if sys.platform.startswith("linux") else "spawn")
    release = threading.Event()
    other = threading.Thread(target=release.wait)
    other.start()
    try:
        assert start_method_for_pool() == "spawn"
    finally:
        release.set()
        other.join()
    with pytest.raises(ValueError, match="start_method = 'thread'"):
        LocalPoolExecutor(1, start_method="thread")
    with LocalPoolExecutor(2, start_method="spawn") as ex:
        spawned = run_map(SPEC, executor=ex)
    assert [list(x) for x in spawned.critical_gj] == forked["critical_gj"]
    assert [c.to_dict() for c in spawned.cells] == forked["cells"]


def test_a_map_on_a_shared_pool_takes_only_its_own_columns(pool_map):
    """A pool shared by several runs (a server's, or a benchmark's warmed one) also returns what
    others submitted: a foreign result waiting in the pool, and one finishing during the map, must
    neither end the map early nor enter it as a column (they once did: a mu 0.1 map showed two
    columns of the axial map run just before it on the same pool)."""
    from amra_core.boundary import compute_column
    other = MapSpec(mu=0.1, cg_values=(0.46,), gj_min=2500.0)
    with LocalPoolExecutor(2) as ex:
        ex.submit(_square, 2, tag=None)  # a stranger's result, ready before the map starts
        ex.submit(compute_column, other.column_task(0.46), (other, 0.46))  # another map's column
        shared = run_map(SPEC, executor=ex)
        while ex.n_pending:
            ex.wait()
    assert shared.complete
    assert shared.critical_gj == pool_map.critical_gj
    assert [c.to_dict() for c in shared.cells] == [c.to_dict() for c in pool_map.cells]


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


def test_dask_resubmits_a_call_whose_worker_died(tmp_path):
    """With the scheduler allowed no retries of its own, a killed worker gives KilledWorker at once:
    the executor resubmits, and the answer arrives."""
    distributed = pytest.importorskip("distributed")
    import dask
    with dask.config.set({"distributed.scheduler.allowed-failures": 0}):
        with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                      dashboard_address=None) as cluster:
            with DaskExecutor(cluster.scheduler_address) as ex:
                got = dict(ex.map_unordered(_die_once, [(str(tmp_path / "m"), 4)]))
    (a, o), = got.items()
    assert o.ok and o.value == 40


def _certs(folder):
    """A CA and one certificate signed by it (openssl), for a tls:// cluster."""
    import shutil
    import subprocess
    if shutil.which("openssl") is None:
        pytest.skip("openssl is not installed: cannot make TLS certificates")
    ca_key, ca, key, csr, cert = (str(folder / n) for n in ("ca.key", "ca.pem", "k.pem", "c.csr", "c.pem"))
    run = lambda *a: subprocess.run(a, check=True, capture_output=True)  # noqa: E731
    run("openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-keyout", ca_key, "-out", ca, "-days", "2",
        "-subj", "/CN=amra-test-ca")
    run("openssl", "req", "-newkey", "rsa:2048", "-nodes", "-keyout", key, "-out", csr, "-subj", "/CN=localhost")
    ext = folder / "ext.cnf"
    ext.write_text("subjectAltName=DNS:localhost,IP:127.0.0.1\n")
    run("openssl", "x509", "-req", "-in", csr, "-CA", ca, "-CAkey", ca_key, "-CAcreateserial", "-out", cert,
        "-days", "2", "-extfile", str(ext))
    return ca, cert, key


def test_dask_over_tls(tmp_path, monkeypatch, capsys):
    distributed = pytest.importorskip("distributed")
    from distributed.security import Security
    ca, cert, key = _certs(tmp_path)
    sec = Security(tls_ca_file=ca, tls_scheduler_cert=cert, tls_scheduler_key=key, tls_worker_cert=cert,
                   tls_worker_key=key, tls_client_cert=cert, tls_client_key=key, require_encryption=True)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False, protocol="tls://",
                                  security=sec, host="127.0.0.1", dashboard_address=None) as cluster:
        addr = cluster.scheduler_address
        assert addr.startswith("tls://")
        monkeypatch.setenv("AMRA_DASK_TLS_CA", ca)
        monkeypatch.setenv("AMRA_DASK_TLS_CERT", cert)
        monkeypatch.setenv("AMRA_DASK_TLS_KEY", key)
        with DaskExecutor(addr) as ex:
            assert dict(ex.map_unordered(_square, [2]))[2].value == 4
        rc = cli.main(["boundary", "--cg", "0.46:0.46:1", "--coarse", "2", "--tol", "0.5", "--scheduler", addr,
                       "--quiet", "--json"])
        out, err = capsys.readouterr()
        assert rc == 0, err
        assert json.loads(out)["executor"].startswith("dask (tls://")
        # last: a refused client can leave distributed's loop runner for this in-process cluster in a
        # state where the next client of the same cluster fails to start (seen under load)
        for name in ("AMRA_DASK_TLS_CA", "AMRA_DASK_TLS_CERT", "AMRA_DASK_TLS_KEY"):
            monkeypatch.delenv(name)
        with pytest.raises(ValueError, match="cannot connect"):  # no certificates: refused
            DaskExecutor(addr, timeout_s=3)


@pytest.mark.parametrize("addr, why", [("http://host:8786", "must start with"), ("", "scheduler")])
def test_dask_bad_address_is_a_clear_error(addr, why):
    pytest.importorskip("distributed")
    with pytest.raises(ValueError, match=why):
        DaskExecutor(addr)


def test_scheduler_help_warns_about_deserialisation(capsys):
    with pytest.raises(SystemExit):
        cli.main(["boundary", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "deserialises" in text and "trusted cluster" in text and "tls://" in text
    assert "strict JSON" in text
