"""Equilibria: steady autorotation solved at one parameter set (the point solvers of the trim).

* Axial flight (time-invariant): solve ``f(y) = 0`` of the full nonlinear model for rotor speed,
  descent rate, inflow, lag and the static blade deflections (thrust = weight, torque = 0).
* Forward flight (periodic): with rotor speed and descent rate held, the blade motion is shot onto
  its periodic orbit (:mod:`amra_core.shooting`), and the revolution-averaged residuals (torque,
  vertical and horizontal rotor force of a gliding isolated rotor) are driven to zero over rotor
  speed, descent rate and shaft tilt by a damped Newton iteration on those averages.
* ``omega_hold_rad_s`` (paper Table 1): rotor speed held at the given value; axial: descent rate
  for thrust = weight; forward: level flight (descent 0) with the shaft tilt for lift = weight.

Following a branch of these equilibria in GJ is :mod:`amra_core.continuation`; the public
:func:`amra_core.trim.trim` does that from a stiff blade down to the requested one.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional

import numpy as np
from scipy.optimize import root

from . import kernel_guard, kernels, trim_kernels, verdict
from .model import (L_THRUST, L_TORQUE, CompiledModel, Y_OMEGA, Y_V0, Y_VD, stable_time_step,
                    transfer_state)
from .shooting import PeriodicShooting, steps_per_rev

MU_RANGE = (0.0, 0.5)


@dataclass
class TrimResult:
    """Outcome of a trim. ``status``: ``trimmed`` or ``no-autorotation`` (then ``reason`` and
    ``branch_end`` say why and where the continuation stopped)."""

    status: str
    state: Optional[np.ndarray] = None
    omega_rad_s: float = float("nan")
    descent_rate_m_s: float = float("nan")
    disk_tilt_rad: float = 0.0
    airspeed_m_s: float = 0.0
    inflow_m_s: float = float("nan")
    thrust_n: float = float("nan")
    torque_nm: float = float("nan")
    teeter_amplitude_rad: float = 0.0
    tip_twist_rad: float = 0.0
    reason: str = ""
    branch_end: dict = field(default_factory=dict)
    model: Optional[CompiledModel] = None
    #: rotor speed [rad/s] where the branch this trim was continued along started (the stiff blade);
    #: nan for a trim solved on its own (a cold start), see :func:`amra_core.continuation.continue_to`
    omega_branch_start_rad_s: float = float("nan")
    #: forward flight: the shooting Jacobian of this trim's periodic orbit, reused by the next trim
    #: of a continuation (:mod:`amra_core.shooting`)
    shooting: Optional[PeriodicShooting] = field(default=None, repr=False, compare=False)

    @property
    def ok(self) -> bool:
        return self.status == "trimmed"

    @property
    def continued(self) -> bool:
        """True when this trim was reached by continuation along a branch (not a cold start)."""
        return math.isfinite(self.omega_branch_start_rad_s)

    @property
    def branch(self) -> str:
        """Which equilibrium this is (issue 21 §4), ``none`` without one:

        * ``normal``: autorotation, descent within the turbulent-wake region (V_d <= 2 v_h);
        * ``overspeed``: beyond 2 v_h, but reached continuously along a branch on which the rotor
          speed rose above the branch's start and the inflow did not collapse: the normal branch
          overspeeding (measured, rigid EA 0.32 CG 0.24 GJ 150: 54.7 rad/s, V_d 2.02 v_h, inflow
          4-7 m/s), not the windmill-brake root;
        * ``windmill-brake``: beyond 2 v_h and either collapsed inflow (below
          ``INFLOW_COLLAPSED_RATIO`` v_h), or a separate root (a cold start, or a continued branch
          whose rotor speed fell): descent 4-6 v_h with inflow about 0.2 v_h at rigid CG 0.36-0.40."""
        if not self.ok or self.model is None or not math.isfinite(self.descent_rate_m_s):
            return "none"
        if branch_of(self.model, self.descent_rate_m_s) == "normal":
            return "normal"
        vh = _hover_induced(self.model)
        collapsed = not (self.inflow_m_s >= INFLOW_COLLAPSED_RATIO * vh)
        if self.continued and not collapsed and self.omega_rad_s > self.omega_branch_start_rad_s:
            return "overspeed"
        return "windmill-brake"

    @property
    def descent_ratio(self) -> float:
        """Descent rate / hover induced velocity v_h [-] (-V_c/v_h)."""
        if self.model is None:
            return float("nan")
        return self.descent_rate_m_s / _hover_induced(self.model)

    @property
    def mu(self) -> float:
        if not self.ok:
            return float("nan")
        return self.airspeed_m_s * math.cos(self.disk_tilt_rad) / (self.omega_rad_s * self.model.rotor.radius_m)

    def to_dict(self) -> dict:
        out = {k: getattr(self, k) for k in ("status", "omega_rad_s", "descent_rate_m_s", "disk_tilt_rad",
                                             "airspeed_m_s", "inflow_m_s", "thrust_n", "torque_nm",
                                             "teeter_amplitude_rad", "tip_twist_rad")}
        out["mu"] = self.mu
        out["branch"] = self.branch
        out["descent_ratio"] = self.descent_ratio if self.ok else float("nan")
        if not self.ok:  # no equilibrium: its tilt, airspeed, teeter and twist are not results (not 0)
            out.update(disk_tilt_rad=None, airspeed_m_s=None, teeter_amplitude_rad=None, tip_twist_rad=None)
        out = {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in out.items()}
        if self.reason:
            out["reason"] = self.reason
        if not self.ok:
            out["branch_end"] = self.branch_end
        return out


def _hover_induced(model: CompiledModel) -> float:
    r = model.rotor
    return math.sqrt(r.vehicle_mass_kg * model.flight.gravity_m_s2 / (2 * model.flight.density_kg_m3 * r.disc_area_m2))


#: an equilibrium descending faster than this many hover induced velocities (V_c/v_h < -2, beyond the
#: turbulent-wake region of the empirical inflow curve) is on the windmill-brake side, not autorotation
#: (the same limit as :data:`amra_core.verdict.WINDMILL_BRAKE_RATIO` for simulated runs)
WINDMILL_BRAKE_RATIO = 2.0


#: induced velocity below this many v_h is "collapsed": the momentum-theory windmill-brake root
#: v/v_h = -x/2 - sqrt(x^2/4 - 1) falls below 0.5 beyond a descent of 2.5 v_h, whereas the normal
#: branch keeps 0.8-1.7 v_h (rigid EA 0.32: 1.5-1.7 v_h near the fold at CG 0.36, 0.8-1.2 v_h
#: overspeeding at CG 0.24)
INFLOW_COLLAPSED_RATIO = 0.5


def branch_of(model: CompiledModel, descent_rate_m_s: float) -> str:
    """``windmill-brake`` if ``descent_rate_m_s`` [m/s] exceeds ``WINDMILL_BRAKE_RATIO`` v_h, else
    ``normal`` (the descent test alone; :attr:`TrimResult.branch` also tells overspeed apart)."""
    return "windmill-brake" if descent_rate_m_s > WINDMILL_BRAKE_RATIO * _hover_induced(model) else "normal"


def _steady_inflow_guess(x: float) -> float:
    """Steady induced velocity / v_h at descent ratio x = V_c / v_h (x < 0): the empirical curve
    inside [-2, 0], the physical windmill-brake root of momentum theory below -2."""
    if x >= -2.0:
        k = kernels.EMP_K
        return k[0] + x * (k[1] + x * (k[2] + x * (k[3] + x * k[4])))
    return -x / 2 - math.sqrt(x * x / 4 - 1.0)


def trim_axial(model: CompiledModel, guess: Optional[np.ndarray] = None, omega_hold: Optional[float] = None) -> TrimResult:
    """Steady axial autorotation (or, with ``omega_hold``, thrust = weight at that rotor speed).

    Without a ``guess`` state, several starting descent rates on the physical inflow branch are
    tried (near ideal autorotation, x = V_c/v_h = -1.9, and deeper in the windmill state)."""
    if guess is not None:
        res = _trim_axial_from(model, guess, omega_hold)
        if res.ok:
            return res
    vh = _hover_induced(model)
    res = None
    for fallback in (False, True):  # the jitted Newton from every start first; scipy's hybr only if none converges
        for ratio in (1.91, 1.85, 1.97, 2.3, 2.8, 3.5):
            y0 = np.zeros(model.n_y) if guess is None else guess.copy()
            y0[Y_OMEGA] = omega_hold or (omega_guess(model) if guess is None else guess[Y_OMEGA])
            y0[Y_VD] = ratio * vh
            y0[Y_V0] = _steady_inflow_guess(-ratio) * vh
            res = _trim_axial_from(model, y0, omega_hold, fallback)
            if res.ok:
                return res
    return res


def _trim_axial_from(model: CompiledModel, y0: np.ndarray, omega_hold: Optional[float],
                     fallback: bool = True) -> TrimResult:
    """The axial trim from ``y0``: the jitted Newton, then (``fallback``) scipy's hybr if it fails."""
    m = model.with_controls(alpha_s_rad=0.0, airspeed_m_s=0.0, quasi_static=True,
                            hold_omega=omega_hold is not None, hold_vd=False)
    a = m.arrays
    vh = _hover_induced(m)
    y0 = y0.copy()
    y0[m.xd_slice()] = 0.0
    y0[4 + 2:8] = 0.0
    dy = np.zeros(m.n_y); loads = np.zeros(8)
    free_omega = omega_hold is None
    if not free_omega:
        y0[Y_OMEGA] = omega_hold

    iu, ir = _axial_indices(m, free_omega)
    kernel_guard.check_state(y0, a)  # shapes checked once here: the residual kernel does not check
    y_work, dy_work, r_work = np.empty(m.n_y), np.empty(m.n_y), np.empty(len(iu))

    def unpack(z):
        y = y0.copy()
        y[iu] = z
        return y

    def resid(z):
        z = np.ascontiguousarray(z, dtype=np.float64)
        if z.shape != r_work.shape:
            raise kernel_guard.KernelShapeError(f"trim unknowns have shape {z.shape}, expected {r_work.shape}")
        trim_kernels.residual_at(z, y0, a, iu, ir, y_work, dy_work, loads, r_work)
        return r_work.copy()

    z0 = y0[iu]

    def physical(y, ok):
        if not ok:
            return False
        omega = y[Y_OMEGA]
        # momentum theory's second windmill root (far wake flowing down) is unphysical and unstable
        windmill_unphysical = (-y[Y_VD] / vh < -2.0 - 0.1) and (-y[Y_VD] + 2 * y[Y_V0] > 0)
        return (0.2 * omega_guess(m) < omega < 4 * omega_guess(m)) and not windmill_unphysical \
            and not _inflow_unstable(m, y)

    # the jitted Newton first; scipy's hybr (``fallback``) where it does not converge or converges
    # to a root off the physical branch (hybr, from the same start, may find the physical one)
    y = _newton_axial(m, y0, free_omega)
    good = y is not None and physical(y, True)
    if not good and fallback:
        sol = root(resid, z0, method="hybr", options={"xtol": 1e-11, "maxfev": 200 * (len(z0) + 1)})
        y = unpack(sol.x)
        res = np.abs(resid(sol.x))
        good = physical(y, sol.success or res.max() < 1e-6)
    if not good:
        return TrimResult("no-autorotation", reason="no torque/thrust equilibrium found on the physical branch",
                          model=model)
    omega = y[Y_OMEGA]
    kernel_guard.evaluate(y, a, dy, loads)
    y_full = y.copy()
    kernel_guard.steady_wagner_states(y_full, model.arrays)
    tw = _tip_twist(model, y_full)
    return TrimResult("trimmed", y_full, omega, y[Y_VD], 0.0, 0.0, y[Y_V0], loads[L_THRUST], loads[L_TORQUE],
                      0.0, tw, model=model)


