"""Linearised stability against time marching (issue 4: growth rates agree within 10 %)."""
import pytest

from amra_core.flight import FlightCondition, SolverSettings
from amra_core.model import compile_model
from amra_core.rotor_io import load_preset
from amra_core.simulation import Case, Perturbation, Simulation
from amra_core.stability import analyse, assess_cell


def _paper_rotor(gj, cg):
    return load_preset("paper-boundary").with_overrides(gj_nm2=gj, x_ea=0.32, x_cg=cg)


@pytest.mark.parametrize("gj, cg", [(300.0, 0.30), (400.0, 0.30)])
def test_eigen_growth_matches_time_marching(gj, cg):
    """Rigid, axial, theodorsen: cells with one dominant unstable (flutter) mode (torsion meeting
    the cyclic flap, 12.7 and 13.7 Hz; the column at CG 0.30 is unstable from 216 to 435). The time run
    starts from trim with a 1e-4 kick (linear regime) and lasts 3 s; its envelope growth rate
    must be within 10 % of the eigenvalue's real part, its frequency within 5 %."""
    rotor = _paper_rotor(gj, cg)
    cell = assess_cell(rotor, FlightCondition(), SolverSettings())
    assert cell.verdict == "flutter"
    run = Simulation(Case(rotor, t_end_s=3.0, perturbation=Perturbation(1e-4, 5e-5))).run()
    v = run.verdict()
    print(f"\nGJ {gj} CG {cg}: eigen {cell.growth_rate_per_s:.3f} 1/s at {cell.frequency_hz:.2f} Hz; "
          f"time marching {v.growth_rate_per_s:.3f} 1/s at {v.frequency_hz:.2f} Hz")
    assert v.verdict == "flutter"
    assert v.growth_rate_per_s == pytest.approx(cell.growth_rate_per_s, rel=0.10)
    assert v.frequency_hz == pytest.approx(cell.frequency_hz, rel=0.05)


@pytest.mark.parametrize("mu", [0.0, 0.1])
def test_nominal_mccutcheon_linearly_stable(mu):
    fl = FlightCondition(mu=mu) if mu else FlightCondition()
    res = analyse(compile_model(load_preset("mccutcheon"), fl, SolverSettings()))
    assert res.trim.ok and res.stable
    assert res.method == ("eigenvalues" if mu == 0 else "floquet")
    assert all(m.real_part_per_s < 0 for m in res.modes)
    labels = {m.label for m in res.modes}
    assert {"torsion", "flap", "lag"} <= labels, labels
    # the teeter mode sits at 1/rev in the rotating frame, damped by the aerodynamics at a damping
    # ratio near 0.5 (axial: 6.0 Hz, -22.7 1/s). With aerodynamics it carries flap, twist and in
    # forward flight inflow about as much as teeter (rigid mu 0.1, over a revolution: inflow 0.36,
    # teeter 0.20, flap 0.17, torsion 0.14), so it is found by its teeter participation, not by its
    # largest one; so damped a mode is a peak as wide as its damping ratio (half-power half-width
    # zeta f), and in forward flight it is found within that of 1/rev (6.92 Hz at 6.02 Hz, zeta 0.50)
    omega_hz = res.trim.omega_rad_s / (2 * 3.141592653589793)
    teeter = [m for m in res.modes if m.participation.get("teeter", 0.0) >= 0.2]
    band = (lambda m: 0.05) if mu == 0 else (lambda m: max(0.05, m.damping_ratio))  # axial: the eigenvalue itself
    assert teeter and min(abs(m.frequency_hz - omega_hz) / band(m) for m in teeter) < omega_hz


def test_fem_coupled_forward_cell_is_not_a_numerical_failure():
    """Regression: the averaged Jacobian used to unfold Floquet exponents was marched with a
    step above the fem-coupled explicit limit and turned NaN (the cell was recorded 'failed')."""
    rotor = _paper_rotor(3000.0, 0.48)
    cell = assess_cell(rotor, FlightCondition(mu=0.1), SolverSettings(fidelity="fem-coupled"))
    print(f"\nfem-coupled mu 0.1 GJ 3000 CG 0.48: {cell.verdict} ({cell.reason})")
    assert cell.verdict != "failed"


def test_unpaired_exponent_is_a_mode_whatever_its_branch():
    """A real negative Floquet multiplier has one exponent, ln|z|/T + i pi/T, and no conjugate;
    unfolding may move it to a branch with a negative imaginary part. It is still a mode: only the
    second member of a complex pair is left out (an unstable mode was dropped this way, calling a
    fluttering trim stable)."""
    import numpy as np
    from amra_core.stability import _modes_from_exponents
    m = compile_model(_paper_rotor(1000.0, 0.36), FlightCondition(mu=0.1), SolverSettings())
    n = m.n_y - 1
    lam = np.array([0.62 - 40.6j, -0.5 + 3.0j, -0.5 - 3.0j, -2.0 + 0.0j])
    vecs = np.zeros((n, 4), dtype=complex)
    vecs[m.x_slice().start - 1:m.x_slice().stop - 1] = 1.0
    modes = _modes_from_exponents(m, lam, vecs, 34.0)
    assert sorted(md.real_part_per_s for md in modes) == pytest.approx([-2.0, -0.5, 0.62])
    unstable = [md for md in modes if md.real_part_per_s > 0]
    assert unstable[0].frequency_hz == pytest.approx(40.6 / (2 * 3.141592653589793))


