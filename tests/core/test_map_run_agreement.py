"""Map and run agree (issue 21 §3): a map cell's verdict and a 20 s run of the same case, from the
same start and the default kick, give the same word from one vocabulary.

Cells sampled: rigid and fem-coupled, axial and mu 0.1, a forward CG (0.28) and an aft one (0.44),
EA 0.32, paper-boundary rotor, theodorsen aerodynamics; per column the walk point nearest the
log-centre of every interval, then further walk points spread in log GJ, at least 5 per column and 40
in all. Points within ``EDGE_MARGIN`` of an interval edge are not sampled: there the eigenvalue
(unstable above 1e-3 1/s) and a 20 s run (unstable above 0.02 1/s) legitimately differ.

The run starts where ``amra simulate`` starts: the trim of the cell (the walk's trim, the branch
point ``amra simulate`` reaches by its own continuation), or, with no normal-branch trim at the cell
(fold, windmill-brake root), the end of the branch above it with the cell's parameters switched on
at t = 0 (model-notes §7).
"""
from __future__ import annotations

import math

import pytest

from amra_core.boundary import VERDICTS as MAP_VERDICTS
from amra_core.boundary import cells_of_walk
from amra_core.column import walk_column
from amra_core.equilibrium import TrimResult
from amra_core.flight import FlightCondition, SolverSettings
from amra_core.rotor_io import load_preset
from amra_core.simulation import Case, Simulation
from amra_core.verdict import VERDICTS as RUN_VERDICTS

EA = 0.32
CONFIGS = [(fid, mu, cg) for fid in ("rigid", "fem-coupled") for mu in (0.0, 0.1) for cg in (0.28, 0.44)]
PER_COLUMN = 5
EDGE_MARGIN = 0.03  #: relative GJ distance from an interval edge within which no cell is sampled
T_END_S = 20.0


def _rotor(cg, gj=None):
    r = load_preset("paper-boundary").with_overrides(x_ea=EA, x_cg=cg)
    return r if gj is None else r.with_overrides(gj_nm2=gj)


def _sample(points, intervals, n):
    edges = [iv["gj_lo_nm2"] for iv in intervals[1:]]
    ok = [p for p in points if all(abs(math.log(p.gj_nm2 / e)) > math.log1p(EDGE_MARGIN) for e in edges)]
    chosen = []
    for iv in intervals:
        inside = [p for p in ok if iv["gj_lo_nm2"] < p.gj_nm2 < iv["gj_hi_nm2"]]
        if inside:
            mid = math.sqrt(iv["gj_lo_nm2"] * iv["gj_hi_nm2"])
            chosen.append(min(inside, key=lambda p: abs(math.log(p.gj_nm2 / mid))))
    rest = sorted((p for p in ok if p not in chosen), key=lambda p: p.gj_nm2)
    while len(chosen) < n and rest:  # spread the rest: the point farthest (log GJ) from those chosen
        far = max(rest, key=lambda p: min(abs(math.log(p.gj_nm2 / q.gj_nm2)) for q in chosen) if chosen else 0)
        chosen.append(far)
        rest.remove(far)
    return sorted(chosen, key=lambda p: p.gj_nm2)


def _start(points, p):
    """The trim a run of point ``p`` starts from (module docstring)."""
    if p.branch in ("normal", "overspeed"):
        return p.trim
    above = [q for q in points if q.gj_nm2 > p.gj_nm2 and q.branch in ("normal", "overspeed")]
    if not above:
        return TrimResult("no-autorotation", reason="no normal-branch trim above the cell in the range")
    q = min(above, key=lambda q: q.gj_nm2)
    return TrimResult("no-autorotation", state=q.trim.state, model=q.trim.model,
                      reason="no steady autorotation at the cell: started from the end of the branch above",
                      branch_end={"gj_scale": q.gj_nm2 / p.gj_nm2, "gj_mean_nm2": q.gj_nm2,
                                  "omega_rad_s": q.trim.omega_rad_s})


def agreement_rows(configs=CONFIGS, per_column=PER_COLUMN):
    rows = []
    for fid, mu, cg in configs:
        fl = FlightCondition(mu=mu) if mu > 0 else FlightCondition()
        st = SolverSettings(fidelity=fid)
        w = walk_column(_rotor(cg), fl, st, cg, 30.0, 3000.0)
        cells = {c.gj_nm2: c for c in cells_of_walk(cg, w.points)}
        for p in _sample(w.points, w.intervals, per_column):
            cell = cells[p.gj_nm2]
            if cell.verdict == "failed":
                continue
            sim = Simulation(Case(_rotor(cg, p.gj_nm2), fl, st, t_end_s=T_END_S), trim_result=_start(w.points, p))
            if sim.status != "not-started":
                sim.run()
            v = sim.verdict()
            rows.append({"fidelity": fid, "mu": mu, "cg": cg, "gj": p.gj_nm2, "map": cell.verdict,
                         "map_growth": cell.growth_rate_per_s, "map_hz": cell.frequency_hz, "run": v.verdict,
                         "run_growth": v.growth_rate_per_s, "run_hz": v.frequency_hz, "outcome": v.outcome,
                         "why": v.explanation})
    return rows