def _axial_indices(m: CompiledModel, free_omega: bool) -> tuple:
    """(unknowns, residuals) of the axial trim as state indices: rotor speed unless held, descent
    rate, inflow, lag and the static structural coordinates; their rates as the residuals."""
    xs, xds = m.x_slice(), m.xd_slice()
    lead = [Y_OMEGA] if free_omega else []
    iu = np.array(lead + [Y_VD, Y_V0, 4, 5] + list(range(xs.start, xs.stop)), dtype=np.int64)
    ir = np.array(lead + [Y_VD, Y_V0, 6, 7] + list(range(xds.start, xds.stop)), dtype=np.int64)
    if len(iu) != len(ir) or max(iu.max(), ir.max()) >= m.n_y or min(iu.min(), ir.min()) < 0:
        raise kernel_guard.KernelShapeError(f"trim unknown/residual indices do not fit a state of length {m.n_y}")
    return iu, ir


def _newton_axial(m: CompiledModel, y0: np.ndarray, free_omega: bool) -> Optional[np.ndarray]:
    """The axial trim by the jitted Newton of :mod:`amra_core.trim_kernels` from ``y0``, or None."""
    iu, ir = _axial_indices(m, free_omega)
    y = np.ascontiguousarray(y0, dtype=np.float64).copy()
    kernel_guard.check_state(y, m.arrays)  # shapes checked once here: the Newton kernel does not check
    it, rn = trim_kernels.newton_axial(y, m.arrays, iu, ir, 1e-8, 40)
    if it < 0 or not np.all(np.isfinite(y)):
        return None
    return y


