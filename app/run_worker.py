"""The per-session solver thread: a run is advanced in short chunks, paced for streaming.

The thread owns the :class:`amra_core.simulation.Simulation`. It posts what it produces as
``(kind, payload)`` messages through ``post`` (a thread-safe queue drained on the session's event
loop, see :mod:`app.dashboard`); it never touches the document itself. Kinds:

``status`` {state, text}; ``started`` {run_id, start_note, trim, omega_ref, gj_nm2};
``rows`` {run_id, rows (n, len(HISTORY_COLUMNS)), gj_nm2}; ``applied`` {run_id, values};
``disc`` {run_id, data}; ``verdict`` {run_id, verdict, final}; ``finished`` {run_id, status,
history, stopped}; ``error`` {text}.

Apply live: :meth:`RunWorker.set_live` queues new GJ/EA/CG; the thread calls
``Simulation.set_parameters`` between chunks, and the run continues from its current state.
The kernels are ``nogil``, so a run does not stall the page.
"""
from __future__ import annotations

import threading
import time
from typing import Callable, Optional

import numpy as np

from amra_core.simulation import Case, Simulation

TICK_S = 0.06  #: wall-clock period of a chunk [s]: about 17 chunks per second
MAX_ROWS_PER_CHUNK = 40  #: rows posted per chunk at most (the full history is kept by the Simulation)
STREAM_RATE_HZ = 200.0  #: rows posted per simulated second (>= 7 per period of a 28 Hz torsion mode)
DISC_PERIOD_S = 1.0  #: wall-clock period of the disc and verdict updates during a run [s]


class RunWorker:
    """One session's run thread. ``post(kind, payload)`` must be thread-safe."""

    def __init__(self, post: Callable[[str, dict], None], tick_s: float = TICK_S):
        self._post = post
        self.tick_s = tick_s
        self._lock = threading.Lock()
        self._thread: Optional[threading.Thread] = None
        self._stop = threading.Event()
        self._pending: dict = {}
        self._speed = 1.0
        self.run_id = 0
        self.sim: Optional[Simulation] = None

    # ------------------------------------------------------------------ control (any thread)
    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def start(self, case: Case, speed: float = 1.0) -> int:
        """Start a new run of ``case`` (stopping any current one); returns its run id."""
        self.stop()
        with self._lock:
            self.run_id += 1
            self._pending = {}
            self._speed = float(speed)
            self._stop = threading.Event()
            run_id = self.run_id
        self._thread = threading.Thread(target=self._loop, args=(case, run_id, self._stop),
                                        name=f"amra-run-{run_id}", daemon=True)
        self._thread.start()
        return run_id

    def stop(self, timeout: float = 10.0) -> None:
        """Stop the current run (between chunks) and wait for the thread."""
        self._stop.set()
        t = self._thread
        if t is not None and t is not threading.current_thread():
            t.join(timeout)
        self._thread = None

    def set_live(self, **values) -> None:
        """Queue GJ [N m^2/rad], EA, CG [chord fractions] for the running Simulation."""
        with self._lock:
            self._pending.update({k: v for k, v in values.items() if v is not None})

    def set_speed(self, speed: float) -> None:
        with self._lock:
            self._speed = float(speed)

    # ------------------------------------------------------------------ the thread
    def _take(self):
        with self._lock:
            pend, self._pending = self._pending, {}
            return pend, self._speed

    def _loop(self, case: Case, run_id: int, stop: threading.Event) -> None:
        post = self._post
        post("status", {"run_id": run_id, "state": "trimming", "text": "finding the trimmed autorotation ..."})
        try:
            with np.errstate(all="ignore"):
                sim = Simulation(case)
        except Exception as exc:  # noqa: BLE001 - shown in the page, the session carries on
            post("error", {"run_id": run_id, "text": f"the run could not start: {exc}"})
            post("status", {"run_id": run_id, "state": "idle", "text": "not started"})
            return
        self.sim = sim
        gj = float(np.mean(case.rotor.stations.gj_nm2))
        post("started", {"run_id": run_id, "start_note": sim.start_note, "trim": sim.trim.to_dict(),
                         "omega_ref": sim.omega_ref, "gj_nm2": gj, "t_end_s": case.t_end_s,
                         "first": _decimate(sim.history, MAX_ROWS_PER_CHUNK)})
        post("status", {"run_id": run_id, "state": "running", "text": "running"})
        t_end = case.t_end_s
        next_tick = time.perf_counter()
        last_disc = next_tick
        try:
            while not stop.is_set() and sim.status == "running" and sim.t < t_end - 1e-9:
                pend, speed = self._take()
                if pend:
                    try:
                        sim.set_parameters(**pend)
                        gj = float(np.mean(sim.case.rotor.stations.gj_nm2))
                        post("applied", {"run_id": run_id, "values": pend, "t_s": sim.t})
                    except Exception as exc:  # noqa: BLE001
                        post("error", {"run_id": run_id, "text": f"could not apply {pend} mid-run: {exc}"})
                with np.errstate(all="ignore"):
                    rows = sim.advance(span_s=min(speed * self.tick_s, t_end - sim.t))
                n_keep = min(MAX_ROWS_PER_CHUNK, max(2, int(round(STREAM_RATE_HZ * speed * self.tick_s))))
                post("rows", {"run_id": run_id, "rows": _decimate(rows, n_keep), "gj_nm2": gj,
                              "t_s": sim.t})
                now = time.perf_counter()
                if now - last_disc >= DISC_PERIOD_S:
                    last_disc = now
                    self._post_views(sim, run_id, final=False)
                next_tick += self.tick_s
                delay = next_tick - time.perf_counter()
                if delay > 0:
                    stop.wait(delay)
                else:
                    next_tick = time.perf_counter()  # the solver is behind the playback speed
        except Exception as exc:  # noqa: BLE001
            post("error", {"run_id": run_id, "text": f"the run failed at t = {sim.t:.2f} s: {exc}"})
        self._post_views(sim, run_id, final=True)
        post("finished", {"run_id": run_id, "status": sim.status, "history": sim.history, "stopped": stop.is_set(),
                          "t_s": sim.t})
        post("status", {"run_id": run_id, "state": "idle",
                        "text": f"{'stopped' if stop.is_set() else 'finished'} at t = {sim.t:.2f} s ({_status(sim)})"})

    def _post_views(self, sim: Simulation, run_id: int, final: bool) -> None:
        try:
            with np.errstate(all="ignore"):
                v = sim.verdict()
            self._post("verdict", {"run_id": run_id, "verdict": v, "final": final,
                                   "status": _status(sim) if final else sim.status,
                                   "start_note": sim.start_note})
        except Exception as exc:  # noqa: BLE001 - too short a run to judge
            if final:
                self._post("error", {"run_id": run_id, "text": f"no verdict: {exc}"})
        try:
            disc = sim.spanwise_last_revolution()
            if disc:
                self._post("disc", {"run_id": run_id, "data": disc})
        except Exception:  # noqa: BLE001 - the disc plots are optional
            pass


def _decimate(rows: np.ndarray, n_max: int) -> np.ndarray:
    if len(rows) <= n_max:
        return rows
    idx = np.linspace(0, len(rows) - 1, n_max).round().astype(int)
    return rows[idx]


def _status(sim: Simulation) -> str:
    """The solver status for the page: a run that reached its length is 'completed', not 'running'."""
    return "completed" if sim.status == "running" else sim.status