def test_real_negative_multiplier_flutter_agrees_with_the_run():
    """Rigid, mu 0.1, CG 0.32, GJ 231 N m^2/rad (just above the fold at 229): the least damped mode
    is a torsion flutter whose Floquet multiplier is real and negative (-1.12, growth +0.62 1/s).
    Before the fix above, the analysis dropped it and called the trim stable (least damped
    -0.33 1/s), while a run of the same case flutters: a kick grows at the same frequency into a
    limit cycle. The map and the run now use the same word."""
    from amra_core.trim import trim
    rotor = _paper_rotor(231.0, 0.32)
    fl = FlightCondition(mu=0.1)
    tr = trim(compile_model(rotor, fl, SolverSettings()))
    assert tr.ok
    res = analyse(tr.model, tr)
    crit = res.critical
    assert not res.stable and crit.label == "torsion"
    assert crit.real_part_per_s == pytest.approx(0.62, abs=0.02)
    v = Simulation(Case(rotor, fl, SolverSettings(), t_end_s=4.0, perturbation=Perturbation(1e-4, 5e-5)),
                   trim_result=tr).run().verdict()
    assert v.verdict == "flutter"
    assert v.frequency_hz == pytest.approx(crit.frequency_hz, rel=0.05)


@pytest.mark.parametrize("fidelity,mu,cg", [("rigid", 0.0, 0.40), ("rigid", 0.0, 0.24), ("rigid", 0.1, 0.3125)])
def test_stability_says_the_word_of_the_map_cell(fidelity, mu, cg):
    """``amra stability`` answered "stable: False" where a map cell of the same trim said flutter (or
    no-autorotation, overspeed): :func:`verdict_of_trim` gives the cell's word for every point of a
    column that has a trim (a fold cell has none: ``amra stability`` then says no-autorotation)."""
    from amra_core.boundary import cells_of_walk
    from amra_core.column import walk_column
    from amra_core.rotor_io import load_preset
    from amra_core.stability import verdict_of_trim
    rotor = load_preset("mccutcheon" if mu else "paper-boundary").with_overrides(x_ea=0.32, x_cg=cg)
    fl = FlightCondition(mu=mu) if mu else FlightCondition()
    w = walk_column(rotor, fl, SolverSettings(fidelity), cg, 30.0, 3000.0, rel_tol=0.05, n_probe=5)
    cells = {c.gj_nm2: c for c in cells_of_walk(cg, w.points)}
    checked = set()
    for p in w.points:
        if p.kind in ("fold", "failed") or p.trim is None or not p.trim.ok:
            continue
        assert verdict_of_trim(p.trim, p.modes) == cells[p.gj_nm2].verdict, (p.gj_nm2, p.kind)
        checked.add(cells[p.gj_nm2].verdict)
    assert "stable" in checked and len(checked) >= 2, checked


@pytest.mark.parametrize("preset, fidelity, mu, cg, gj, hz", [
    ("paper-boundary", "rigid", 0.3, 0.40, 1500.0, 18.7),
    ("mccutcheon", "fem-coupled", 0.1, 0.3125, 283.0, 6.5),
])
def test_a_floquet_mode_has_the_frequency_its_motion_has(preset, fidelity, mu, cg, gj, hz):
    """A Floquet exponent is defined up to whole multiples of the rotor speed; the modes table puts
    each at the harmonic where its named group moves most (Bauchau & Nikishkov 2001). Checked
    against time marching: a run kicked off the trim, minus the same run unkicked, scaled by the
    mode's growth, moves the tip twist of its blades most at the unstable mode's frequency (the
    fem-coupled one is spread over harmonics: blade 0 at 2.2, 6.5 and 11.0 Hz, 1.0 : 0.97 : 0.75,
    blade 1 at 10.8, 6.5 and 2.2 Hz, 1.0 : 0.87 : 0.72; together 6.5 Hz). The nearest
    averaged-Jacobian eigenvalue put the fem-coupled flutter pair at 54.45 Hz with all 106
    exponents (Arnoldi's 50: 6.53 Hz), and the rigid mu 0.3 one at 24.6 Hz, a harmonic off."""
    import numpy as np
    from amra_core.simulation import COL
    rotor = load_preset(preset).with_overrides(gj_nm2=gj, x_ea=0.32, x_cg=cg)
    fl = FlightCondition(mu=mu)
    m = compile_model(rotor, fl, SolverSettings(fidelity))
    full, kry = analyse(m, None, "forward"), analyse(m, None, "krylov")
    crit, crit_k = full.critical, kry.critical
    assert crit.label == crit_k.label == "torsion" and crit.real_part_per_s > 0.5
    assert crit_k.frequency_hz == pytest.approx(crit.frequency_hz, abs=0.02)  # one mode, one frequency
    assert crit.frequency_hz == pytest.approx(hz, abs=0.1)
    runs = []
    for kick in (Perturbation(teeter_rad=1e-6, twist_rad=5e-7), Perturbation(teeter_rad=0.0, twist_rad=0.0)):
        sim = Simulation(Case(rotor, fl, SolverSettings(fidelity), t_end_s=6.0, perturbation=kick))
        runs.append(sim.run().history)
    t = runs[0][:, COL["t_s"]]
    power = 0.0  # the twist of both blades, as the torsion group counts it
    for col in ("tip_twist_0_rad", "tip_twist_1_rad"):
        d = (runs[0][:, COL[col]] - runs[1][:, COL[col]]) * np.exp(-crit.real_part_per_s * t)
        power = power + np.abs(np.fft.rfft(d * np.hanning(len(d)))) ** 2
    f = np.fft.rfftfreq(len(t), t[1] - t[0])
    assert f[np.argmax(power)] == pytest.approx(crit.frequency_hz, abs=0.3)