def _inflow_unstable(m: CompiledModel, y: np.ndarray) -> bool:
    """True where the inflow equation alone is unstable at ``y`` (d(dv0/dt)/dv0 > 0): a root of
    the steady equations on the unphysical side of the turbulent-wake curve, which an eigen
    analysis would report as a real 'inflow' divergence that no flight test has seen."""
    h = 1e-4 * max(abs(y[Y_V0]), 1.0)
    dy = np.zeros(m.n_y); loads = np.zeros(8)
    yp = y.copy(); yp[Y_V0] += h
    kernel_guard.evaluate(yp, m.arrays, dy, loads); up = dy[Y_V0]
    yp[Y_V0] -= 2 * h
    kernel_guard.evaluate(yp, m.arrays, dy, loads)
    return (up - dy[Y_V0]) / (2 * h) > 0.0


def omega_guess(model: CompiledModel) -> float:
    """A tip speed of 150 m/s: only a scale for sanity checks and first guesses."""
    return 150.0 / model.rotor.radius_m


def _tip_twist(model: CompiledModel, y: np.ndarray) -> float:
    return float(model.arrays.tip[0, 1] @ y[model.x_slice()])


# --------------------------------------------------------------------------- forward flight
def _march_revs(model: CompiledModel, y: np.ndarray, n_revs: int, dt: float):
    """March ``n_revs`` revolutions (rotor speed/descent held per the model flags) and return the
    state and the averages of thrust, torque, vertical and horizontal force over the last one,
    and the teeter history of the last revolution."""
    steps_rev, dt_rev = steps_per_rev(y[Y_OMEGA], dt)
    n = n_revs * steps_rev
    hist = np.zeros((steps_rev, kernels.N_HIST)); states = np.zeros((steps_rev, len(y)))
    if n_revs > 1:
        dummy_h = np.zeros((1, kernels.N_HIST)); dummy_s = np.zeros((1, len(y)))
        kernel_guard.advance(y, 0.0, dt_rev, n - steps_rev, 10**9, model.arrays, dummy_h, dummy_s, -1.0)
    done, rows, status = kernel_guard.advance(y, 0.0, dt_rev, steps_rev, 1, model.arrays, hist, states, -1.0)
    if status != 0:
        raise FloatingPointError("non-finite state while converging the periodic solution")
    avg = hist[:rows].mean(axis=0)
    return y, avg, hist[:rows]


