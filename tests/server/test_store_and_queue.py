"""The result store on a read-only or a full disk: the server still serves, runs stream, maps
complete, and the page says the results are not kept. The map queue: first come first served,
positions reported, bounded ("busy") instead of stalling.

The disks are real: small tmpfs mounts (needs root, as the image tests do).
"""
from __future__ import annotations

import os
import subprocess
import threading
import time
import warnings

import pytest

from amra_core.boundary import MapSpec, run_map, solver_fingerprint
from amra_core.executor import SerialExecutor
from amra_core.store import CellStore
from app.server.map_jobs import Busy, FairSlots, open_store

SPEC = MapSpec(fidelity="rigid", cg_values=(0.3, 0.4), n_coarse=3, gj_rel_tol=0.3)


@pytest.fixture
def tmpfs(tmp_path):
    """A factory of small tmpfs mounts: ``tmpfs(size_kb, read_only=False) -> Path``."""
    mounts = []

    def make(size_kb=256, read_only=False, prefill=None):
        d = tmp_path / f"mnt{len(mounts)}"
        d.mkdir()
        r = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size_kb}k", "tmpfs", str(d)], capture_output=True,
                           text=True)
        if r.returncode != 0:
            pytest.fail(f"cannot mount a tmpfs (the store fault tests need root): {r.stderr.strip()}")
        mounts.append(d)
        if prefill:
            prefill(d)
        if read_only:
            subprocess.run(["mount", "-o", "remount,ro", str(d)], check=True)
        return d

    yield make
    for d in reversed(mounts):
        subprocess.run(["umount", "-l", str(d)], capture_output=True)


def test_read_only_disk_gives_no_store_and_a_notice(tmpfs):
    ro = tmpfs(read_only=True)
    store, notice = open_store(ro / "amra-store.sqlite", solver_fingerprint())
    assert store is None
    assert "cannot be used" in notice and "not kept" in notice and "read-only" in notice.lower()


def test_existing_store_on_read_only_disk_is_not_destroyed(tmpfs):
    def prefill(d):
        with CellStore(d / "amra-store.sqlite") as s:
            s.put("k1", {"a": 1}, {"verdict": "stable"})
    ro = tmpfs(read_only=True, prefill=prefill)
    before = sorted(os.listdir(ro))
    store, notice = open_store(ro / "amra-store.sqlite")
    # opened read-only (amra_core.store): the stored cells are still served, new ones not kept
    assert store is not None and store.read_only and "read-only" in notice
    assert store.get("k1") == {"verdict": "stable"}
    store.close()
    assert sorted(os.listdir(ro)) == before  # nothing renamed, nothing created


def test_full_disk_map_completes_without_the_store(tmpfs):
    full = tmpfs(size_kb=64)
    store, notice = open_store(full / "amra-store.sqlite")
    assert store is not None and notice == ""
    fd = os.open(full / "filler", os.O_WRONLY | os.O_CREAT)  # fill the disk
    try:
        while True:
            os.write(fd, b"\0" * 4096)
    except OSError:
        pass
    finally:
        os.close(fd)
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        m = run_map(SPEC, executor=SerialExecutor(), store=store)
    assert m.verdict_counts()["failed"] == 0 and len(m.cells) >= 6
    assert any("result store write failed" in str(x.message) for x in w)
    store.close()


def test_fair_slots_first_come_first_served_and_bounded():
    slots = FairSlots(max_running=1, max_queued=2)
    order, started = [], {}
    jobs = ["a", "b", "c"]
    for j in jobs:
        slots.admit(j)
    assert [slots.position(j) for j in jobs] == [0, 1, 2]
    with pytest.raises(Busy, match="2 maps are queued"):
        slots.admit("d")

    def work(j, hold):
        with slots.slot(j) as got:
            assert got
            order.append(j)
            started[j] = time.monotonic()
            hold.wait(5)

    holds = {j: threading.Event() for j in jobs}
    threads = [threading.Thread(target=work, args=(j, holds[j])) for j in reversed(jobs)]  # start in reverse
    for t in threads:
        t.start()
    time.sleep(0.5)
    assert order == ["a"]
    holds["a"].set()
    time.sleep(0.6)
    assert order == ["a", "b"] and slots.position("c") == 1
    holds["b"].set()
    holds["c"].set()
    for t in threads:
        t.join(5)
    assert order == ["a", "b", "c"]
    slots.admit("d")  # room again


def test_cancelled_while_queued_leaves_the_queue():
    slots = FairSlots(max_running=1, max_queued=4)
    slots.admit("run")
    slots.admit("waits")
    cancel = threading.Event()
    result = {}

    def waiter():
        with slots.slot("waits", cancel) as got:
            result["got"] = got
    with slots.slot("run"):
        t = threading.Thread(target=waiter)
        t.start()
        time.sleep(0.3)
        cancel.set()
        t.join(3)
    assert result == {"got": False} and slots.queued == 0
