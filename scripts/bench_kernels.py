"""Where a right-hand side's time goes, per fidelity: one evaluation of ``kernels.rhs`` with air
(full), in vacuum (structure, rotor speed and lag only: no blade stations) and the difference per
blade station; and the real-time factor that four evaluations per RK4 step would allow at the
model's own step. A benchmark, not a test: run it on a quiet core.

    taskset -c 0 python scripts/bench_kernels.py [--json FILE]
"""
from __future__ import annotations

import argparse
import json
import time

import numpy as np
from numba import njit

from amra_core import kernels
from amra_core.flight import FlightCondition, SolverSettings
from amra_core.layout import P_NST, P_VACUUM
from amra_core.rotor_io import load_preset
from amra_core.simulation import Case, Simulation


@njit(cache=False)
def _repeat_rhs(y, m, n):
    dy = np.empty_like(y)
    loads = np.zeros(8)
    work, cw = kernels.new_work(m)
    for _ in range(n):
        y[1] += 1e-9  # a new azimuth each call, so nothing is hoisted out of the loop
        kernels.rhs(y, dy, m, loads, work, cw)
    return dy[0]


def _rhs_us(y, m, n) -> float:
    _repeat_rhs(y.copy(), m, 10)
    best = np.inf
    for _ in range(3):
        t0 = time.perf_counter()
        _repeat_rhs(y.copy(), m, n)
        best = min(best, (time.perf_counter() - t0) / n * 1e6)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", help="also write the figures to this file")
    args = ap.parse_args()
    out = {}
    for fid in ("rigid", "fem-torsion", "fem-coupled"):
        sim = Simulation(Case(load_preset("mccutcheon"), FlightCondition(), SolverSettings(fid, n_elements=10)))
        m = sim.model.arrays
        p_vac = m.p.copy()
        p_vac[P_VACUUM] = 1.0
        full = _rhs_us(sim.y, m, 50_000)
        vacuum = _rhs_us(sim.y, m._replace(p=p_vac), 50_000)
        n_stations = 2 * int(m.p[P_NST])
        out[fid] = {"rhs_us": round(full, 3), "vacuum_rhs_us": round(vacuum, 3),
                    "per_station_ns": round((full - vacuum) / n_stations * 1e3, 1), "stations": n_stations,
                    "dt_s": sim.dt, "x_realtime_if_4_rhs_per_step": round(sim.dt / (4 * full * 1e-6))}
        print(f"{fid:12s} rhs {full:6.3f} us  vacuum {vacuum:6.3f} us  "
              f"{out[fid]['per_station_ns']:5.1f} ns/station ({n_stations})  dt {1e3 * sim.dt:.3f} ms  "
              f"-> {out[fid]['x_realtime_if_4_rhs_per_step']} x real time")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(out, f, indent=1)


if __name__ == "__main__":
    main()