#: a forward trim's Newton iteration stops when this many iterations did not halve its best residual
#: while that is still above STALL_FAR: on a branch that has ended it cycles (residuals 0.45, 0.54,
#: 0.45, ...) and 30 iterations cost 100+ revolutions per failed continuation step. Near the
#: acceptance level (1e-3) it is left to run: there the revolution averages of a lightly damped
#: blade fluctuate about 1e-3 and a later iterate often falls below it.
STALL_ITERATIONS = 8
STALL_FAR = 1e-2
#: it also stops when its last STALL_ITERATIONS residuals are all above this many times its best one,
#: whatever the level: it has left that iterate behind. Near an unstable periodic orbit (fem-coupled
#: McCutcheon, mu 0.5, the continuation in GJ at 3,600-3,700 N m^2/rad) such an iteration drifted on
#: for all its 30 iterations (residuals from 1e-3 up to 3e-2) and failed. Measured when this came in
#: (2026-12-07): the McCutcheon trims at every fidelity and mu 0.1-0.5, the validation report and the
#: mu 0.1 maps gave the same answers as without it, with up to 22 % fewer revolutions marched
#: (``tests/core/test_trim_work.py``)
LEFT_BEST_FACTOR = 2.0
#: halvings of a Newton step that raises the residual (from a continuation step's prediction near
#: a fold the full step overshoots, and the undamped iteration wandered off a trim that exists)
BACKTRACKS = 3


#: statuses of a held-speed trim's second and third starts (:func:`trim_forward`)
RETRIES = ("retry-bracket", "retry")
#: shaft tilts [deg] at which a failed held-speed trim looks for the vertical force crossing the weight
BRACKET_TILTS_DEG = (-10.0, -5.0, 0.0, 5.0, 10.0, 15.0, 20.0)


def _tilt_bracket(model: CompiledModel, y0: np.ndarray, omega: float, airspeed_m_s, mu, dt: float):
    """The shaft tilt [rad] where the vertical force, marched 12 revolutions from ``y0`` at each
    tilt of :data:`BRACKET_TILTS_DEG`, first rises through the weight (linear between the two
    tilts), or None. A held-speed trim's Newton iteration from its cold start (8 deg) can wander to
    the tilt bound where the marched force is not yet periodic (paper Table 1 case B,
    fem-coupled); from this bracket it starts next to the trim."""
    H = {c: i for i, c in enumerate(kernels.HISTORY_COLUMNS)}
    weight = model.rotor.vehicle_mass_kg * model.flight.gravity_m_s2
    prev = None
    for deg in BRACKET_TILTS_DEG:
        tilt = math.radians(deg)
        speed = airspeed_m_s if mu is None else mu * omega * model.rotor.radius_m / math.cos(tilt)
        y = y0.copy(); y[Y_OMEGA] = omega; y[Y_VD] = 0.0
        try:
            _, avg, _ = _march_revs(model.with_controls(alpha_s_rad=tilt, airspeed_m_s=speed, hold_omega=True,
                                                        hold_vd=True), y, 12, dt)
        except FloatingPointError:
            prev = None
            continue
        res = avg[H["vertical_force_n"]] / weight - 1.0
        if prev is not None and prev[1] < 0.0 <= res:
            return prev[0] + (tilt - prev[0]) * (-prev[1]) / (res - prev[1])
        prev = (tilt, res)
    return None