def _fmt(x, f):
    return "-" if x is None else format(x, f)


def report(rows) -> str:
    lines = [f"{'fidelity':12s} {'mu':>4s} {'CG':>5s} {'GJ':>8s}  {'map':16s} {'1/s':>7s} {'Hz':>5s}  "
             f"{'run':16s} {'1/s':>7s} {'Hz':>5s}  outcome"]
    for r in rows:
        lines.append(f"{r['fidelity']:12s} {r['mu']:4.2f} {r['cg']:5.2f} {r['gj']:8.1f}  {r['map']:16s} "
                     f"{_fmt(r['map_growth'], '+7.3f')} {_fmt(r['map_hz'], '5.1f')}  {r['run']:16s} "
                     f"{_fmt(r['run_growth'], '+7.3f')} {_fmt(r['run_hz'], '5.1f')}  {r['outcome']}"
                     + ("" if r["map"] == r["run"] else "   <-- DISAGREE: " + r["why"]))
    return "\n".join(lines)


def test_one_vocabulary():
    """Every map verdict but ``failed`` (a crashed worker, no physics) is a run's verdict word."""
    assert set(MAP_VERDICTS) - {"failed"} <= set(RUN_VERDICTS)


@pytest.mark.slow
def test_map_cells_and_runs_agree():
    rows = agreement_rows()
    agree = [r for r in rows if r["map"] == r["run"]]
    print(f"\nmap vs run agreement: {len(agree)} / {len(rows)}\n" + report(rows))
    assert len(rows) >= 40
    assert {(r["fidelity"], r["mu"], r["cg"]) for r in rows} == set(CONFIGS)
    bad = [r for r in rows if r["map"] != r["run"]]
    assert len(agree) >= 0.95 * len(rows), f"{len(agree)} / {len(rows)} agree:\n" + report(bad)


@pytest.mark.parametrize("t_end_s", [10.0, 20.0, 30.0])
def test_a_limit_cycle_is_flutter_whatever_the_run_length(t_end_s):
    """The McCutcheon blade at EA 32 %, CG 31.25 %, GJ 200 N m^2/rad, mu 0.1, rigid: the map's cell
    is flutter (Floquet +1.1 1/s at 6.3 Hz) and a run's kick grows into a limit cycle about 20 times
    its size (twist +/-6.7 deg). Runs of 10 and 30 s said flutter, one of 20 s "stable, decays": the
    cycle ended at 19.6 x, under the 20 x of a saturated one, and its last third's slope, -0.008
    1/s of noise, read as a decay."""
    from amra_core.stability import analyse
    rotor = load_preset("mccutcheon").with_overrides(gj_nm2=200.0, x_ea=0.32, x_cg=0.3125)
    sim = Simulation(Case(rotor, FlightCondition(mu=0.1), SolverSettings("rigid"), t_end_s=t_end_s))
    assert sim.trim.ok
    sim.run()
    v = sim.verdict()
    assert (v.verdict, v.outcome) == ("flutter", "bounded-oscillation"), v.explanation
    assert v.amplitude > 10.0 and abs(v.growth_rate_per_s) < 0.02
    assert v.limit_cycle["twist_deg"] > 5.0
    assert v.frequency_hz == pytest.approx(6.3, abs=0.1)
    if t_end_s == 20.0:  # the map's own analysis of the same trim
        res = analyse(sim.model, sim.trim)
        assert not res.stable and res.critical.real_part_per_s > 0.5
        assert res.critical.frequency_hz == pytest.approx(6.3, abs=0.1)


def test_a_kick_that_grew_and_saturated_is_a_limit_cycle_not_a_runaway():
    """Rigid paper-boundary, EA 32 %, CG 27.5 %, GJ 500, axial: the kick grows into a limit cycle 34 x its size
    (teeter +/-14 deg) by 5 s. A 10 s run said "flutter, growing oscillation, still growing (runaway)": its
    envelope fit over the last two thirds (+0.093 1/s) spans the growth; the last third is flat. A 20 s run said
    bounded oscillation already."""
    rotor = _rotor(0.275, 500.0)
    for t_end_s in (10.0, 20.0):
        sim = Simulation(Case(rotor, FlightCondition(), SolverSettings("rigid"), t_end_s=t_end_s))
        sim.run()
        v = sim.verdict()
        assert (v.verdict, v.outcome) == ("flutter", "bounded-oscillation"), (t_end_s, v.explanation)
        assert v.amplitude > 20.0 and v.limit_cycle["teeter_deg"] > 5.0
