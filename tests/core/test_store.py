"""SQLite cell store: round trip, resume of an interrupted map, repeated map at once, several
writers at once, corrupt and foreign files set aside with a message."""
from __future__ import annotations

import multiprocessing as mp
import sqlite3
import threading
import time
import warnings

import pytest

from amra_core.boundary import MapSpec, run_map, solver_fingerprint
from amra_core.stability import CellResult
from amra_core.store import APPLICATION_ID, CellStore, StoreWarning


def _result(i):
    return CellResult(0.4, 100.0 + i, "stable", True, "", -0.5, 12.0, 40.0, f"row {i}")


def test_round_trip_and_wal(tmp_path):
    p = tmp_path / "s.sqlite"
    with CellStore(p, solver="x") as st:
        assert st.get("k") is None and len(st) == 0
        st.put("k", {"cg": 0.4, "gj_nm2": 100.0, "nan": float("nan")}, _result(0))
        st.put("k2", {"cg": 0.4}, _result(1).to_dict())
        assert CellResult.from_dict(st.get("k")) == _result(0)
        assert set(st.get_many(["k", "k2", "nope"])) == {"k", "k2"}
        assert "k" in st and len(st) == 2
    conn = sqlite3.connect(p)
    assert conn.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
    assert conn.execute("PRAGMA application_id").fetchone()[0] == APPLICATION_ID
    conn.close()
    with CellStore(p) as st:  # reopened: still there, no warning
        assert st.notice == "" and len(st) == 2


def _writer(path, wid, n):
    st = CellStore(path, solver="w")
    for i in range(n):
        st.put(f"w{wid}-{i}", {"writer": wid, "i": i}, _result(i))
        st.put("shared", {"writer": wid}, _result(i))  # the same key from every writer too
    st.close()


def test_several_processes_writing_at_once_lose_nothing(tmp_path):
    path = tmp_path / "s.sqlite"
    n_proc, n = 4, 150
    ctx = mp.get_context("spawn")
    procs = [ctx.Process(target=_writer, args=(str(path), w, n)) for w in range(n_proc)]
    for p in procs:
        p.start()
    for p in procs:
        p.join(120)
        assert p.exitcode == 0
    with CellStore(path) as st:
        keys = set(st.keys())
        assert len(st) == n_proc * n + 1
        assert keys == {f"w{w}-{i}" for w in range(n_proc) for i in range(n)} | {"shared"}
        assert all(CellResult.from_dict(st.get(f"w{w}-{n - 1}")).reason == f"row {n - 1}" for w in range(n_proc))


def _set_aside_files(tmp_path, kind):
    return sorted(p.name for p in tmp_path.iterdir() if f".{kind}-" in p.name and not p.name.endswith(("-wal", "-shm")))


@pytest.mark.parametrize("content", [b"this is not a database at all\n" * 50, b"SQLite format 3\x00" + b"\xff" * 4000])
def test_corrupt_file_is_set_aside_with_a_message(tmp_path, content):
    p = tmp_path / "cells.sqlite"
    p.write_bytes(content)
    with pytest.warns(StoreWarning, match=r"set aside as 'cells\.sqlite\.corrupt-") as rec:
        st = CellStore(p)
    assert "not a readable SQLite database" in str(rec[0].message) or "damaged" in str(rec[0].message)
    assert st.notice and "fresh store" in st.notice
    aside = _set_aside_files(tmp_path, "corrupt")
    assert len(aside) == 1 and (tmp_path / aside[0]).read_bytes() == content  # kept untouched
    st.put("k", {}, _result(0))
    assert st.get("k") is not None
    st.close()


def test_foreign_sqlite_file_is_set_aside(tmp_path):
    p = tmp_path / "cells.sqlite"
    conn = sqlite3.connect(p)
    conn.execute("CREATE TABLE invoices (id INTEGER PRIMARY KEY, amount REAL)")
    conn.execute("INSERT INTO invoices VALUES (1, 9.5)")
    conn.commit()
    conn.close()
    with pytest.warns(StoreWarning, match="another program"):
        st = CellStore(p)
    aside = _set_aside_files(tmp_path, "foreign")
    assert len(aside) == 1
    conn = sqlite3.connect(tmp_path / aside[0])
    assert conn.execute("SELECT amount FROM invoices").fetchone()[0] == 9.5  # their data intact
    conn.close()
    assert len(st) == 0
    st.close()