def trim_forward(model: CompiledModel, airspeed_m_s: Optional[float], omega_hold: Optional[float] = None,
                 guess: Optional[TrimResult] = None, mu: Optional[float] = None, settle: bool = False) -> TrimResult:
    """Periodic trim in forward flight at horizontal airspeed ``airspeed_m_s`` [m/s], or, with
    ``mu`` given (and ``airspeed_m_s`` None), at the advance ratio ``mu``: the airspeed then follows
    the unknowns, ``V = mu Omega R / cos(tilt)``, inside the one Newton iteration (a fixed point
    on the airspeed around whole trims cost two to three trims per advance ratio). ``settle``: every
    trial's blade motion is shot all the way onto its periodic orbit (:attr:`PeriodicShooting.settle`),
    the fallback of :func:`trim_forward_continued` for a step that failed without it."""
    H = {c: i for i, c in enumerate(kernels.HISTORY_COLUMNS)}
    weight = model.rotor.vehicle_mass_kg * model.flight.gravity_m_s2
    base = trim_axial(model) if guess is None else guess
    if not base.ok and base.status not in RETRIES:
        return base
    y = base.state.copy()
    omega = omega_hold or base.omega_rad_s
    vd = 0.0 if omega_hold else (base.descent_rate_m_s if guess is not None else base.descent_rate_m_s * 0.5)
    tilt = base.disk_tilt_rad if guess is not None else math.radians(8.0)
    y[Y_OMEGA] = omega
    y[Y_VD] = vd
    dt = stable_time_step(model, omega)
    free = ["tilt"] if omega_hold else ["omega", "vd", "tilt"]

    def speed(vals) -> float:
        if mu is None:
            return airspeed_m_s
        return mu * vals["omega"] * model.rotor.radius_m / math.cos(vals["tilt"])

    # the periodic orbit of every trial is shot for with the transition matrix of a neighbouring
    # trim (a continuation's last one) or of this trim's start, formed again once if the Newton
    # iteration stalls with it; a cold start marches until it stalls near the trim
    inherited = guess is not None and guess.shooting is not None and guess.shooting.fits(model)
    shooting = guess.shooting.copy() if inherited else PeriodicShooting()
    shooting.settle = settle

    def evaluate(z, n_revs):
        nonlocal y
        vals = dict(omega=omega, vd=vd, tilt=tilt)
        vals.update(dict(zip(free, z)))
        m = model.with_controls(alpha_s_rad=vals["tilt"], airspeed_m_s=speed(vals), hold_omega=True, hold_vd=True)
        y[Y_OMEGA] = vals["omega"]; y[Y_VD] = vals["vd"]
        if shooting.lu is not None:  # onto this trial's periodic orbit, then one revolution to average
            y, _ = shooting.project(m, y, dt)
            n_revs = 1
        y, avg, last = _march_revs(m, y, n_revs, dt)
        res = [avg[H["vertical_force_n"]] / weight - 1.0]
        if not omega_hold:
            res = [avg[H["torque_nm"]] / (0.05 * weight * model.rotor.radius_m)] + res + [avg[H["horizontal_force_n"]] / weight]
        return np.array(res), avg, last, m

    z = np.array([dict(omega=omega, vd=vd, tilt=tilt)[k] for k in free])
    res, avg, last, m = evaluate(z, 12 if guess is None else 4)
    if shooting.lu is None and guess is not None:
        shooting.build(m, y, dt)
        res, avg, last, m = evaluate(z, 1)
    steps = np.array([dict(omega=0.2, vd=0.1, tilt=math.radians(0.2))[k] for k in free])
    J, last_norm, norms = None, math.inf, []
    for it in range(30):
        norm = np.max(np.abs(res))
        norms.append(norm)
        if norm < 2e-4:
            break
        if (it >= STALL_ITERATIONS + 4 and min(norms) > STALL_FAR
                and min(norms[-STALL_ITERATIONS:]) > 0.5 * min(norms[:-STALL_ITERATIONS])):
            break  # stagnation far from a trim: no halving of the best residual lately (it cycles)
        if it >= STALL_ITERATIONS and min(norms[-STALL_ITERATIONS:]) > LEFT_BEST_FACTOR * min(norms):
            break  # drifting away from its best iterate, at any level
        # chord Newton: the difference Jacobian (one march per unknown) is formed again only when
        # the last step did not halve the residual; a good one is reused, so an iteration that
        # converges costs one march instead of one plus one per unknown
        if norm > 0.5 * last_norm and (inherited or (shooting.lu is None and norm < STALL_FAR)):
            # the neighbour's matrix no longer serves, or a cold start (marched: its guess is far
            # from any orbit) stalls near the trim on the blade's slow transient
            inherited = False
            shooting.build(m, y, dt)
            res, avg, last, m = evaluate(z, 1)
            norm = np.max(np.abs(res))
        if J is None or norm > 0.5 * last_norm:
            J = np.zeros((len(z), len(z)))
            y_keep = y.copy()
            for k in range(len(z)):
                zp = z.copy(); zp[k] += steps[k]
                y = y_keep.copy()
                rp, _, _, _ = evaluate(zp, 3)
                J[:, k] = (rp - res) / steps[k]
            y = y_keep
        last_norm = norm
        try:
            dz = -np.linalg.solve(J, res)
        except np.linalg.LinAlgError:
            break
        lim = np.array([dict(omega=5.0, vd=2.0, tilt=math.radians(2.0))[k] for k in free])
        dz = np.clip(dz, -lim, lim)
        y_keep = y.copy()
        trial = evaluate(z + dz, 4)
        for _ in range(BACKTRACKS):  # a damped step: halved while it raises the residual
            if np.max(np.abs(trial[0])) <= norm:
                break
            dz = dz / 2
            y = y_keep.copy()
            trial = evaluate(z + dz, 4)
        z = z + dz
        res, avg, last, m = trial
    vals = dict(omega=omega, vd=vd, tilt=tilt); vals.update(dict(zip(free, z)))
    ok = np.max(np.abs(res)) < 1e-3 and 0.2 * omega_guess(model) < vals["omega"] < 4 * omega_guess(model)
    if not ok and omega_hold:
        tried = guess.status if guess is not None else None
        if tried not in RETRIES:  # again from the tilt where the marched vertical force crosses the weight
            tilt0 = _tilt_bracket(model, base.state, omega_hold, airspeed_m_s, mu, dt)
            if tilt0 is not None:
                retry = TrimResult("retry-bracket", state=base.state, disk_tilt_rad=tilt0, omega_rad_s=omega_hold,
                                   model=model)
                return trim_forward(model, airspeed_m_s, omega_hold, retry, mu)
        if tried != "retry":
            retry = TrimResult("retry", state=base.state, disk_tilt_rad=math.radians(20.0), omega_rad_s=omega_hold,
                               model=model)
            return trim_forward(model, airspeed_m_s, omega_hold, retry, mu)
        return _max_thrust_level(model, speed(vals), omega_hold, base.state, dt)
    if not ok:
        return TrimResult("no-autorotation", reason=f"forward-flight trim did not converge (residuals {np.round(res, 4).tolist()})",
                          model=model)
    final = model.with_controls(alpha_s_rad=vals["tilt"], airspeed_m_s=speed(vals),
                                hold_omega=omega_hold is not None, hold_vd=omega_hold is not None)
    return TrimResult("trimmed", y.copy(), vals["omega"], vals["vd"], vals["tilt"], speed(vals),
                      float(y[Y_V0]), float(avg[H["thrust_n"]]), float(avg[H["torque_nm"]]),
                      verdict.teeter_amplitude_rad(last), float(np.mean(last[:, H["tip_twist_0_rad"]])), model=final,
                      shooting=shooting)


