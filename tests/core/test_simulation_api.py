"""The chunked simulation API a dashboard streams from (issue 3): ``advance`` returns only the new
rows, chunks concatenate to exactly one long run, ``set_parameters`` changes the model between
chunks and the run continues from the current state, ``Case.key()`` identifies a run, a
non-finite state ends the run as ``numerical-failure`` without raising, and the CSV round-trips."""
from __future__ import annotations

import math
import os
import re
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from amra_core.flight import FlightCondition, SolverSettings
from amra_core.kernels import HISTORY_COLUMNS
from amra_core.model import N_Y_FIXED, Y_OMEGA
from amra_core.rotor_io import load_preset
from amra_core.simulation import COL, Case, Perturbation, Simulation

REPO = Path(__file__).resolve().parents[2]
T = COL["t_s"]


_TRIMS = {}


def new_sim(rotor, flight=FlightCondition(), **settings) -> Simulation:
    """A fresh Simulation; the trim is computed once per (rotor, flight, settings) and reused."""
    case = Case(rotor, flight, SolverSettings(**settings), t_end_s=10.0)
    key = case.key()
    if key not in _TRIMS:
        sim = Simulation(case)
        _TRIMS[key] = sim.trim
        return sim
    return Simulation(case, trim_result=_TRIMS[key])


def assert_same_run(a: np.ndarray, b: np.ndarray):
    """Histories/states equal: bitwise, except the time column (summed in chunks) to 1e-12."""
    assert a.shape == b.shape
    np.testing.assert_allclose(a[:, T], b[:, T], rtol=0, atol=1e-12)
    cols = [i for i in range(a.shape[1]) if i != T]
    np.testing.assert_array_equal(a[:, cols], b[:, cols])


# ---------------------------------------------------------------------------------------------
# chunks
# ---------------------------------------------------------------------------------------------
CONFIGS = [
    pytest.param(dict(fidelity="rigid"), FlightCondition(), id="rigid-axial"),
    pytest.param(dict(fidelity="fem-coupled"), FlightCondition(), id="fem-coupled-axial"),
    pytest.param(dict(fidelity="rigid", aero="quasi-steady"), FlightCondition(), id="rigid-quasi-steady"),
    pytest.param(dict(fidelity="rigid"), FlightCondition(mu=0.1), id="rigid-mu0.1"),
]


@pytest.mark.parametrize("settings, flight", CONFIGS)
def test_chunks_equal_one_long_run(mccutcheon, settings, flight):
    long = new_sim(mccutcheon, flight, **settings)
    every = long.record_every
    n_rows = int(round(0.72 / long.record_interval_s))  # 0.72 s: long enough for a growth-rate fit
    n_total = n_rows * every
    rows_long = long.advance(n_steps=n_total)
    assert len(rows_long) == n_rows

    chunked = new_sim(mccutcheon, flight, **settings)
    pieces = []
    for n in (1, 7, 32, 100, n_rows - 140):  # uneven chunk sizes, in recording intervals
        new = chunked.advance(n_steps=n * every)
        assert len(new) == n  # only the new rows
        if pieces:  # continuing in time: no repeated or missing row at the boundary
            assert new[0, T] == pytest.approx(pieces[-1][-1, T] + every * chunked.dt, abs=1e-12)
        pieces.append(new)
    assert_same_run(np.concatenate(pieces), rows_long)
    assert_same_run(chunked.history, long.history)
    np.testing.assert_array_equal(chunked.states, long.states)
    np.testing.assert_array_equal(chunked.y, long.y)
    assert chunked.t == pytest.approx(long.t, abs=1e-12)
    # the verdict on the same history is the same (time column aside, which differs by rounding)
    va, vb = chunked.verdict(), long.verdict()
    assert va.verdict == vb.verdict and (va.frequency_hz is None) == (vb.frequency_hz is None)
    assert va.frequency_hz is None or va.frequency_hz == pytest.approx(vb.frequency_hz, rel=1e-9)
    assert va.growth_rate_per_s == pytest.approx(vb.growth_rate_per_s, rel=1e-9)


