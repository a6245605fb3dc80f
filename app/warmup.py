"""``panel serve --setup app/warmup.py``: run once per server process before any session.

Compiles (or loads from Numba's cache) the kernels a session uses, trim, a short run at every
fidelity, the stability analysis and the fan plot, so the first user does not wait for the JIT,
and creates the process-wide map registry and analysis process pool.
"""
from __future__ import annotations

import time


def warm() -> float:
    """Warm the solver paths the dashboard uses; returns the time taken [s]."""
    t0 = time.perf_counter()
    from amra_core.flight import FlightCondition, SolverSettings
    from amra_core.model import compile_model
    from amra_core.modes import fan_plot
    from amra_core.rotor_io import load_preset
    from amra_core.simulation import Case, Simulation
    from amra_core.stability import analyse

    rotor = load_preset("paper-boundary")
    for fid in ("rigid", "fem-torsion", "fem-coupled"):
        settings = SolverSettings(fidelity=fid)
        sim = Simulation(Case(rotor, FlightCondition(), settings, t_end_s=0.1))
        sim.advance(span_s=0.05)
        sim.set_parameters(gj_nm2=1400.0)
        sim.advance(span_s=0.05)
        sim.verdict()
        sim.spanwise_last_revolution()
        analyse(compile_model(rotor, FlightCondition(), settings))
    fan_plot(rotor, [0.0, 30.0], fidelity="rigid")
    return time.perf_counter() - t0


if __name__ in ("panel_setup_module", "__main__"):

    import logging  # noqa: E402
    import os  # noqa: E402

    # the app's loggers ("amra.*", e.g. the server-side latency of live changes) at the server's level
    level = {"trace": "DEBUG"}.get(os.environ.get("AMRA_LOG_LEVEL", "info"), os.environ.get("AMRA_LOG_LEVEL", "info"))
    logging.getLogger("amra").setLevel(level.upper())

    from app.analysis import warm_worker  # noqa: E402
    from app.background import get_analysis_pool  # noqa: E402
    from app.map_jobs import get_registry  # noqa: E402
    from app.settings import ServerSettings  # noqa: E402

    get_registry(ServerSettings.from_env())
    get_analysis_pool().submit(warm_worker)  # start and warm the analysis process too
    print(f"AMRA warm-up: kernels ready in {warm():.1f} s", flush=True)
