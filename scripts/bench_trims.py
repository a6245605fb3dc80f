"""Cold trims: each fidelity at advance ratios 0, 0.1, 0.3 and 0.5 (McCutcheon preset, its own GJ),
each in a fresh process with the kernels loaded from the on-disk cache, as a user's ``amra trim``
meets it. Reports the trim's own time, the whole process (imports included) and the trim's answer.
A benchmark, not a test (issue 24 asks for every trim under 2 s).

    taskset -c 0 python scripts/bench_trims.py [--json FILE]
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time

_ONE = """
import json, sys, time
t0 = time.perf_counter()
from amra_core.flight import FlightCondition, SolverSettings
from amra_core.model import compile_model
from amra_core.rotor_io import load_preset
from amra_core.trim import trim
fid, mu = sys.argv[1], float(sys.argv[2])
t1 = time.perf_counter()
model = compile_model(load_preset("mccutcheon"), FlightCondition(mu=mu) if mu else FlightCondition(), SolverSettings(fid))
res = trim(model)
t2 = time.perf_counter()
print(json.dumps({"status": res.status, "omega_rad_s": res.omega_rad_s if res.ok else None,
                  "trim_s": round(t2 - t1, 3), "imports_s": round(t1 - t0, 3)}))
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", help="also write the figures to this file")
    args = ap.parse_args()
    subprocess.run([sys.executable, "-c", _ONE, "rigid", "0"], check=True, capture_output=True)  # warm cache
    rows = []
    for fid in ("rigid", "fem-torsion", "fem-coupled"):
        for mu in (0.0, 0.1, 0.3, 0.5):
            t0 = time.perf_counter()
            out = subprocess.run([sys.executable, "-c", _ONE, fid, str(mu)], check=True, capture_output=True, text=True)
            row = {"fidelity": fid, "mu": mu, **json.loads(out.stdout.strip().splitlines()[-1]),
                   "process_s": round(time.perf_counter() - t0, 3)}
            rows.append(row)
            print(f"{fid:12s} mu {mu:<4g} trim {row['trim_s']:6.2f} s  process {row['process_s']:6.2f} s  {row['status']}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