def test_advance_span_returns_new_rows(mccutcheon):
    sim = new_sim(mccutcheon)
    a = sim.advance(span_s=0.25)
    b = sim.advance(span_s=0.25)
    assert len(a) > 0 and len(b) > 0
    assert a[0, T] == 0.0
    assert sim.t == pytest.approx(0.5, abs=2 * sim.dt * sim.record_every)
    assert b[0, T] > a[-1, T]
    assert len(sim.history) == len(a) + len(b)
    # uniform sampling across the chunk boundary
    dt_rec = np.diff(sim.history[:, T])
    np.testing.assert_allclose(dt_rec, sim.dt * sim.record_every, rtol=1e-9)
    # spans and steps agree: the same interval by n_steps gives the same rows
    other = new_sim(mccutcheon)
    c = other.advance(n_steps=len(a) * other.record_every)
    assert_same_run(c, a)


def test_run_reaches_t_end(mccutcheon):
    sim = new_sim(mccutcheon)
    sim.run(t_end_s=1.2, chunk_s=0.3)
    assert sim.t >= 1.2 - 1e-9 and sim.t < 1.2 + 2 * sim.dt * sim.record_every
    assert np.all(np.diff(sim.history[:, T]) > 0)
    assert sim.status == "finished"  # a finished run says so (issue 8 section 4), ...
    more = sim.advance(span_s=0.1)  # ... and can be continued
    assert len(more) > 0 and sim.status == "running"


# ---------------------------------------------------------------------------------------------
# parameters changed between chunks
# ---------------------------------------------------------------------------------------------
def test_set_parameters_continues_from_current_state(mccutcheon):
    ref = new_sim(mccutcheon)
    sim = new_sim(mccutcheon)
    n = 80 * sim.record_every
    first = sim.advance(n_steps=n)
    ref.advance(n_steps=n)
    y_before = sim.y.copy()
    k0_before = sim.model.arrays.k0.copy()
    key_before = sim.case.key()

    sim.set_parameters(gj_nm2=400.0, x_cg=0.33)

    # the model changed ...
    assert set(sim.case.rotor.stations.gj_nm2) == {400.0}
    assert set(sim.case.rotor.stations.x_cg) == {0.33}
    assert not np.allclose(sim.model.arrays.k0, k0_before)
    assert sim.case.key() != key_before
    # ... the state did not (rigid blade: physical coordinates are the state)
    np.testing.assert_array_equal(sim.y, y_before)
    assert sim.t == ref.t

    # the stable step is recomputed for the new blade, the recording interval is kept
    assert sim.dt * sim.record_every == pytest.approx(ref.dt * ref.record_every, rel=1e-12)
    nxt = sim.advance(span_s=n * ref.dt)
    ref_nxt = ref.advance(n_steps=n)
    assert nxt.shape == ref_nxt.shape
    # continues in time and from where it was (not from trim)
    assert nxt[0, T] == pytest.approx(first[-1, T] + sim.dt * sim.record_every, abs=1e-12)
    for c in ("omega_rad_s", "teeter_rad", "descent_rate_m_s", "inflow_m_s", "azimuth_rad"):
        assert nxt[0, COL[c]] == ref_nxt[0, COL[c]], c
    # and the softer blade twists more from there on
    tw = COL["tip_twist_0_rad"]
    assert np.mean(nxt[-40:, tw]) > np.mean(ref_nxt[-40:, tw]) + 1e-3
    assert not np.allclose(nxt[:, tw], ref_nxt[:, tw])