def _solve_at(model: CompiledModel, hold, guess: Optional[TrimResult]) -> TrimResult:
    fl = model.flight
    if guess is not None and guess.model is not model:
        from dataclasses import replace as _replace
        guess = _replace(guess, state=transfer_state(guess.state, guess.model, model), model=model)
    if fl.is_axial:
        res = trim_axial(model, guess=None if guess is None else guess.state, omega_hold=hold)
        if res.ok and hold is not None:
            res.model = model.with_controls(hold_omega=True)
        return res
    if guess is None and hold is None:
        return trim_forward_continued(model)  # a cold start only at low speed, then step up
    return _solve_forward_at(model, hold, guess)


def _solve_forward_at(model: CompiledModel, hold, guess: Optional[TrimResult], settle: bool = False) -> TrimResult:
    """Forward-flight trim at the model's airspeed or advance ratio from ``guess`` (cold start from
    the axial trim when None: converges only at low speed, see :func:`trim_forward_continued`)."""
    fl = model.flight
    if fl.mu is None:
        return trim_forward(model, fl.airspeed_m_s, hold, guess, settle=settle)
    return trim_forward(model, None, hold, guess, mu=fl.mu, settle=settle)


#: forward trims are cold-started (from the axial trim, shaft tilt 8 deg, half the axial descent
#: rate) only up to this advance ratio; faster conditions are reached by continuation from there
FORWARD_COLD_START_MU = (0.15, 0.1, 0.05)
FORWARD_STEP_MU = 0.05  #: first continuation step in advance ratio (halved on a failed step)
FORWARD_MIN_STEP_MU = 0.004


