"""Every in-range forward-flight condition ends in an answer (issue 8 section 4).

``amra simulate --preset mccutcheon --mu 0.3`` (every mu 0.25..0.5, and ``--airspeed 80``) ended in
``RuntimeError: no trimmed state to start from``. Cause: the forward trim was cold-started from the
axial trim with a shaft tilt of +8 deg and half the axial descent rate, while the trims have a
forward-tilted shaft (about -3 deg at mu 0.3) and 4-7 m/s descent; from mu 0.25 up the Newton
iteration on few-revolution averages wandered off (unconverged at 0.25, a non-finite march at 0.3)
even for the 30x stiffer blade that starts the GJ continuation, so no trim and no branch end existed.
Now the trim is cold-started at mu <= 0.15 and continued up in mu (or airspeed)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from amra_core import equilibrium as trim_mod  # the point solvers of the trim
from amra_core.flight import FlightCondition, SolverSettings
from amra_core.model import Y_OMEGA, compile_model
from amra_core.simulation import COL, Case, Simulation
from amra_core.trim import TrimResult, _solve_at, _with_gj_scale
from amra_core.verdict import VERDICTS
from cli_helpers import run_cli, strict_json


@pytest.mark.parametrize("mu", [0.3, 0.5])
def test_stiff_blade_forward_trim_exists_up_to_mu_0_5(mccutcheon, mu):
    """The first point of the GJ continuation (30x stiffer blade) trims at the requested advance
    ratio (before: non-finite march at 0.3), and the trim is an equilibrium: marched 15 revolutions
    with the rotor speed and descent rate free, they stay where the trim put them."""
    model = _with_gj_scale(compile_model(mccutcheon, FlightCondition(mu=mu), SolverSettings()), 30.0)
    res = _solve_at(model, None, None)
    assert res.ok, res.reason
    assert res.mu == pytest.approx(mu, abs=1e-3)
    print(f"mu {mu}: omega {res.omega_rad_s:.2f} rad/s, descent {res.descent_rate_m_s:.2f} m/s, "
          f"shaft tilt {math.degrees(res.disk_tilt_rad):.2f} deg")
    assert res.disk_tilt_rad < 0  # forward-tilted shaft: why the +8 deg cold start failed
    sim = Simulation(Case(model.rotor, model.flight, model.settings), trim_result=res)
    sim.advance(span_s=15 * 2 * math.pi / res.omega_rad_s)
    h = sim.history
    last = h[h[:, COL["t_s"]] >= h[-1, COL["t_s"]] - 2 * math.pi / res.omega_rad_s]
    assert np.mean(last[:, COL["omega_rad_s"]]) == pytest.approx(res.omega_rad_s, rel=0.005)
    assert np.mean(last[:, COL["descent_rate_m_s"]]) == pytest.approx(res.descent_rate_m_s, abs=0.15)


@pytest.mark.parametrize("args", [("--mu", "0.25"), ("--mu", "0.3"), ("--mu", "0.35"), ("--mu", "0.4"),
                                  ("--mu", "0.45"), ("--mu", "0.5"), ("--airspeed", "80")],
                         ids=lambda a: "".join(a))
def test_cli_forward_flight_always_answers(capsys, args):
    rc, out, err = run_cli(capsys, "simulate", "--preset", "mccutcheon", *args, "--t-end", "3", "--json", "--quiet")
    assert rc == 0, err
    assert "Traceback" not in err
    d = strict_json(out)
    print(args, d["verdict"], "|", d["explanation"], "|", d["start"])
    assert d["verdict"] in VERDICTS and d["verdict"] != "numerical-failure"
    assert d["run_status"] in ("finished", "rotor-stopped", "overspeed-stop")
    assert d["start"] and d["explanation"]
    if d["omega_trim_rad_s"] is None:  # no trim at the requested parameters: the note says where it started
        assert "started from" in d["start"] and "branch" in d["start"]


def test_forward_branch_end_starts_from_the_nearest_trim(mccutcheon, monkeypatch):
    """Where the forward trim branch ends before the requested speed, the run starts from its last
    trimmed point with the requested airspeed switched on, and says so (the path is forced here by
    refusing every trim above mu 0.2)."""
    real = trim_mod._solve_forward_at

    def refuse_fast(model, hold, guess, settle=False):
        if model.flight.mu is not None and model.flight.mu > 0.2:
            return TrimResult("no-autorotation", reason="refused by the test", model=model)
        return real(model, hold, guess, settle)

    monkeypatch.setattr(trim_mod, "_solve_forward_at", refuse_fast)
    model = _with_gj_scale(compile_model(mccutcheon, FlightCondition(mu=0.3), SolverSettings()), 30.0)
    res = trim_mod.trim_forward_continued(model)
    assert res.status == "no-autorotation" and res.state is not None
    be = res.branch_end
    assert be["kind"] == "forward-speed" and 0.15 <= be["mu"] <= 0.2 + 1e-6 and be["requested_mu"] == 0.3
    assert "ends at mu" in res.reason
    sim = Simulation(Case(model.rotor, model.flight, model.settings, t_end_s=1.0), trim_result=res)
    assert "nearest trimmed condition" in sim.start_note and "mu 0.3" in sim.start_note
    from amra_core.model import P_VH
    v_req = 0.3 * be["omega_rad_s"] * mccutcheon.radius_m / math.cos(be["disk_tilt_rad"])
    assert sim.model.arrays.p[P_VH] == pytest.approx(v_req)  # the requested speed acts from t = 0
    assert sim.y[Y_OMEGA] == pytest.approx(be["omega_rad_s"])
    sim.run()
    assert sim.verdict().verdict in VERDICTS


def test_cli_without_any_trim_reports_no_autorotation(capsys, monkeypatch):
    """No trim and no branch end at all: the verdict is the trim's, exit 0, never a traceback."""
    import amra_core.trim as t
    monkeypatch.setattr(t, "trim", lambda model, **kw: TrimResult("no-autorotation", reason="no trim (test)",
                                                                  model=model))
    rc, out, err = run_cli(capsys, "simulate", "--preset", "mccutcheon", "--mu", "0.3", "--json", "--quiet")
    assert rc == 0, err
    d = strict_json(out)
    assert d["verdict"] == "no-autorotation" and d["explanation"] == "no trim (test)"
    assert d["run_status"] == "not-started"