def test_set_parameters_fem_projects_the_motion(mccutcheon):
    """FEM levels: the state is modal, so changing GJ re-projects the physical motion onto the new
    modes; the tip twist and flap carry over to within the truncation of the modal basis."""
    sim = new_sim(mccutcheon, fidelity="fem-coupled")
    sim.advance(n_steps=40 * sim.record_every)
    x_before, _ = sim.model.physical(sim.y)
    tips_before = sim.model.arrays.tip @ sim.y[sim.model.x_slice()]
    sim.set_parameters(gj_nm2=800.0)
    x_after, _ = sim.model.physical(sim.y)
    tips_after = sim.model.arrays.tip @ sim.y[sim.model.x_slice()]
    assert x_after[0] == pytest.approx(x_before[0], abs=1e-6)  # teeter
    np.testing.assert_allclose(tips_after, tips_before, rtol=0.02, atol=2e-4)
    rows = sim.advance(n_steps=40 * sim.record_every)
    assert np.isfinite(rows).all() and sim.status == "running"


def test_set_parameters_into_no_autorotation(paper):
    """Switching the paper-boundary rotor (GJ 1500, stable) to GJ 100 mid-run (Fig. 10 parameters,
    for which no steady autorotation exists) makes the rotor speed fall: the new model acts."""
    sim = new_sim(paper)
    sim.advance(span_s=0.5)
    om0 = sim.y[Y_OMEGA]
    keep = new_sim(paper)
    keep.advance(span_s=0.5)
    sim.set_parameters(gj_nm2=100.0)
    sim.advance(span_s=4.0)
    keep.advance(span_s=4.0)
    print(f"omega after 4 s: GJ 1500 kept {keep.y[Y_OMEGA]:.2f}, switched to GJ 100 {sim.y[Y_OMEGA]:.2f} rad/s")
    assert keep.y[Y_OMEGA] == pytest.approx(om0, rel=0.01)
    assert sim.y[Y_OMEGA] < 0.95 * om0


# ---------------------------------------------------------------------------------------------
# case keys
# ---------------------------------------------------------------------------------------------
def test_case_key_stable(mccutcheon):
    a = Case(mccutcheon)
    assert a.key() == a.key()
    assert a.key() == Case(load_preset("mccutcheon")).key()  # a fresh load of the same file
    assert re.fullmatch(r"[0-9a-f]{20}", a.key())
    # the provenance text is not part of the physics
    assert Case(replace(mccutcheon, sources=())).key() == a.key()


def test_case_key_stable_across_processes(mccutcheon):
    code = ("from amra_core.simulation import Case; from amra_core.rotor_io import load_preset; "
            "from amra_core.flight import FlightCondition; "
            "print(Case(load_preset('mccutcheon'), FlightCondition(mu=0.1)).key())")
    env = dict(os.environ, PYTHONPATH=str(REPO), PYTHONHASHSEED="123")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == Case(mccutcheon, FlightCondition(mu=0.1)).key()


def _variants(rotor):
    base = Case(rotor)
    yield "gj", replace(base, rotor=rotor.with_overrides(gj_nm2=1000.0))
    yield "ea", replace(base, rotor=rotor.with_overrides(x_ea=0.30))
    yield "cg", replace(base, rotor=rotor.with_overrides(x_cg=0.30))
    yield "one station gj", replace(base, rotor=replace(rotor, stations=replace(
        rotor.stations, gj_nm2=rotor.stations.gj_nm2[:-1] + (1409.5,))))
    yield "incidence", replace(base, rotor=replace(rotor, incidence_rad=rotor.incidence_rad + 1e-4))
    yield "mass", replace(base, rotor=replace(rotor, vehicle_mass_kg=361.0))
    yield "name", replace(base, rotor=replace(rotor, name="other"))
    yield "airspeed", replace(base, flight=FlightCondition(airspeed_m_s=10.0))
    yield "mu", replace(base, flight=FlightCondition(mu=0.1))
    yield "omega hold", replace(base, flight=FlightCondition(omega_hold_rad_s=38.0))
    yield "density", replace(base, flight=FlightCondition(density_kg_m3=1.0))
    yield "fidelity", replace(base, settings=SolverSettings(fidelity="fem-coupled"))
    yield "aero", replace(base, settings=SolverSettings(aero="quasi-steady"))
    yield "elements", replace(base, settings=SolverSettings(n_elements=12))
    yield "stations", replace(base, settings=SolverSettings(n_stations=16))
    yield "dt", replace(base, settings=SolverSettings(dt_s=0.001))
    yield "max mode", replace(base, settings=SolverSettings(max_mode_hz=100.0))
    yield "t_end", replace(base, t_end_s=11.0)
    yield "perturbation", replace(base, perturbation=Perturbation(teeter_rad=0.02))


