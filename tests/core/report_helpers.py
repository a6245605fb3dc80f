"""Counts for the issue-10 closing note: property-test outcomes per area and the fault table.

Written as JSON to :func:`report_dir` (``$AMRA_REPORT_DIR``, default ``.pytest_cache/amra-reports``
in the repository): ``properties-<pid>.json`` (area -> outcome -> count) and ``faults.json`` (one
row per fault case). ``python tests/core/report_helpers.py`` prints both as tables.
"""
from __future__ import annotations

import atexit
import json
import os
from collections import Counter, defaultdict
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
OUTCOMES = ("result", "clean error", "traceback", "hang")


def report_dir() -> Path:
    d = Path(os.environ.get("AMRA_REPORT_DIR", REPO / ".pytest_cache" / "amra-reports"))
    d.mkdir(parents=True, exist_ok=True)
    return d


_counts: dict = defaultdict(Counter)


def count(area: str, outcome: str) -> None:
    """Count one generated case of ``area`` ending in ``outcome`` (one of :data:`OUTCOMES`)."""
    _counts[area][outcome] += 1


@atexit.register
def _write_counts() -> None:
    if _counts:
        tag = "bc" if os.environ.get("NUMBA_BOUNDSCHECK") == "1" else "normal"
        path = report_dir() / f"properties-{tag}.json"
        path.write_text(json.dumps({a: dict(c) for a, c in sorted(_counts.items())}, indent=1))


def record_fault(case: str, finished: bool, identical: bool, message: str) -> None:
    path = report_dir() / "faults.json"
    try:
        rows = json.loads(path.read_text())
    except (OSError, ValueError):
        rows = []
    rows = [r for r in rows if r["case"] != case] + [
        {"case": case, "finished": bool(finished), "identical_map": bool(identical), "message": message}]
    path.write_text(json.dumps(rows, indent=1))


def main() -> None:
    d = report_dir()
    for f in sorted(d.glob("properties-*.json")):
        data = json.loads(f.read_text())
        print(f"{f.name}\n{'area':32s} " + " ".join(f"{o:>12s}" for o in OUTCOMES) + f" {'total':>7s}")
        for area, c in data.items():
            print(f"{area:32s} " + " ".join(f"{c.get(o, 0):12d}" for o in OUTCOMES) + f" {sum(c.values()):7d}")
        print(f"{'all':32s} " + " ".join(f"{sum(c.get(o, 0) for c in data.values()):12d}" for o in OUTCOMES)
              + f" {sum(sum(c.values()) for c in data.values()):7d}\n")
    f = d / "faults.json"
    if f.exists():
        for r in json.loads(f.read_text()):
            print(f"| {r['case']} | {'yes' if r['finished'] else 'NO'} | {'yes' if r['identical_map'] else 'NO'} "
                  f"| {r['message']} |")


if __name__ == "__main__":
    main()