def trim_forward_continued(model: CompiledModel) -> TrimResult:
    """Forward-flight trim (free rotor speed) by continuation in flight speed from a slow condition.

    Why: the cold start of :func:`trim_forward` guesses shaft tilt +8 deg and half the axial descent
    rate; the trims of the McCutcheon rotor have a forward-tilted shaft (-2.4 deg at mu 0.2, -3.4
    deg at mu 0.3, -5.2 deg at mu 0.5) and a descent rate of 4-7 m/s. From mu 0.25 up the Newton
    iteration on 3-revolution averages (whose blade motion has not settled from the bad guess) then
    wanders with clipped steps and ends unconverged (mu 0.25) or in a non-finite march (mu 0.3), although a
    trim exists all the way to mu 0.5. So the trim is cold-started at mu <= 0.15 and followed up in
    advance ratio (or in airspeed, when the airspeed is given) with each trim the guess of the next,
    halving the step on a failure. When the branch cannot be followed to the requested speed, the
    result is ``no-autorotation`` with the last trimmed point's state and model and ``branch_end``
    (``kind: forward-speed``, its advance ratio, airspeed, rotor speed, descent rate, shaft tilt), from
    which a simulation can start."""
    from dataclasses import replace as _replace
    fl = model.flight
    by_mu = fl.mu is not None
    target = float(fl.mu) if by_mu else float(fl.airspeed_m_s)
    omega0 = omega_guess(model)
    scale = 1.0 if by_mu else omega0 * model.rotor.radius_m  # speed per unit advance ratio [m/s]

    def model_at(s: float) -> CompiledModel:
        if abs(s - target) < 1e-12:
            return model
        f = _replace(fl, mu=s) if by_mu else _replace(fl, airspeed_m_s=s)
        return _replace(model, flight=f)

    def solve(s, guess, prev2=None, ratio=1.0, settle=False) -> Optional[TrimResult]:
        """The trim at speed ``s`` from ``guess``: None unless it continues the branch through
        ``guess`` and ``prev2`` (:func:`on_branch`, the secant over the last two speeds, ``ratio``
        the new step over the last one)."""
        try:
            res = _solve_forward_at(model_at(s), None, guess, settle)
        except FloatingPointError as exc:
            res = TrimResult("no-autorotation", reason=str(exc), model=model_at(s))
        if guess is None:
            return res if _plausible(res, None) else None
        if not on_branch(res, guess, prev2, ratio):
            # a step that failed is tried again with every trial shot all the way onto its orbit:
            # near mu 0.5 the orbit is unstable (largest multipliers 1.8 to 3.4 per revolution), and one
            # chord Newton step leaves a gap that the averaging revolution amplifies
            return None if settle else solve(s, guess, prev2, ratio, True)
        return res

    prev, s_prev = None, None
    for s0 in sorted({min(target, mu0 * scale) for mu0 in FORWARD_COLD_START_MU}, reverse=True):
        prev = solve(s0, None)
        if prev is not None:
            s_prev = s0
            break
    if prev is None:
        return TrimResult("no-autorotation", model=model,
                          reason=f"no forward-flight trim even at mu <= {FORWARD_COLD_START_MU[0]:g} "
                                 f"(cold starts from the axial trim did not converge)")
    step = FORWARD_STEP_MU * scale
    prev2, s_prev2 = None, None
    while s_prev < target - 1e-12:
        s = min(target, s_prev + step)
        ratio = (s - s_prev) / (s_prev - s_prev2) if prev2 is not None else 0.0
        res = solve(s, prev, prev2, ratio)
        if res is not None:
            prev2, s_prev2, prev, s_prev = prev, s_prev, res, s
            step = min(FORWARD_STEP_MU * scale, 1.5 * step)
            continue
        step *= 0.5
        if step < FORWARD_MIN_STEP_MU * scale:
            break
    if s_prev >= target - 1e-12 and prev.model.flight == model.flight:
        return prev
    out = TrimResult("no-autorotation", model=prev.model, state=prev.state)
    what = f"mu {s_prev:.3g}" if by_mu else f"airspeed {s_prev:.3g} m/s"
    out.reason = (f"no steady autorotation: the forward-flight trim branch, followed up in "
                  f"{'advance ratio' if by_mu else 'airspeed'} from a slow trim, ends at {what} "
                  f"(no trim for a step of {step / scale:.2g} in mu beyond it)")
    out.branch_end = {"kind": "forward-speed", "mu": float(prev.mu), "airspeed_m_s": float(prev.airspeed_m_s),
                      "omega_rad_s": float(prev.omega_rad_s), "descent_rate_m_s": float(prev.descent_rate_m_s),
                      "disk_tilt_rad": float(prev.disk_tilt_rad), "tip_twist_rad": float(prev.tip_twist_rad),
                      "gj_mean_nm2": gj_mean_of(prev.model),
                      "requested_mu": float(fl.mu) if by_mu else None,
                      "requested_airspeed_m_s": None if by_mu else float(fl.airspeed_m_s)}
    out.start = prev
    return out


def gj_mean_of(model: CompiledModel) -> float:
    return float(np.mean(model.rotor.stations.gj_nm2))