def test_store_of_another_schema_is_set_aside(tmp_path):
    p = tmp_path / "cells.sqlite"
    conn = sqlite3.connect(p)
    conn.execute("CREATE TABLE cells (key TEXT)")
    conn.execute(f"PRAGMA application_id = {APPLICATION_ID}")
    conn.execute("PRAGMA user_version = 99")
    conn.commit()
    conn.close()
    with pytest.warns(StoreWarning, match="schema 99"):
        CellStore(p).close()


def test_new_or_empty_file_gives_no_warning(tmp_path):
    p = tmp_path / "empty.sqlite"
    p.write_bytes(b"")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        CellStore(p).close()
        CellStore(tmp_path / "sub" / "new.sqlite").close()


def test_cli_reports_a_corrupt_store_and_carries_on(tmp_path, capsys):
    from amra_core import cli
    p = tmp_path / "cells.sqlite"
    p.write_text("garbage " * 100)
    rc = cli.main(["boundary", "--cg", "0.46:0.46:1", "--coarse", "3", "--tol", "0.3", "--workers", "1",
                   "--store", str(p), "--quiet", "--json"])
    assert rc == 0
    err = capsys.readouterr().err
    assert "warning" in err and "set aside" in err and ".corrupt-" in err


# ----------------------------------------------------------------------------- maps with a store
SPEC = MapSpec(cg_values=(0.38, 0.44, 0.50))


def test_interrupted_map_resumes_with_only_the_missing_cells(tmp_path):
    path = tmp_path / "cells.sqlite"
    reference = run_map(SPEC, workers=1)
    cancel, got = threading.Event(), []

    def on_cell(c):
        got.append(c)
        if len(got) == 12:
            cancel.set()

    with CellStore(path, solver=solver_fingerprint()) as st:
        part = run_map(SPEC, workers=1, store=st, on_cell=on_cell, cancel=cancel)
        assert part.cancelled and part.cases == 12 and len(st) == 12
    computed = []
    with CellStore(path, solver=solver_fingerprint()) as st:
        resumed = run_map(SPEC, workers=1, store=st, on_cell=computed.append)
        assert len(st) == resumed.cases
    assert resumed.complete
    assert resumed.cached_cases == 12
    assert resumed.computed_cases == reference.cases - 12
    assert resumed.critical_gj == reference.critical_gj
    assert [c.to_dict() for c in resumed.cells] == [c.to_dict() for c in reference.cells]
    assert resumed.boundaries == reference.boundaries


def test_repeated_map_is_served_from_the_store_at_once(tmp_path):
    path = tmp_path / "cells.sqlite"
    first = run_map(SPEC, workers=1, store=path)  # a path is accepted too
    t0 = time.perf_counter()
    again = run_map(SPEC, store=path)  # default executor: a pool that never has to start
    wall = time.perf_counter() - t0
    assert again.cached_cases == again.cases == first.cases and again.computed_cases == 0
    assert wall < 1.0 and again.wall_time_s < 1.0
    assert again.critical_gj == first.critical_gj
    assert [c.to_dict() for c in again.cells] == [c.to_dict() for c in first.cells]


@pytest.mark.slow
def test_full_default_map_repeated_from_store_under_one_second(tmp_path):
    """Issue 4 target: the 16-column map read back from the store in <= 1 s."""
    path = tmp_path / "cells.sqlite"
    first = run_map(MapSpec(), workers=2, store=path)
    t0 = time.perf_counter()
    again = run_map(MapSpec(), workers=2, store=path)
    wall = time.perf_counter() - t0
    print(f"16-column map: {first.cases} cells in {first.wall_time_s:.2f} s; from the store in {wall:.3f} s")
    assert again.cached_cases == again.cases == first.cases
    assert wall < 1.0
    assert again.to_dict()["critical_gj"] == first.to_dict()["critical_gj"]