def test_case_key_differs_for_every_parameter(mccutcheon):
    base = Case(mccutcheon).key()
    keys = {"base": base}
    for name, case in _variants(mccutcheon):
        k = case.key()
        assert k != base, f"changing {name} does not change the key"
        assert k not in keys.values(), f"{name} collides with {[n for n, v in keys.items() if v == k]}"
        keys[name] = k


# ---------------------------------------------------------------------------------------------
# numerical failure
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("slot", ["omega", "structure", "wagner"])
def test_non_finite_state_is_numerical_failure(mccutcheon, slot):
    sim = new_sim(mccutcheon)
    good = sim.advance(n_steps=20 * sim.record_every)
    i = {"omega": Y_OMEGA, "structure": N_Y_FIXED, "wagner": len(sim.y) - 1}[slot]
    sim.y[i] = np.nan if slot != "wagner" else np.inf
    rows = sim.advance(n_steps=20 * sim.record_every)  # must not raise
    assert sim.status == "numerical-failure"
    assert len(rows) >= 1
    v = sim.verdict()
    assert v.verdict == "numerical-failure"
    assert v.growth_rate_per_s is None and v.frequency_hz is None
    assert "non-finite" in v.explanation
    # the run is over: further chunks are empty, and the good part of the history is kept
    assert sim.advance(n_steps=10).shape == (0, len(HISTORY_COLUMNS))
    np.testing.assert_array_equal(sim.history[:len(good)], good)
    # and the results that a UI shows can still be produced
    sim.spanwise_last_revolution()


def test_explicit_step_blow_up_is_not_a_physical_verdict(mccutcheon):
    sim = new_sim(mccutcheon, dt_s=0.01)
    sim.run(t_end_s=2.0)
    print(sim.status, sim.t, sim.y[Y_OMEGA], sim.verdict())
    assert sim.verdict().verdict == "numerical-failure"


# ---------------------------------------------------------------------------------------------
# CSV
# ---------------------------------------------------------------------------------------------
def test_to_csv_round_trip(mccutcheon, tmp_path):
    sim = new_sim(mccutcheon, fidelity="fem-coupled")
    sim.advance(span_s=0.3)
    sim.advance(span_s=0.2)
    path = tmp_path / "history.csv"
    sim.to_csv(path)
    with open(path) as fh:
        lines = fh.read().splitlines()
    meta = [ln for ln in lines if ln.startswith("#")]  # the case and solver version first
    assert lines[:len(meta)] == meta and meta[0].startswith("# AMRA ")
    assert tuple(lines[len(meta)].split(",")) == HISTORY_COLUMNS
    back = np.loadtxt(path, delimiter=",", skiprows=len(meta) + 1, ndmin=2)
    # 8 significant digits (amra_core.export: finer than the integrator's own accuracy, no round-off noise)
    np.testing.assert_allclose(back, sim.history, rtol=5e-8, atol=1e-300)


