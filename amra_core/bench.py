"""``amra bench``: simulated seconds per wall second for each fidelity (one core, after warm-up),
the interpreted (``NUMBA_DISABLE_JIT=1``) ratio on a short run, and the time from a fresh process
(warm on-disk cache) to the first step."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import time

TARGETS_X_REALTIME = {"rigid": 300.0, "fem-torsion": 50.0, "fem-coupled": 10.0}

_FRESH = """
import time, json
t0 = time.perf_counter()
from amra_core.rotor_io import load_preset
from amra_core.flight import FlightCondition, SolverSettings
from amra_core.simulation import Case, Simulation
sim = Simulation(Case(load_preset('mccutcheon'), FlightCondition(), SolverSettings('rigid')))
sim.advance(n_steps=1)
print(json.dumps({"first_step_s": time.perf_counter() - t0}))
"""

_STEPS = """
import time, json, sys
from amra_core.rotor_io import load_preset
from amra_core.flight import FlightCondition, SolverSettings
from amra_core.simulation import Case, Simulation
sim = Simulation(Case(load_preset('mccutcheon'), FlightCondition(), SolverSettings('rigid')))
sim.advance(n_steps=sim.record_every)
n = int(sys.argv[1])
t0 = time.perf_counter(); sim.advance(n_steps=n); w = time.perf_counter() - t0
print(json.dumps({"steps": n, "wall_s": w, "dt_s": sim.dt}))
"""


def _speed(fidelity: str, sim_seconds: float) -> dict:
    from .flight import FlightCondition, SolverSettings
    from .rotor_io import load_preset
    from .simulation import Case, Simulation
    sim = Simulation(Case(load_preset("mccutcheon"), FlightCondition(), SolverSettings(fidelity, n_elements=10)))
    sim.advance(span_s=0.05)  # warm-up (compilation or cache load)
    w0, t0 = sim.wall_time_s, sim.t
    sim.advance(span_s=sim_seconds)
    ratio = (sim.t - t0) / (sim.wall_time_s - w0)
    return {"x_realtime": round(ratio, 1), "dt_s": sim.dt, "structural_coordinates": sim.model.n_s,
            "target_x_realtime": TARGETS_X_REALTIME[fidelity], "meets_target": ratio >= TARGETS_X_REALTIME[fidelity]}


def _subprocess_json(code: str, args=(), env_extra=None) -> dict:
    env = dict(os.environ, **(env_extra or {}))
    out = subprocess.run([sys.executable, "-c", code, *map(str, args)], capture_output=True, text=True,
                         env=env, timeout=600)
    if out.returncode != 0:
        raise RuntimeError(out.stderr.strip().splitlines()[-1] if out.stderr else "benchmark subprocess failed")
    return json.loads(out.stdout.strip().splitlines()[-1])


def run_bench(sim_seconds: float = 5.0) -> dict:
    """All figures as a dict (see module docstring)."""
    rep = {"cpu_count": os.cpu_count(), "fidelities": {}}
    for fid in ("rigid", "fem-torsion", "fem-coupled"):
        rep["fidelities"][fid] = _speed(fid, sim_seconds)
    jit = _subprocess_json(_STEPS, [2000])
    nojit = _subprocess_json(_STEPS, [20], {"NUMBA_DISABLE_JIT": "1"})
    per_jit = jit["wall_s"] / jit["steps"]
    per_py = nojit["wall_s"] / nojit["steps"]
    rep["interpreted_vs_jit"] = {"rigid_step_jit_us": round(per_jit * 1e6, 2),
                                 "rigid_step_interpreted_us": round(per_py * 1e6, 1),
                                 "speedup": round(per_py / per_jit, 1)}
    _subprocess_json(_FRESH)  # make sure the on-disk cache is warm
    t0 = time.perf_counter()
    fresh = _subprocess_json(_FRESH)
    rep["fresh_process"] = {"import_trim_first_step_s": round(fresh["first_step_s"], 3),
                            "process_total_s": round(time.perf_counter() - t0, 3), "target_s": 3.0}
    return rep