def _plausible(res: TrimResult, prev: Optional[TrimResult]) -> bool:
    """Reject solutions off the physical branch: tip Mach above 0.9, or a jump in rotor speed."""
    if not res.ok:
        return False
    m = res.model
    if res.omega_rad_s * m.rotor.radius_m / m.flight.speed_of_sound_m_s > 0.9:
        return False
    if prev is not None and abs(res.omega_rad_s - prev.omega_rad_s) > 0.25 * prev.omega_rad_s:
        return False
    return True


#: largest change, beyond the secant prediction, that a continuation step may show: rotor speed
#: [fraction], descent rate and inflow [fraction of v_h], tip twist [rad]
STEP_OMEGA_REL = 0.05
STEP_SPEED_VH = 0.15
STEP_TWIST_RAD = 0.02


def _trim_scalars(res: TrimResult) -> np.ndarray:
    return np.array([res.omega_rad_s, res.descent_rate_m_s, res.inflow_m_s, res.tip_twist_rad])


def on_branch(res: TrimResult, prev: TrimResult, prev2: Optional[TrimResult] = None, s: float = 1.0) -> bool:
    """True if ``res`` continues the branch through ``prev`` (and ``prev2``): trimmed, the same branch
    tip Mach below 0.9, and rotor speed, descent rate, inflow and tip twist within ``STEP_*`` of
    the secant prediction. A False here means: halve the step (or a fold). The branch may move
    continuously across V_c/v_h = -2 (its points there are then ``windmill-brake``); a jump onto the
    separate windmill-brake root (descent rates 2-4 times the normal one) fails the descent check."""
    if not _plausible(res, None):
        return False
    vh = _hover_induced(res.model)
    x1 = _trim_scalars(prev)
    pred = x1 if prev2 is None else x1 + s * (x1 - _trim_scalars(prev2))
    d = np.abs(_trim_scalars(res) - pred)
    return bool(d[0] <= STEP_OMEGA_REL * prev.omega_rad_s and d[1] <= STEP_SPEED_VH * vh
                and d[2] <= STEP_SPEED_VH * vh and d[3] <= STEP_TWIST_RAD)


def _max_thrust_level(model: CompiledModel, airspeed_m_s: float, omega: float, y0: np.ndarray, dt: float) -> TrimResult:
    """Level flight at a held rotor speed where lift cannot reach the weight: scan the shaft tilt
    for the largest revolution-averaged vertical force and report it (status ``thrust-limited``)
    with the teeter amplitude there (model-notes §6, G-UNIV Table 1)."""
    H = {c: i for i, c in enumerate(kernels.HISTORY_COLUMNS)}
    y = y0.copy(); y[Y_OMEGA] = omega; y[Y_VD] = 0.0
    best = None
    for tilt_deg in np.arange(-4.0, 50.01, 2.0):
        m = model.with_controls(alpha_s_rad=math.radians(tilt_deg), airspeed_m_s=airspeed_m_s, hold_omega=True, hold_vd=True)
        y, avg, last = _march_revs(m, y, 10, dt)
        if best is None or avg[H["vertical_force_n"]] > best[1][H["vertical_force_n"]]:
            best = (tilt_deg, avg, last, y.copy())
    tilt_deg, avg, last, yb = best
    weight = model.rotor.vehicle_mass_kg * model.flight.gravity_m_s2
    res = TrimResult("thrust-limited", yb, omega, 0.0, math.radians(tilt_deg), airspeed_m_s, float(yb[Y_V0]),
                     float(avg[H["thrust_n"]]), float(avg[H["torque_nm"]]), verdict.teeter_amplitude_rad(last),
                     float(np.mean(last[:, H["tip_twist_0_rad"]])), model=model)
    res.reason = (f"with the rotor speed held at {omega:g} rad/s the largest vertical force in level flight is "
                  f"{avg[H['vertical_force_n']]:.0f} N ({100 * avg[H['vertical_force_n']] / weight:.0f} % of the weight "
                  f"{weight:.0f} N), at a shaft tilt of {tilt_deg:g} deg; reported there")
    return res


def windmill_brake_state(model: CompiledModel, hold=None) -> Optional[TrimResult]:
    """An axial equilibrium of ``model`` on the windmill-brake side (cold starts deep in the
    windmill state), or None (forward flight: not searched)."""
    if not model.flight.is_axial:
        return None
    vh = _hover_induced(model)
    for fallback in (False, True):
        for ratio in (2.8, 3.5, 4.5, 6.0):
            y0 = np.zeros(model.n_y)
            y0[Y_OMEGA] = hold or omega_guess(model)
            y0[Y_VD] = ratio * vh
            y0[Y_V0] = _steady_inflow_guess(-ratio) * vh
            try:
                res = _trim_axial_from(model, y0, hold, fallback)
            except FloatingPointError:
                continue
            if _plausible(res, None) and res.branch == "windmill-brake":
                return res
    return None