def test_to_csv_after_failure(mccutcheon, tmp_path):
    """A failed run still writes its history (non-finite values as nan/inf text)."""
    sim = new_sim(mccutcheon)
    sim.advance(n_steps=5 * sim.record_every)
    sim.y[Y_OMEGA] = np.nan
    sim.advance(n_steps=5 * sim.record_every)
    path = tmp_path / "failed.csv"
    sim.to_csv(path)
    n_meta = sum(1 for ln in open(path) if ln.startswith("#"))
    back = np.loadtxt(path, delimiter=",", skiprows=n_meta + 1, ndmin=2)  # past the # lines and the names
    np.testing.assert_array_equal(np.isnan(back), np.isnan(sim.history))
    fin = np.isfinite(back)
    np.testing.assert_allclose(back[fin], sim.history[fin], rtol=5e-8, atol=1e-300)



@pytest.mark.parametrize("fidelity", ["rigid", "fem-coupled"])
def test_the_last_revolution_comes_from_the_tail_and_equals_the_whole_history_answer(fidelity):
    """The disc view asks every second: only the last chunks are joined, with the same answer as
    from the whole run (a mid-run change of the modal basis included)."""
    sim = Simulation(Case(load_preset("mccutcheon"), FlightCondition(), SolverSettings(fidelity=fidelity)))
    for k in range(30):
        sim.advance(span_s=0.06)
        if k == 15:
            sim.set_parameters(gj_nm2=400.0)
    h_tail, s_tail = sim._tail(sim._one_revolution_s())
    assert len(h_tail) < len(sim.history) / 4 and len(h_tail) == len(s_tail)
    fast = sim.spanwise_last_revolution()
    whole = (sim.history, sim.states)
    sim._tail = lambda span_s: whole
    slow = sim.spanwise_last_revolution()
    assert fast.keys() == slow.keys() and len(fast["azimuth_rad"]) == 36
    for key in fast:
        np.testing.assert_allclose(np.array(fast[key]), np.array(slow[key]), rtol=0, atol=0)


def test_a_run_with_no_branch_to_follow_says_where_it_starts_without_nan():
    """Paper-boundary, GJ 10: even the 30x stiffer start (GJ 300) has no normal autorotation, so the
    trim has no branch end. The start note read 'the end of the trim branch (GJ xnan, mean GJ nan
    N m^2/rad, rotor speed nan rad/s)' in the CLI, the card, the toast and the CSV."""
    from amra_core.flight import FlightCondition, SolverSettings
    from amra_core.rotor_io import load_preset
    from amra_core.simulation import Case, Simulation
    sim = Simulation(Case(load_preset("paper-boundary").with_overrides(gj_nm2=10.0), FlightCondition(),
                          SolverSettings("rigid"), t_end_s=0.5))
    note = sim.start_note
    assert "nan" not in note.lower()
    assert note.startswith("no steady autorotation even for a 30x stiffer blade: started from the equilibrium")
    assert "mean GJ 300 N m^2/rad" in note and f"rotor speed {sim.trim.omega_rad_s:.2f} rad/s" in note


def test_a_run_from_the_branch_end_says_at_which_gj_it_starts_in_words():
    """Paper-boundary, GJ 200, CG 40 %: no trim, the run starts from the last trim of the branch
    followed down in GJ. The note said "(GJ x2.07, mean GJ 415 N m^2/rad, ...)", read as a riddle."""
    from amra_core.flight import FlightCondition, SolverSettings
    from amra_core.rotor_io import load_preset
    from amra_core.simulation import Case, Simulation
    sim = Simulation(Case(load_preset("paper-boundary").with_overrides(gj_nm2=200.0, x_ea=0.32, x_cg=0.40),
                          FlightCondition(), SolverSettings("rigid"), t_end_s=0.5))
    be = sim.trim.branch_end
    assert not sim.trim.ok and be["gj_mean_nm2"] > 200.0
    assert (f"started from the last trim of the branch followed down in GJ (at GJ {be['gj_mean_nm2']:.0f} N m^2/rad "
            f"span mean, {be['gj_scale']:.3g} times this blade's; rotor speed {be['omega_rad_s']:.2f} rad/s)") \
        in sim.start_note
    assert "GJ x" not in sim.start_note
