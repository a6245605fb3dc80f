"""Warm the Numba kernels before the first session (``panel serve --setup app/warmup.py``, run
once in every server process, also under ``--num-procs``; and ``python app/warmup.py`` at image
build time, which fills ``NUMBA_CACHE_DIR``).

A short rigid run and a short fem-coupled run load (or, on a cold cache, compile and store) every
kernel a dashboard run uses, so the first user does not wait for compilation. Failures are
reported and swallowed: a server whose warm-up failed still serves, only the first run is slower.
"""
from __future__ import annotations

import sys
import time


def warmup() -> dict:
    """Advance a rigid and a fem-coupled simulation a few steps; ``{fidelity: seconds}``."""
    from amra_core.flight import FlightCondition, SolverSettings
    from amra_core.rotor_io import load_preset
    from amra_core.simulation import Case, Simulation

    rotor = load_preset("mccutcheon")
    timings = {}
    for fidelity, mu in (("rigid", 0.0), ("fem-coupled", 0.1)):
        t0 = time.perf_counter()
        sim = Simulation(Case(rotor, FlightCondition(mu=mu or None),
                              SolverSettings(fidelity=fidelity, n_elements=4)))
        sim.advance(n_steps=1)
        timings[fidelity] = round(time.perf_counter() - t0, 2)
    return timings


def _run() -> None:
    try:
        t = warmup()
        print(f"amra warm-up: Numba kernels ready ({', '.join(f'{k} {v} s' for k, v in t.items())})",
              file=sys.stderr, flush=True)
    except Exception as exc:  # noqa: BLE001 - never stop the server for a failed warm-up
        print(f"amra warm-up failed ({type(exc).__name__}: {exc}); the first run will compile",
              file=sys.stderr, flush=True)


_run()
