"""Branch-true column walks (issue 8 §2, §5): windmill-brake class, continuity, intervals, speed-ups."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from amra_core import cli
from amra_core.column import BranchPoint, ColumnWalk, walk_column
from amra_core.flight import FlightCondition, SolverSettings
from amra_core.model import compile_model
from amra_core.stability import analyse
from amra_core.trim import (WINDMILL_BRAKE_RATIO, _hover_induced, _trim_axial_from, on_branch, trim,
                            trim_axial, windmill_brake_state)

EA = 0.32


def _model(paper, cg, gj, fidelity="rigid", flight=FlightCondition()):
    return compile_model(paper.with_overrides(x_ea=EA, x_cg=cg, gj_nm2=gj), flight, SolverSettings(fidelity=fidelity))


@pytest.fixture(scope="module")
def walk_036(paper):
    """Rigid axial column CG 0.36 (EA 0.32), GJ 30-3000, 2 %."""
    seen = []
    w = walk_column(paper.with_overrides(x_ea=EA), FlightCondition(), SolverSettings(), 0.36, 30.0, 3000.0,
                    on_point=seen.append)
    return w, seen


# ----------------------------------------------------------------------------- the reproducer
def test_windmill_state_is_classified_windmill_brake(paper):
    """Issue 8 reproducer: at CG 0.36, GJ 150 (rigid) the root with descent 25.6 m/s (4.5 v_h; 24.9 m/s,
    4.4 v_h with the static pitch terms of the physics change) is the windmill-brake equilibrium."""
    m = _model(paper, 0.36, 150.0)
    wb = windmill_brake_state(m)
    assert wb is not None and wb.ok
    vh = _hover_induced(m)
    assert wb.branch == "windmill-brake"
    assert wb.descent_rate_m_s == pytest.approx(24.9, abs=0.3)  # 25.6 before the static pitch terms
    assert wb.descent_rate_m_s / vh > WINDMILL_BRAKE_RATIO and wb.descent_ratio > 4.0
    assert wb.to_dict()["branch"] == "windmill-brake"
    # the normal autorotation of a stiff blade is on the normal branch, near 1.9 v_h
    stiff = trim(_model(paper, 0.36, 3000.0))
    assert stiff.ok and stiff.branch == "normal" and 1.7 < stiff.descent_ratio < 2.0


def test_trim_by_continuation_reports_the_fold_not_the_windmill_root(paper):
    """The continuation from the stiff blade stays on the normal branch: it reports the fold (issue:
    near GJ 285; 269 with the static pitch terms) and names the windmill state."""
    res = trim(_model(paper, 0.36, 150.0))
    assert res.status == "no-autorotation" and res.branch == "none"
    be = res.branch_end
    assert be["gj_mean_nm2"] == pytest.approx(269.0, rel=0.03)  # the walk brackets the fold to 2 %
    assert be["descent_rate_m_s"] < WINDMILL_BRAKE_RATIO * _hover_induced(res.model)  # the branch end is normal
    assert be["windmill_brake_descent_rate_m_s"] == pytest.approx(24.9, abs=0.3)
    assert "windmill-brake" in res.reason


def test_cli_trim_says_which_branch(capsys):
    argv = ["trim", "--preset", "paper-boundary", "--fidelity", "rigid", "--ea", "0.32", "--cg", "0.36",
            "--gj", "150", "--json"]
    assert cli.main(argv) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["status"] == "no-autorotation" and d["branch"] == "none"
    assert cli.main(argv[:-3] + ["--gj", "1500", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["status"] == "trimmed" and d["branch"] == "normal" and d["descent_ratio"] < 2.0


# ----------------------------------------------------------------------------- continuity
def test_on_branch_rejects_a_jump_to_the_windmill_root(paper):
    prev = trim(_model(paper, 0.36, 300.0))
    assert prev.ok and prev.branch == "normal"
    near = _trim_axial_from(_model(paper, 0.36, 294.0), prev.state, None)
    assert near.ok and on_branch(near, prev)
    wb = windmill_brake_state(_model(paper, 0.36, 150.0))  # the windmill root, 2.3x the normal descent
    assert wb is not None and not on_branch(wb, prev)


def test_walk_stays_on_its_branch(walk_036):
    w, seen = walk_036
    assert isinstance(w, ColumnWalk) and all(isinstance(p, BranchPoint) for p in w.points)
    assert [p.gj_nm2 for p in w.points] == sorted(p.gj_nm2 for p in w.points)
    assert len(seen) == len(w.points) and seen[0].gj_nm2 == 3000.0  # on_point in walk order, from the top
    top = [p for p in w.points if p.branch == "normal" and p.gj_nm2 >= w.fold_gj_nm2]
    assert top and all(p.trim.descent_ratio < WINDMILL_BRAKE_RATIO for p in top)
    for a, b in zip(top[:-1], top[1:]):  # continuity of rotor speed, descent rate, inflow, twist
        assert abs(b.trim.omega_rad_s - a.trim.omega_rad_s) < 0.06 * a.trim.omega_rad_s
        assert abs(b.trim.descent_rate_m_s - a.trim.descent_rate_m_s) < 1.0
        assert abs(b.trim.inflow_m_s - a.trim.inflow_m_s) < 1.0
        assert abs(b.trim.tip_twist_rad - a.trim.tip_twist_rad) < 0.03
    for p in w.points:
        if p.branch == "normal":
            assert p.modes and p.max_real_part_per_s == max(m.real_part_per_s for m in p.modes)
        if p.branch == "windmill-brake":
            assert not p.stable and p.kind == "windmill-brake"
    # the old flawed map called GJ 68-280 stable here: below the fold nothing is stable
    assert not any(p.stable for p in w.points if p.gj_nm2 < w.fold_gj_nm2)
    assert w.fold_gj_nm2 == pytest.approx(269.0, rel=0.03)


def test_every_interval_is_reported(walk_036):
    """Rigid CG 0.36: stable from the stiff blade down to just above the fold, flutter at the fold,
    then no normal trim and windmill-brake states; the intervals tile the range. (Before the static
    pitch terms this column also had a flutter window ~372-428 inside the stable range; the
    fem-coupled CG 0.32 window is checked below.)"""
    w, _ = walk_036
    kinds = [iv["kind"] for iv in w.intervals]
    print([(iv["kind"], round(iv["gj_lo_nm2"]), round(iv["gj_hi_nm2"])) for iv in w.intervals])
    assert kinds[-1] == "stable" and "windmill-brake" in kinds and "fold" in kinds and "flutter" in kinds
    iv = w.intervals
    assert iv[0]["gj_lo_nm2"] == 30.0 and iv[-1]["gj_hi_nm2"] == 3000.0
    assert all(a["gj_hi_nm2"] == b["gj_lo_nm2"] for a, b in zip(iv[:-1], iv[1:]))
    assert all(x["resolved"] for x in iv if x["kind"] in ("stable", "flutter"))
    # every stability change on the branch bracketed to 2 %
    pts = [p for p in w.points if p.branch == "normal"]
    changes = 0
    for a, b in zip(pts[:-1], pts[1:]):
        if a.stable != b.stable:
            changes += 1
            assert b.gj_nm2 / a.gj_nm2 <= 1.02 * (1 + 1e-9)
    assert changes >= 1
    assert w.critical_gj_nm2 == pytest.approx(iv[-1]["gj_lo_nm2"], rel=0.011)


def test_a_narrow_unstable_window_is_found_and_bracketed(paper, monkeypatch):
    """The issue's example (fem-coupled CG 0.32 unstable for GJ ~370-400 only) was found by the walk
    before the physics merge (365-399, see docs/validation-summary.md); with the static pitch terms
    that column is stable from 250 to 1000, so the walk's window finding is tested here on real
    trims with the exponents of a 7.5 % wide window (GJ 800-860) raised to +1 1/s: the old 7-point
    grid (cells at 646 and 1393) could not see it."""
    import amra_core.column as column
    from dataclasses import replace as _r
    real = column.analyse

    class _Res:
        def __init__(self, modes, stable):
            self.modes, self.stable = modes, stable

    def windowed(model, tr, *a, **k):
        res = real(model, tr, *a, **k)
        gj = float(model.rotor.stations.gj_nm2[0])
        if 800.0 <= gj <= 860.0:
            top = max(res.modes, key=lambda m: m.real_part_per_s)
            return _Res([_r(m, real_part_per_s=1.0) if m is top else m for m in res.modes], False)
        return res

    monkeypatch.setattr(column, "analyse", windowed)
    w = walk_column(paper.with_overrides(x_ea=EA), FlightCondition(), SolverSettings(), 0.44, 500.0, 3000.0)
    print([(iv["kind"], round(iv["gj_lo_nm2"]), round(iv["gj_hi_nm2"])) for iv in w.intervals])
    win = [iv for iv in w.intervals if iv["kind"] == "flutter" and iv["gj_lo_nm2"] > 700.0]
    assert len(win) == 1 and win[0]["resolved"]
    assert win[0]["gj_lo_nm2"] == pytest.approx(800.0, rel=0.02) and win[0]["gj_hi_nm2"] == pytest.approx(860.0, rel=0.02)
    i = w.intervals.index(win[0])
    assert w.intervals[i - 1]["kind"] == "stable" and w.intervals[i + 1]["kind"] == "stable"
    assert w.critical_gj_nm2 == pytest.approx(860.0, rel=0.021)


# ----------------------------------------------------------------------------- speed-ups keep the answers
def test_jitted_newton_matches_scipy_hybr(paper, monkeypatch):
    import amra_core.equilibrium as T
    m = _model(paper, 0.40, 800.0)
    fast = trim_axial(m)
    monkeypatch.setattr(T, "_newton_axial", lambda *a: None)  # force the scipy path
    slow = trim_axial(m)
    assert fast.ok and slow.ok
    for k in ("omega_rad_s", "descent_rate_m_s", "inflow_m_s", "tip_twist_rad"):
        assert getattr(fast, k) == pytest.approx(getattr(slow, k), rel=1e-7, abs=1e-9)


def test_one_sided_monodromy_matches_central(paper):
    """Forward flight (rigid, mu 0.1, CG 0.36, GJ 1000): the Floquet exponents of the least damped
    modes by one-sided differences agree with central differences.

    The issue measured 2e-5 1/s, and that held until the twist's in-plane momentum was coupled to
    the lag pivot as well (commit d6a952e, a term of third order in the small quantities). Since
    then the one-sided exponents differ by up to 1.6e-4 1/s at the relative step 3e-6, and no step
    does better than 5.5e-5 (measured 2026-12-01: 1e-5 -> 5.5e-4, 3e-6 -> 3.5e-4 / 1.6e-4,
    1e-6 -> 1.6e-4 / 5.5e-5, 3e-7 -> 7.2e-4 1/s for all six / the four least damped): truncation
    above 3e-6, round-off below. The bound is therefore 2e-4 1/s, against real parts of -5 to 0 1/s,
    and the stability decision must agree."""
    m = _model(paper, 0.36, 1000.0, flight=FlightCondition(mu=0.1))
    tr = trim(m)
    assert tr.ok
    fwd = analyse(m, tr, "forward")
    cen = analyse(m, tr, "central")

    def least_damped(r):
        return np.array(sorted(md.real_part_per_s for md in r.modes if md.label != "aero lag")[-6:])
    d = np.abs(least_damped(fwd) - least_damped(cen))
    print(f"differences of the 6 least damped exponents: {d} 1/s")
    assert np.max(d[-4:]) < 2e-4  # the modes that decide stability (real parts above -5 1/s here)
    assert np.max(d) < 5e-4  # better damped ones (-10 to -18 1/s): within 5e-5 relative
    assert fwd.stable == cen.stable


@pytest.mark.parametrize("fidelity, cg, gj", [("rigid", 0.36, 1000.0), ("rigid", 0.30, 300.0),
                                               ("fem-coupled", 0.36, 1000.0), ("fem-coupled", 0.38, 786.0)])
def test_krylov_floquet_matches_the_full_monodromy(paper, fidelity, cg, gj):
    """The map's Floquet analysis (Arnoldi on the monodromy, ``stability.floquet_krylov``) against
    the full matrix of one-sided differences and against central differences (mu 0.1; stable
    cases, a fluttering one at rigid CG 0.30, and a real negative multiplier at fem-coupled CG 0.38).

    The resolved multipliers equal the full matrix's largest to 1e-4 (both are differences of the
    same marches, along other directions); the least damped four exponents agree with central
    differences within the bound the one-sided full matrix is held to (2e-4 1/s, measured here up
    to 1.0e-4) or 5e-5 relative, the stability decision agrees, and it costs at most 60 % of the
    full matrix's revolutions (measured 47-48 % rigid, 48-51 % fem-coupled). Deterministic: a second
    analysis gives the same numbers bit for bit."""
    from amra_core.model import Y_OMEGA, stable_time_step
    from amra_core.stability import floquet_krylov, monodromy
    m = _model(paper, cg, gj, fidelity, flight=FlightCondition(mu=0.1))
    tr = trim(m)
    assert tr.ok
    y0 = tr.state
    dt = stable_time_step(tr.model, 1.3 * y0[Y_OMEGA])
    import scipy.linalg as sla
    z, _, _, revs, n_res, converged = floquet_krylov(tr.model, y0, dt)
    full, left, right = sla.eig(monodromy(tr.model, y0, dt)[0], left=True, right=True)
    assert converged and n_res >= 12
    for zk in z[:n_res]:
        i = np.argmin(np.abs(full - zk))
        # first-order perturbation: two difference matrices of the same marches differ by about 1e-5
        # (relative, along other directions), and an eigenvalue moves by that times its condition
        # number; the damped pairs of fem-coupled CG 0.36 (|z| 0.21-0.28) have 110-170, and one of
        # them (|z| 0.209, kappa 119) moved 2.3e-4 on an AVX-512 machine, both from the forward and
        # from the central full matrix (which agree with each other to 1e-6 there)
        kappa = np.linalg.norm(left[:, i]) * np.linalg.norm(right[:, i]) / abs(left[:, i].conj() @ right[:, i])
        assert abs(full[i] - zk) < max(1e-4, 1e-5 * kappa) * max(1.0, abs(zk)), (zk, full[i], kappa)
    assert revs <= 0.6 * len(y0)

    kry, cen = analyse(m, tr, "krylov"), analyse(m, tr, "central")

    def least_damped(r):
        return np.array(sorted(md.real_part_per_s for md in r.modes if md.label != "aero lag")[-4:])
    a, b = least_damped(kry), least_damped(cen)
    print(f"{fidelity} CG {cg} GJ {gj}: {revs} revolutions (full {len(y0)}); least damped {a} vs central {b}")
    # an exponent s = log(z) / T moves by dz / (|z| T): for an ill-conditioned multiplier, by the bound
    # above (fem-coupled CG 0.36: -6.5325 against -6.5331 1/s, |z| 0.22, kappa ~120)
    T = 2 * np.pi / y0[Y_OMEGA]
    for ak, bk in zip(a, b):
        zb = np.exp(bk * T)
        i = np.argmin(np.abs(np.abs(full) - zb))
        kappa = np.linalg.norm(left[:, i]) * np.linalg.norm(right[:, i]) / abs(left[:, i].conj() @ right[:, i])
        assert abs(ak - bk) <= max(2e-4, 5e-5 * abs(bk), 1e-5 * kappa / T), (ak, bk, kappa)
    assert kry.stable == cen.stable
    again = analyse(m, tr, "krylov")
    assert [md.real_part_per_s for md in again.modes] == [md.real_part_per_s for md in kry.modes]


def test_krylov_that_does_not_resolve_its_modes_falls_back_to_the_full_matrix(paper, monkeypatch):
    """Arnoldi capped at 8 vectors cannot resolve 20 multipliers: the analysis then forms the full
    matrix and reports every mode, as the one-sided scheme does."""
    import amra_core.floquet as floquet
    m = _model(paper, 0.36, 1000.0, flight=FlightCondition(mu=0.1))
    tr = trim(m)
    monkeypatch.setattr(floquet, "KRYLOV_MAX_DIM", 8)
    from amra_core.model import Y_OMEGA, stable_time_step
    *_, converged = floquet.floquet_krylov(tr.model, tr.state, stable_time_step(tr.model, 1.3 * tr.state[Y_OMEGA]))
    assert not converged
    capped, full = analyse(m, tr, "krylov"), analyse(m, tr, "forward")
    assert [md.real_part_per_s for md in capped.modes] == [md.real_part_per_s for md in full.modes]


def test_axial_least_damped_modes_are_the_full_analysis_ones(paper):
    """In axial flight the walk's analysis (``"krylov"``) keeps the least damped 20 eigenvalues of the
    same Jacobian, with the same labels and participations: the same modes as the full analysis,
    and the same stability decision (rigid CG 0.30: stable at GJ 800, fluttering at 300)."""
    for gj in (800.0, 300.0):
        m = _model(paper, 0.30, gj)
        tr = trim(m)
        full, least = analyse(m, tr), analyse(m, tr, "krylov")
        assert least.stable == full.stable == (gj == 800.0)
        assert len(least.modes) < len(full.modes)
        key = lambda md: (md.real_part_per_s, md.frequency_hz)  # noqa: E731
        top = sorted(full.modes, key=key, reverse=True)[:len(least.modes)]
        got = sorted(least.modes, key=key, reverse=True)
        assert [(md.label, md.real_part_per_s, md.frequency_hz, md.participation) for md in got] == \
            [(md.label, md.real_part_per_s, md.frequency_hz, md.participation) for md in top]


def test_walk_reports_every_mode_when_asked(paper):
    """The map's walk keeps the least damped modes; the dashboard's root locus asks for every mode
    (``modes="forward"``) and gets the full analysis at each point (fem-coupled, mu 0.1)."""
    fl, st = FlightCondition(mu=0.1), SolverSettings(fidelity="fem-coupled")
    rotor = paper.with_overrides(x_ea=EA)
    every = walk_column(rotor, fl, st, 0.36, 1500.0, 3000.0, modes="forward")
    least = walk_column(rotor, fl, st, 0.36, 1500.0, 3000.0)
    p = every.points[-1]
    full = analyse(p.trim.model, p.trim)
    assert len(p.modes) == len(full.modes) > len(least.points[-1].modes)
    assert every.critical_gj_nm2 == least.critical_gj_nm2


def test_forward_continuation_matches_trim_forward(paper):
    """The periodic trim continued from a neighbour equals a fresh forward trim of the same model."""
    from amra_core.periodic_trim import PeriodicContinuation
    fl = FlightCondition(mu=0.1)
    a = trim(_model(paper, 0.40, 1200.0, flight=fl))
    m = _model(paper, 0.40, 1100.0, flight=fl)
    pc = PeriodicContinuation()
    cont = pc.step(m, a)
    ref = trim(m)
    assert cont.ok and ref.ok
    assert cont.mu == pytest.approx(0.1, abs=1e-9)
    assert cont.omega_rad_s == pytest.approx(ref.omega_rad_s, rel=2e-3)
    assert cont.descent_rate_m_s == pytest.approx(ref.descent_rate_m_s, abs=0.05)
    assert cont.disk_tilt_rad == pytest.approx(ref.disk_tilt_rad, abs=math.radians(0.1))
    assert pc.revolutions < 120
