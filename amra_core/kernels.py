"""Jitted right-hand side and time stepping of the aeroelastic rotor (no Python objects inside).

Blade element aerodynamics per station (paper §2.1, eq. 1): inflow angle ``phi = atan2(U_P, U_T)``
with ``U_P`` positive for flow coming up through the disc, ``alpha = theta + phi`` evaluated with
the 3/4-chord pitch-rate term, lift/drag/moment from the full-range table (reverse flow handled by
the ±180° data, not clipped). Unsteady option: Theodorsen in the time domain, the velocity normal to
the chord lagged by R.T. Jones' two-state approximation of Wagner's function; Theodorsen's
non-circulatory terms (apparent mass in the mass matrix, pitch-rate lift and moment here).
Induced velocity: Pitt-Peters uniform inflow ``(8/3) rho R^3 v0' + 2 rho pi R^2 V_m v0 = T``
(model-notes §3 erratum of eq. 7) with the turbulent-wake treatment of :func:`mass_flow`.
"""
from __future__ import annotations

import math

import numpy as np

from .airfoil_kernel import mach_factor, table_position, table_values
from .atan2_kernel import atan2
from .jit import exact_kernel, inline_kernel, kernel
from .sincos_kernel import sincos
from .layout import (L_FHORIZ, L_FVERT, L_HFORCE, L_THRUST, L_TORQUE, L_VM, N_LOADS, N_Y_FIXED, P_A_SOUND,
                    P_AERO, P_ALPHA_S, P_CLAG, P_FLAG, P_G, P_HOLD_OMEGA, P_HOLD_VD, P_ILAG, P_K2LAG, P_KLAG, P_MASS,
                    P_LAWSON, P_LAWSON_LAGS, P_UNIT_MASS,
                    P_INFLOW3, P_IR, P_NQ, P_NS, P_NST, P_QUASI_STATIC, P_R, P_R0, P_RHO, P_SLAG, P_VACUUM,
                    P_VH, S_A, S_C, S_R, S_THETA0, S_W, S_XAC, S_XEA, STATION_STRIDE, SV_A, SV_C, SV_R, SV_SIGN,
                    SV_THETA0, SV_W, SV_XAC, SV_XEA, N_XQ, N_XQ_UNIT, N_XQD, XQ_GLH0, XQ_GYH, XQ_K0, XQ_K2,
                    XQ_LI0, XQ_LI1, XQ_LS0, XQ_LS1, XQ_UGLH0, XQ_UGYH, XQD_C, XQD_GLH0, XQD_GYH, WAGNER_A, WAGNER_B, Y_OMEGA, Y_PSI, Y_V0, Y_VD, Y_ZETA0,
                    Y_ZETAD0)

#: hash of the amra_core modules imported above: Numba's cache does not see them
#: (tests/core/test_kernel_cache_stamps.py)
CACHE_STAMP = "5632898297839201"

A1, A2 = WAGNER_A
B1, B2 = WAGNER_B

#: Empirical induced velocity in the vortex-ring / turbulent-wake region (Leishman 2006, as in
#: physics-reference §4.6): v/v_h = K0 + K1 x + K2 x^2 + K3 x^3 + K4 x^4, x = V_c/v_h in [-2, 0].
EMP_K = (1.15, -1.125, -1.372, -1.718, -0.655)
EMP_BLEND = 0.1  # width in x over which the curve is blended into momentum theory at -2 and 0

# history columns written by advance()
HISTORY_COLUMNS = ("t_s", "azimuth_rad", "omega_rad_s", "teeter_rad", "tip_twist_0_rad",
                   "tip_twist_1_rad", "tip_flap_0_m", "tip_flap_1_m", "descent_rate_m_s",
                   "inflow_m_s", "thrust_n", "torque_nm", "lag_0_rad", "lag_1_rad",
                   "vertical_force_n", "horizontal_force_n")
N_HIST = len(HISTORY_COLUMNS)


@kernel
def mass_flow(thrust, vx, vc, v0, rho, area):
    """Mass-flow velocity V_m [m/s] of the uniform inflow equation.

    Momentum theory ``sqrt(Vx^2 + (Vc + v0)^2)`` outside the turbulent-wake region; inside
    (-2 <= Vc/v_h <= 0, ``Vc`` the climb velocity normal to the disc) V_m is set so that the steady
    inflow equals the empirical curve: ``V_m = sqrt(Vx^2 + (v_h^2 / v_emp)^2)``, blended linearly
    into momentum theory over EMP_BLEND outside both ends. Below -2 the blend partner is the
    windmill-brake root written the same way, ``v_h^2 / v_wb(x)`` (equal to momentum theory's
    ``|Vc + v0|`` at that root), so V_m does not depend on v0 there and the steady inflow has one
    root: blending with ``|Vc + v0|`` itself admits a second, unstable root near x = -2."""
    vh = math.sqrt(max(abs(thrust), 1.0) / (2.0 * rho * area))
    mom = math.sqrt(vx * vx + (vc + v0) ** 2)
    x = vc / vh
    if x <= -2.0 - EMP_BLEND or x >= EMP_BLEND:
        return max(mom, 1e-3 * vh)
    xc = min(max(x, -2.0), 0.0)
    poly = EMP_K[0] + xc * (EMP_K[1] + xc * (EMP_K[2] + xc * (EMP_K[3] + xc * EMP_K[4])))
    emp = math.sqrt(vx * vx + (vh / poly) ** 2)
    if x >= 0.0:
        w = (EMP_BLEND - x) / EMP_BLEND
        return max(w * emp + (1.0 - w) * mom, 1e-3 * vh)
    if x >= -2.0:
        return emp
    w = (x + 2.0 + EMP_BLEND) / EMP_BLEND
    v_wb = -0.5 * x - math.sqrt(max(0.25 * x * x - 1.0, 0.0))  # windmill-brake root / v_h
    wb = math.sqrt(vx * vx + (vh / v_wb) ** 2)
    return max(w * emp + (1.0 - w) * wb, 1e-3 * vh)


@inline_kernel
def wagner(wn, v, c, x1, x2):
    """R.T. Jones two-state Wagner lag of the velocity ``wn`` normal to the chord [m/s].
    Returns (effective normal velocity, dx1/dt, dx2/dt); ``x1, x2`` are the lag states [m/s],
    ``v`` the section speed [m/s], ``c`` the chord [m]. Steady state: x_k = A_k wn."""
    rate = 2.0 * v / c
    return ((1.0 - A1 - A2) * wn + x1 + x2,
            rate * B1 * (A1 * wn - x1),
            rate * B2 * (A2 * wn - x2))


@inline_kernel
def section_flow(ut, up, theta, thd, c, xea, x1, x2, theo):
    """The flow a section sees: (speed v [m/s]; effective velocity normal to the chord and along
    it [m/s], after the Wagner lag when ``theo``; dx1/dt; dx2/dt). Arguments as :func:`station_aero`."""
    v = math.sqrt(ut * ut + up * up) + 1e-9
    up34 = up + thd * (0.75 - xea) * c  # flow at the 3/4 chord (pitch-rate term)
    st_, ct_ = sincos(theta)
    # velocity normal to and along the chord (angle theta + atan2(up34, ut)), scaled to speed v
    v34 = math.sqrt(ut * ut + up34 * up34) + 1e-9
    wn = v * (st_ * ut + ct_ * up34) / v34
    uc = v * (ct_ * ut - st_ * up34) / v34
    if theo:
        wn, d1, d2 = wagner(wn, v, c, x1, x2)
    else:
        d1 = 0.0; d2 = 0.0
    return v, wn, uc, d1, d2


@inline_kernel
def section_loads(cl, cd, cm, v, wn, uc, ut, up, thd, c, xea, xac, a, rho):
    """(Force normal to the disc, up [N/m]; in-plane force in the direction of rotation [N/m];
    pitching moment about the EA, nose up [N m/m]) from the coefficients at the effective angle
    ``atan2(wn, uc)``. Arguments as :func:`station_aero` and :func:`section_flow`."""
    inv = 1.0 / (math.sqrt(wn * wn + uc * uc) + 1e-12)
    cos_a = uc * inv; sin_a = wn * inv
    qdyn = 0.5 * rho * v * v
    lift = qdyn * c * cl; drag = qdyn * c * cd
    hb = 0.5 * c
    fup = (lift * ut + drag * up) / v + math.pi * rho * hb * hb * v * thd
    ffwd = (lift * up - drag * ut) / v
    cn = cl * cos_a + cd * sin_a
    mea = qdyn * c * c * (cm + (xea - xac) * cn) - math.pi * rho * hb * hb * hb * v * (0.5 - a) * thd
    return fup, ffwd, mea


@inline_kernel
def station_aero(ut, up, theta, thd, c, xea, xac, a, x1, x2, theo, rho, a_sound,
                 af0, daf, cl_t, cd_t, cm_t):
    """Loads per unit span at one blade station.

    ``ut``: in-plane speed towards the leading edge; ``up``: flow up through the disc relative
    to the blade [m/s]; ``theta``: total pitch, ``thd``: elastic pitch rate [rad, rad/s];
    ``c`` chord [m]; ``xea``, ``xac`` chord fractions; ``a`` EA position in semichords aft of
    mid-chord. Returns (force normal to the disc, up [N/m]; in-plane force in the direction of
    rotation [N/m]; pitching moment about the EA, nose up [N m/m]; dx1/dt; dx2/dt).

    The same three steps (:func:`section_flow`, the table, :func:`section_loads`) that :func:`rhs`
    runs over all stations of both blades at once, so the two give the same numbers."""
    v, wn, uc, d1, d2 = section_flow(ut, up, theta, thd, c, xea, x1, x2, theo)
    cell, frac, aw = table_position(atan2(wn, uc), af0, daf, cl_t.shape[0])
    cl, cd, cm = table_values(cell, frac, cl_t, cd_t, cm_t)
    cl *= mach_factor(aw, v / a_sound)
    fup, ffwd, mea = section_loads(cl, cd, cm, v, wn, uc, ut, up, thd, c, xea, xac, a, rho)
    return fup, ffwd, mea, d1, d2


@inline_kernel
def section_velocities(om, r, r0, zetad, vx, vup, v0, hs, hc, sp, cp, wdot, wp):
    """(U_T, U_P) [m/s] at radius ``r`` of a blade at azimuth sine/cosine ``sp``, ``cp``: rotation
    ``om``, in-plane free stream ``vx``, lag rate ``zetad`` about the pivot at ``r0``; flow up
    through the disc ``vup`` less the induced velocity (``v0`` and the first harmonics ``hs``,
    ``hc`` per unit radius), the flap rate ``wdot`` and the free stream along the flap slope ``wp``."""
    ut = om * r + vx * sp + (r - r0) * zetad
    up = vup - (v0 + r * (hs * sp + hc * cp)) - wdot - vx * cp * wp
    return ut, up


@inline_kernel
def station_kinematics(y, m, b, j, vx, vup, sp, cp, hs, hc):
    """Blade ``b``, station ``j``: (U_T, U_P, total pitch, elastic pitch rate, flap slope,
    flap displacement, elastic twist) from the state ``y`` (see :mod:`amra_core.model`).
    ``sp``, ``cp``: sine and cosine of the blade's azimuth; ``hs``, ``hc``: first-harmonic inflow
    per unit radius [1/s] (see :func:`inflow_gradients`)."""
    p = m.p
    ns = int(p[P_NS])
    x0 = N_Y_FIXED; xd0 = N_Y_FIXED + ns
    r = m.st[j, S_R]
    w = 0.0; wdot = 0.0; wp = 0.0; th = 0.0; thd = 0.0
    for k in range(ns):
        q = y[x0 + k]; qd = y[xd0 + k]
        w += m.shw[b, j, k] * q
        wdot += m.shw[b, j, k] * qd
        wp += m.shd[b, j, k] * q
        th += m.sht[b, j, k] * q
        thd += m.sht[b, j, k] * qd
    ut, up = section_velocities(y[Y_OMEGA], r, p[P_R0], y[Y_ZETAD0 + b], vx, vup, y[Y_V0], hs, hc, sp, cp, wdot, wp)
    return ut, up, m.st[j, S_THETA0] + th, thd, wp, w, th


@inline_kernel
def inflow_gradients(y, m):
    """(v_s / R, v_c / R) [1/s] of the three-state inflow (the last two states), or zeros."""
    if m.p[P_INFLOW3] > 0.5:
        ih = y.shape[0] - 2
        return y[ih] / m.p[P_R], y[ih + 1] / m.p[P_R]
    return 0.0, 0.0


@inline_kernel
def free_stream(y, m):
    """(in-plane, up-through-disc) free-stream components [m/s] for the shaft tilt and airspeed."""
    ca = math.cos(m.p[P_ALPHA_S]); sa = math.sin(m.p[P_ALPHA_S])
    return m.p[P_VH] * ca - y[Y_VD] * sa, y[Y_VD] * ca + m.p[P_VH] * sa


#: The right-hand side's scratch vector ``work`` (:func:`new_work`): rows of STATION_STRIDE entries,
#: one per blade station of both blades (blade 0's n_st, then blade 1's); ``W_x`` is where row x
#: starts, so station s of it is ``work[W_x + s]``
W_WDOT, W_WP, W_TH, W_THD, W_UT, W_UP, W_V, W_WN, W_UC, W_CELL, W_FRAC, W_ALPHA = range(0, 12 * STATION_STRIDE,
                                                                                   STATION_STRIDE)
W_CL, W_CD, W_CM, W_FZ, W_FFWD, W_MY = range(12 * STATION_STRIDE, 18 * STATION_STRIDE, STATION_STRIDE)
#: the two Wagner states in, their rates out
W_LAG1, W_LAG2 = range(18 * STATION_STRIDE, 20 * STATION_STRIDE, STATION_STRIDE)
N_STATION_ROWS = 20
#: and the per-coordinate scratch ``cw`` (N_COORDINATE_ROWS, n_s): generalised aerodynamic force,
#: force vector and ``ul_b``.
C_Q, C_F, C_UL0, C_UL1 = range(4)
N_COORDINATE_ROWS = 4


#: and after the station rows, the products of the structural matrices with x and x' (``ModelArrays.xq``,
#: ``xqd``): ``work[W_PQ + j n + i] = (A_j x)_i``, then ``N_XQD`` rows for ``x'``
W_PQ = N_STATION_ROWS * STATION_STRIDE


@kernel
def new_work(m):
    """The two scratch arrays of :func:`rhs` for the model ``m``: (work, cw)."""
    ns = int(m.p[P_NS])
    return np.empty(W_PQ + (N_XQ + N_XQD) * ns), np.empty((N_COORDINATE_ROWS, ns))


@kernel
def rhs(y, dy, m, loads, work, cw):
    """dy = f(y). ``m`` is a ModelArrays; ``loads`` receives thrust, torque etc.; ``work`` and
    ``cw`` are the scratch arrays from :func:`new_work`.

    The blade stations of both blades are one vector (station ``s`` = blade * n_st + j, the
    layout of ``m.sv``, ``m.kin`` and ``work``), run through in passes the compiler vectorises:
    deflections at the stations, section flow, the angle of attack, the table position, the table lookups
    (indexed loads: one station after the other), the section loads; then the sums over stations. The
    structural matrices' products with the coordinates are one pass too (``ModelArrays.xq``, ``xqd``)."""
    p = m.p
    nst = int(p[P_NST]); ns = int(p[P_NS])
    rho = p[P_RHO]; R = p[P_R]; r0 = p[P_R0]
    theo = p[P_AERO] > 0.5 and p[P_QUASI_STATIC] < 0.5
    om = y[Y_OMEGA]; psi = y[Y_PSI]
    x0 = N_Y_FIXED; xd0 = N_Y_FIXED + ns; a0 = N_Y_FIXED + 2 * ns
    ca = math.cos(p[P_ALPHA_S]); sa = math.sin(p[P_ALPHA_S])
    vx, vup = free_stream(y, m)  # in-plane (towards psi = 0, the tail) and up through the disc
    thrust = 0.0; torque = 0.0; hforce = 0.0
    lagm0 = 0.0; lagm1 = 0.0
    mom_s = 0.0; mom_c = 0.0  # first moments of the normal force (sine and cosine of azimuth)
    a_sound = p[P_A_SOUND]
    hs, hc = inflow_gradients(y, m)
    vacuum = p[P_VACUUM] > 0.5
    sp0 = math.sin(psi); cp0 = math.cos(psi)  # blade 1 at psi + pi: the signs in sv[SV_SIGN]
    zd0 = y[Y_ZETAD0]; zd1 = y[Y_ZETAD0 + 1]; v0 = y[Y_V0]
    sv = m.sv; kin = m.kin
    n_af = m.af_cl.shape[0]; af_alpha0 = m.af_alpha0; af_dalpha = m.af_dalpha
    nsv = 0 if vacuum else 2 * nst
    # flap rate, flap slope, elastic twist and twist rate at every station (kin = shw, shd, sht)
    for s in range(nsv):
        work[W_WDOT + s] = 0.0; work[W_WP + s] = 0.0; work[W_TH + s] = 0.0; work[W_THD + s] = 0.0
    for k in range(ns):
        q = y[x0 + k]; qd = y[xd0 + k]
        for s in range(nsv):
            work[W_WDOT + s] += kin[k, s] * qd
            work[W_WP + s] += kin[k, STATION_STRIDE + s] * q
            work[W_TH + s] += kin[k, 2 * STATION_STRIDE + s] * q
            work[W_THD + s] += kin[k, 2 * STATION_STRIDE + s] * qd
    for s in range(nsv):  # the Wagner states, interleaved in y, as rows (a strided copy)
        work[W_LAG1 + s] = y[a0 + 2 * s]; work[W_LAG2 + s] = y[a0 + 2 * s + 1]
    # the section's flow and Wagner state rates
    for s in range(nsv):
        r = sv[SV_R, s]; sp = sv[SV_SIGN, s] * sp0; cp = sv[SV_SIGN, s] * cp0
        ut, up = section_velocities(om, r, r0, zd0 if s < nst else zd1, vx, vup, v0, hs, hc, sp, cp,
                                    work[W_WDOT + s], work[W_WP + s])
        v, wn, uc, d1, d2 = section_flow(ut, up, sv[SV_THETA0, s] + work[W_TH + s], work[W_THD + s],
                                         sv[SV_C, s], sv[SV_XEA, s], work[W_LAG1 + s], work[W_LAG2 + s], theo)
        work[W_UT + s] = ut; work[W_UP + s] = up; work[W_V + s] = v; work[W_WN + s] = wn; work[W_UC + s] = uc
        work[W_LAG1 + s] = d1; work[W_LAG2 + s] = d2
    # the angle and the table position in passes of their own: the three are each a long chain of
    # dependent operations, and in one loop body too long for the processor to overlap one
    # station's chain with the next (measured: the pass 31 % faster split in three, same numbers)
    for s in range(nsv):
        work[W_ALPHA + s] = atan2(work[W_WN + s], work[W_UC + s])
    for s in range(nsv):
        cell, frac, aw = table_position(work[W_ALPHA + s], af_alpha0, af_dalpha, n_af)
        work[W_CELL + s] = cell; work[W_FRAC + s] = frac; work[W_ALPHA + s] = aw
    for s in range(nsv):
        dy[a0 + 2 * s] = work[W_LAG1 + s]; dy[a0 + 2 * s + 1] = work[W_LAG2 + s]
    for s in range(nsv):  # indexed loads: not vectorised
        cl, cd, cm = table_values(work[W_CELL + s], work[W_FRAC + s], m.af_cl, m.af_cd, m.af_cm)
        work[W_CL + s] = cl; work[W_CD + s] = cd; work[W_CM + s] = cm
    for s in range(nsv):
        v = work[W_V + s]; wgt = sv[SV_W, s]
        cl = work[W_CL + s] * mach_factor(work[W_ALPHA + s], v / a_sound)
        fup, ffwd, mea = section_loads(cl, work[W_CD + s], work[W_CM + s], v, work[W_WN + s], work[W_UC + s],
                                       work[W_UT + s], work[W_UP + s], work[W_THD + s], sv[SV_C, s], sv[SV_XEA, s],
                                       sv[SV_XAC, s], sv[SV_A, s], rho)
        work[W_FZ + s] = fup * wgt; work[W_FFWD + s] = ffwd * wgt; work[W_MY + s] = mea * wgt
    # rotor totals and the generalised aerodynamic forces
    for k in range(ns):
        cw[C_Q, k] = 0.0
    for s in range(nsv):
        r = sv[SV_R, s]; sp = sv[SV_SIGN, s] * sp0; cp = sv[SV_SIGN, s] * cp0
        fz = work[W_FZ + s]; ffw = work[W_FFWD + s]; my = work[W_MY + s]
        thrust += fz
        mom_s += fz * sp * r
        mom_c += fz * cp * r
        torque += r * ffw
        if s < nst:
            lagm0 += (r - r0) * ffw
        else:
            lagm1 += (r - r0) * ffw
        hforce += -ffw * sp - fz * work[W_WP + s] * cp
        b = 0 if s < nst else 1
        j = s - b * nst
        for k in range(ns):
            cw[C_Q, k] += m.shw[b, j, k] * fz + m.sht[b, j, k] * my
    # Structure and rotor speed from one Lagrangian (docs/model-equations.md):
    #   M x'' + g(x) Omega' + sum gl_b zeta_b'' = F_x = Q + Omega^2 f - (K0 + Omega^2 K2) x - C x'
    #   J(x) Omega' + sum S_b zeta_b'' + g^T x'' = torque - Omega J' - x'^T H x' - sum S_b' zeta_b'
    #   I_b zeta_b'' + S_b Omega' + gl_b^T x'' = lag moment + Omega^2 f_lag - (k_lag + Omega^2 k2_lag) zeta_b
    #                               - c zeta_b' - Omega S_b' - I_b' zeta_b' - x'^T HL_b x'
    # with J = I_R + 2 f^T x - x^T K2 x + 2 f_lag sum zeta - k2_lag |zeta|^2, g = g0 + H x, the
    # lag-pivot coupling gl_b = gl0_b + HL_b x and the coned blade's lag coupling S_b(x) and inertia
    # I_b(x) (plus their Coriolis forces on x), by eliminating x'' (u = M^-1 g is kept in dy[x'] and
    # ul_b = M^-1 gl_b in cw[C_UL0], cw[C_UL1] until Omega' and zeta'' are known), then the 3 x 3 system
    # of (Omega', zeta_0'', zeta_1'').
    om2 = om * om
    z0 = y[Y_ZETA0]; z1 = y[Y_ZETA0 + 1]; zd0 = y[Y_ZETAD0]; zd1 = y[Y_ZETAD0 + 1]
    fx = 0.0; xk2x = 0.0; jdot = 0.0; xhx = 0.0; uf = 0.0; ug = 0.0
    xs0x = 0.0; xs1x = 0.0; xs0xd = 0.0; xs1xd = 0.0; xi0x = 0.0; xi1x = 0.0; xi0xd = 0.0; xi1xd = 0.0
    ugl0 = 0.0; ugl1 = 0.0; l00 = 0.0; l01 = 0.0; l11 = 0.0; ul0f = 0.0; ul1f = 0.0; xhl0 = 0.0; xhl1 = 0.0
    # a mass-normalised modal basis (every reduced FEM level) has M = I: then M^-1 H = H and the
    # products with M^-1 are the vectors themselves (model.py sets P_UNIT_MASS; the guard checks it)
    unit_mass = p[P_UNIT_MASS] > 0.5
    # every product A_j x, A_j x' of the structural matrices at once (ModelArrays.xq, xqd): one pass
    # over k whose inner loop runs along a row, vectorised; each sum still adds its terms in the order
    # k = 0, 1, ..., so the numbers are those of row-by-row dot products (measured with
    # scripts/bench_kernels.py against those: right-hand side 16 % faster fem-coupled, 14 % fem-torsion)
    w_pqd = W_PQ + N_XQ * ns
    npq = (N_XQ_UNIT if unit_mass else N_XQ) * ns
    npqd = N_XQD * ns
    xq = m.xq; xqd = m.xqd
    for r in range(npq):
        work[W_PQ + r] = 0.0
    for r in range(npqd):
        work[w_pqd + r] = 0.0
    for k in range(ns):
        q = y[x0 + k]; qd = y[xd0 + k]
        for r in range(npq):
            work[W_PQ + r] += xq[k, r] * q
        for r in range(npqd):
            work[w_pqd + r] += xqd[k, r] * qd
    for i in range(ns):
        k0x = work[W_PQ + XQ_K0 * ns + i]; k2x = work[W_PQ + XQ_K2 * ns + i]
        hx = work[W_PQ + XQ_GYH * ns + i]
        s0x = work[W_PQ + XQ_LS0 * ns + i]; s1x = work[W_PQ + XQ_LS1 * ns + i]
        i0x = work[W_PQ + XQ_LI0 * ns + i]; i1x = work[W_PQ + XQ_LI1 * ns + i]
        h0x = work[W_PQ + XQ_GLH0 * ns + i]
        cxd = work[w_pqd + XQD_C * ns + i]; hxd = work[w_pqd + XQD_GYH * ns + i]
        h0xd = work[w_pqd + XQD_GLH0 * ns + i]
        ux = work[W_PQ + XQ_UGYH * ns + i]; v0x = work[W_PQ + XQ_UGLH0 * ns + i]
        if unit_mass:
            ux = hx; v0x = h0x
        # blade 1's parts from the totals (glh[0] + glh[1] = gyh, uglh[0] + uglh[1] = ugyh)
        h1x = hx - h0x; h1xd = hxd - h0xd; v1x = ux - v0x
        # flap-lag Coriolis: -d/dx of Omega S_b(x) zeta_b' + 1/2 I_b(x) zeta_b'^2
        f = cw[C_Q, i] + om2 * (m.sf[i] - k2x) - k0x - cxd - om * (zd0 * s0x + zd1 * s1x) \
            - zd0 * zd0 * i0x - zd1 * zd1 * i1x
        cw[C_F, i] = f
        qi = y[x0 + i]; qdi = y[xd0 + i]
        u = m.ugy0[i] + ux
        dy[xd0 + i] = u
        ul0 = m.ugl0[0, i] + v0x; ul1 = m.ugl0[1, i] + v1x
        cw[C_UL0, i] = ul0
        cw[C_UL1, i] = ul1
        gl0i = m.gl0[0, i] + h0x; gl1i = m.gl0[1, i] + h1x
        fx += m.sf[i] * qi
        xk2x += qi * k2x
        jdot += (m.sf[i] - k2x) * qdi
        xhx += qdi * hxd
        uf += u * f
        ug += u * (m.gy0[i] + hx)
        ugl0 += u * gl0i; ugl1 += u * gl1i
        l00 += ul0 * gl0i; l01 += ul0 * gl1i; l11 += ul1 * gl1i
        ul0f += ul0 * f; ul1f += ul1 * f
        xhl0 += qdi * h0xd; xhl1 += qdi * h1xd
        xs0x += qi * s0x; xs1x += qi * s1x; xs0xd += qdi * s0x; xs1xd += qdi * s1x
        xi0x += qi * i0x; xi1x += qi * i1x; xi0xd += qdi * i0x; xi1xd += qdi * i1x
    # rotor speed and lag: S_b = S - x^T S2_b x / 2, I_b = I_z - x^T I2_b x
    k2lag = p[P_K2LAG]
    klag = p[P_KLAG] + om2 * k2lag
    clag = p[P_CLAG]
    sl0 = p[P_SLAG] - 0.5 * xs0x; sl1 = p[P_SLAG] - 0.5 * xs1x
    il0 = p[P_ILAG] - xi0x; il1 = p[P_ILAG] - xi1x
    flag = om2 * p[P_FLAG]
    # with S_b' = -x^T S2_b x', I_b' = -2 x^T I2_b x'
    f1 = lagm0 + flag - klag * z0 - clag * zd0 + om * xs0xd + 2.0 * xi0xd * zd0 - xhl0
    f2 = lagm1 + flag - klag * z1 - clag * zd1 + om * xs1xd + 2.0 * xi1xd * zd1 - xhl1
    # lag block after eliminating x'': A [zeta0'', zeta1''] = b - c Omega'
    a11 = il0 - l00; a12 = -l01; a22 = il1 - l11
    b1 = f1 - ul0f; b2 = f2 - ul1f
    c1 = sl0 - ugl0; c2 = sl1 - ugl1
    det = a11 * a22 - a12 * a12
    dy[Y_PSI] = om
    if p[P_HOLD_OMEGA] > 0.5:
        omd = 0.0
    else:
        jpol = p[P_IR] + 2.0 * fx - xk2x + 2.0 * p[P_FLAG] * (z0 + z1) - k2lag * (z0 * z0 + z1 * z1)
        jdot = 2.0 * jdot + 2.0 * p[P_FLAG] * (zd0 + zd1) - 2.0 * k2lag * (z0 * zd0 + z1 * zd1)
        f0 = torque - om * jdot - xhx + xs0xd * zd0 + xs1xd * zd1
        # Schur complement of the lag block: c^T A^-1 b and c^T A^-1 c
        cab = (c1 * (a22 * b1 - a12 * b2) + c2 * (a11 * b2 - a12 * b1)) / det
        cac = (c1 * (a22 * c1 - a12 * c2) + c2 * (a11 * c2 - a12 * c1)) / det
        omd = (f0 - uf - cab) / (jpol - ug - cac)
    dy[Y_OMEGA] = omd
    r1 = b1 - c1 * omd; r2 = b2 - c2 * omd
    zdd0 = (a22 * r1 - a12 * r2) / det
    zdd1 = (a11 * r2 - a12 * r1) / det
    dy[Y_ZETAD0] = zdd0
    dy[Y_ZETAD0 + 1] = zdd1
    for i in range(ns):
        acc = cw[C_F, i]
        if not unit_mass:
            acc = 0.0
            for k in range(ns):
                acc += m.minv[i, k] * cw[C_F, k]
        dy[x0 + i] = y[xd0 + i]
        dy[xd0 + i] = acc - dy[xd0 + i] * omd - cw[C_UL0, i] * zdd0 - cw[C_UL1, i] * zdd1
    dy[Y_ZETA0] = zd0
    dy[Y_ZETA0 + 1] = zd1
    # vehicle descent and inflow
    fvert = thrust * ca - hforce * sa
    fhoriz = thrust * sa + hforce * ca
    area = math.pi * R * R
    if vacuum:  # no air: inflow, lag states and descent rate frozen
        vm = 0.0
        for i in range(N_Y_FIXED + 2 * ns, y.shape[0]):
            dy[i] = 0.0
        dy[Y_V0] = 0.0
        dy[Y_VD] = 0.0
    else:
        dy[Y_VD] = 0.0 if p[P_HOLD_VD] > 0.5 else p[P_G] - fvert / p[P_MASS]
        vm = mass_flow(thrust, vx, -vup, y[Y_V0], rho, area)
        if p[P_INFLOW3] > 0.5:
            inflow_harmonics(y, dy, thrust, mom_s, mom_c, vx, vup, vm, rho, R)
        else:
            dy[Y_V0] = (thrust - 2.0 * rho * area * vm * y[Y_V0]) * 3.0 / (8.0 * rho * R * R * R)
    loads[L_THRUST] = thrust; loads[L_TORQUE] = torque; loads[L_HFORCE] = hforce
    loads[L_FVERT] = fvert; loads[L_FHORIZ] = fhoriz; loads[L_VM] = vm


@kernel
def inflow_harmonics(y, dy, thrust, mom_s, mom_c, vx, vup, vm, rho, R):
    """Peters-HaQuang three-state inflow ``v0 + (r/R)(v_s sin psi + v_c cos psi)`` [m/s].

    Dimensional form of ``M lambda' + V L^-1 lambda = (C_T, C_L, C_M)``: apparent masses
    ``(8/3) rho R^3`` and ``(16/45) rho R^4``, ``L`` of Pitt-Peters with the wake skew angle
    ``chi = atan(|V_x| / |V_c - v0|)`` (``L11 = 1/2``, ``L22 = 4/(1+cos chi)``,
    ``L33 = 4 cos chi/(1+cos chi)``, ``L13 = 15 pi/64 tan(chi/2)``), and every row scaled by the
    mass-flow parameter ``vm`` of :func:`mass_flow` (so the mean inflow keeps the turbulent-wake
    curve; in axial flight the v0 equation is the uniform model's). The (v0, v_c) block of L is
    ``[[1/2, -L13], [L13, L33]]`` in these signs (thrust alone gives Pitt-Peters' longitudinal
    gradient ``v_c = (15 pi/32) tan(chi/2) v0``, more inflow at the rear), which stays regular for
    every skew angle. Forcing: thrust and the
    first moments of the normal force about the azimuth axes (``mom_s`` towards psi = 90 deg,
    ``mom_c`` towards psi = 0, the tail), so more lift on one side makes more inflow there."""
    ih = y.shape[0] - 2
    v0 = y[Y_V0]; vs = y[ih]; vc = y[ih + 1]
    chi = math.atan2(abs(vx), abs(vup - v0) + 1e-9)
    cchi = math.cos(chi)
    l11 = 0.5; l13 = 15.0 * math.pi / 64.0 * math.tan(0.5 * chi)
    l22 = 4.0 / (1.0 + cchi); l33 = 4.0 * cchi / (1.0 + cchi)
    det = l11 * l33 + l13 * l13  # [[l11, -l13], [l13, l33]]^-1 = [[l33, l13], [-l13, l11]] / det
    i11 = l33 / det; i13 = l13 / det; i31 = -l13 / det; i33 = l11 / det
    a_r = math.pi * rho * R * R
    dy[Y_V0] = (thrust - a_r * vm * (i11 * v0 + i13 * vc)) * 3.0 / (8.0 * rho * R * R * R)
    m_h = 16.0 / 45.0 * rho * R * R * R * R
    dy[ih] = (mom_s - a_r * R * vm * vs / l22) / m_h
    dy[ih + 1] = (mom_c - a_r * R * vm * (i31 * v0 + i33 * vc)) / m_h


@kernel
def steady_wagner_states(y, m):
    """Set the Wagner lag states to their steady values A_k * w_n for the current state."""
    nst = int(m.p[P_NST]); ns = int(m.p[P_NS])
    a0 = N_Y_FIXED + 2 * ns
    vx, vup = free_stream(y, m)
    hs, hc = inflow_gradients(y, m)
    for b in range(2):
        sgn = 1.0 - 2.0 * b  # blade 1 at psi + pi, as in rhs
        sp = sgn * math.sin(y[Y_PSI]); cp = sgn * math.cos(y[Y_PSI])
        for j in range(nst):
            ut, up, theta, thd, wp, w, th = station_kinematics(y, m, b, j, vx, vup, sp, cp, hs, hc)
            v, wn, uc, d1, d2 = section_flow(ut, up, theta, thd, m.st[j, S_C], m.st[j, S_XEA], 0.0, 0.0, False)
            ia = a0 + 2 * (b * nst + j)
            y[ia] = A1 * wn
            y[ia + 1] = A2 * wn


@kernel
def station_loads(y, m, out):
    """Spanwise distributions for both blades into ``out`` (2, n_st, 5): normal force [N/m],
    torque per length about the shaft [N m/m], pitching moment about the EA [N m/m],
    elastic twist [rad] and flap displacement [m]."""
    p = m.p
    nst = int(p[P_NST]); ns = int(p[P_NS])
    a0 = N_Y_FIXED + 2 * ns
    theo = p[P_AERO] > 0.5 and p[P_QUASI_STATIC] < 0.5
    vx, vup = free_stream(y, m)
    hs, hc = inflow_gradients(y, m)
    for b in range(2):
        sgn = 1.0 - 2.0 * b  # blade 1 at psi + pi, as in rhs
        sp = sgn * math.sin(y[Y_PSI]); cp = sgn * math.cos(y[Y_PSI])
        for j in range(nst):
            ut, up, theta, thd, wp, w, th = station_kinematics(y, m, b, j, vx, vup, sp, cp, hs, hc)
            ia = a0 + 2 * (b * nst + j)
            fup, ffwd, mea, d1, d2 = station_aero(ut, up, theta, thd, m.st[j, S_C], m.st[j, S_XEA],
                                                  m.st[j, S_XAC], m.st[j, S_A], y[ia], y[ia + 1], theo,
                                                  p[P_RHO], p[P_A_SOUND], m.af_alpha0, m.af_dalpha,
                                                  m.af_cl, m.af_cd, m.af_cm)
            out[b, j, 0] = fup
            out[b, j, 1] = ffwd * m.st[j, S_R]
            out[b, j, 2] = mea
            out[b, j, 3] = th
            out[b, j, 4] = w


@inline_kernel
def record_row(t, y, m, loads, row):
    """One history row (columns HISTORY_COLUMNS) for state ``y`` at time ``t``. Inlined into
    :func:`advance`, which records every step at the rigid level's step: an out-of-line call with
    its arrays cost 1 us of a 3.6 us step."""
    ns = int(m.p[P_NS])
    x0 = N_Y_FIXED
    row[0] = t; row[1] = y[Y_PSI]; row[2] = y[Y_OMEGA]
    beta = 0.0; fl0 = 0.0; fl1 = 0.0; tw0 = 0.0; tw1 = 0.0
    for k in range(ns):
        q = y[x0 + k]
        beta += m.teeter[k] * q
        fl0 += m.tip[0, 0, k] * q; tw0 += m.tip[0, 1, k] * q
        fl1 += m.tip[1, 0, k] * q; tw1 += m.tip[1, 1, k] * q
    row[3] = beta; row[4] = tw0; row[5] = tw1; row[6] = fl0; row[7] = fl1
    row[8] = y[Y_VD]; row[9] = y[Y_V0]; row[10] = loads[L_THRUST]; row[11] = loads[L_TORQUE]
    row[12] = y[Y_ZETA0]; row[13] = y[Y_ZETA0 + 1]; row[14] = loads[L_FVERT]; row[15] = loads[L_FHORIZ]


#: the oscillators' frequencies follow the rotor speed, rounded to this bin [rad/s]: a function of
#: the state alone, so a run in chunks takes the steps of one long run, bit for bit
OSCILLATOR_OMEGA_BIN = 0.02
#: the Wagner decay's reference section speed is at least this [m/s] (a rotor at rest)
LAG_SPEED_FLOOR = 1.0
#: the Wagner decays follow the rotor speed in coarser bins [rad/s] (0.25 rad/s off is 1 m/s of
#: section speed at a 4 m tip, which RK4 takes with the rest), so that a run whose rotor speed
#: ripples by more than the oscillators' bin does not make their 4 n_st exponentials at every step
LAG_OMEGA_BIN = 0.5


@inline_kernel
def oscillator_tables(m, om, dt, w2, cr, sw, ws):
    """The half-step flow of ``x_i'' = -w_i^2 x_i``, ``w_i^2 = k0_ii + om^2 k2_ii`` (>= 0)."""
    for i in range(w2.shape[0]):
        w2[i] = max(m.k0[i, i] + om * om * m.k2[i, i], 0.0)
        w = math.sqrt(w2[i])
        if w * dt > 1e-12:
            cr[i] = math.cos(0.5 * dt * w); sw[i] = math.sin(0.5 * dt * w) / w; ws[i] = w * math.sin(0.5 * dt * w)
        else:
            cr[i] = 1.0; sw[i] = 0.5 * dt; ws[i] = 0.0


@inline_kernel
def lag_tables(m, om, dt, lam, inv_lam, e2):
    """The Wagner states' decay rates ``lam = 2 B_k max(|om| r, LAG_SPEED_FLOOR) / c`` [1/s] (the
    section speed of the rotation alone), their inverses and their half-step flow ``exp(-lam dt/2)``."""
    for s in range(lam.shape[0] // 2):
        base = 2.0 * max(abs(om) * m.sv[SV_R, s], LAG_SPEED_FLOOR) / m.sv[SV_C, s]
        lam[2 * s] = B1 * base; lam[2 * s + 1] = B2 * base
    for i in range(lam.shape[0]):
        inv_lam[i] = 1.0 / lam[i]
        e2[i] = math.exp(-0.5 * dt * lam[i])


@inline_kernel
def lag_start(out, y, k1, a0, inv_lam, lz, e2):
    """The Wagner rows of Lawson's step, in the rows' own terms: about their rest ``ybar = y - z``
    under the step's first forces, ``z = -f(y) / lam`` (so N1 = 0), with E2 = ``e2`` the stages are
    Z2 = E2 z, Z3 = E2 z + h/2 N2, Z4 = E2 (E2 z + h N3), z+ = E2 (E2 z + h/3 (N2 + N3)) + h/6 N4,
    and N = f(ybar + Z) + lam Z. Here: ``z`` into ``lz``, the rows of Y2 into ``out``."""
    for i in range(lz.shape[0]):
        j = a0 + i
        z = -k1[j] * inv_lam[i]
        lz[i] = z
        out[j] = y[j] - z + e2[i] * z


@inline_kernel
def lag_stage(stage, out, y, a0, lam, lz, e2, h, k, n2, n3):
    """After stage ``stage`` (2, 3, 4) has put ``f`` into ``k``: its N in the Wagner rows (``n2``,
    ``n3``: the N of stages 2 and 3, as far as known), and the rows of the next point (Y3, Y4; after
    stage 4 the step's end) into ``out`` (:func:`lag_start`)."""
    for i in range(lz.shape[0]):
        j = a0 + i; z = lz[i]; a = e2[i]
        if stage == 2:
            k[j] += lam[i] * a * z
            out[j] = y[j] - z + a * z + 0.5 * h * k[j]
        elif stage == 3:
            k[j] += lam[i] * (a * z + 0.5 * h * n2[j])
            out[j] = y[j] - z + a * (a * z + h * k[j])
        else:
            k[j] += lam[i] * a * (a * z + h * n3[j])
            out[j] = y[j] - z + a * (a * z + h / 3.0 * (n2[j] + n3[j])) + h / 6.0 * k[j]


@inline_kernel
def rotate_modes(v, x0, xd0, ns, cr, sw, ws):
    """``v``'s modal pairs (x_i, x_i') advanced by the exact flow of ``x_i'' = -w_i^2 x_i`` over the
    step the tables were made for: ``cr = cos(w h)``, ``sw = sin(w h) / w``, ``ws = w sin(w h)``."""
    for i in range(ns):
        a = v[x0 + i]; b = v[xd0 + i]
        v[x0 + i] = cr[i] * a + sw[i] * b
        v[xd0 + i] = cr[i] * b - ws[i] * a


@inline_kernel
def without_oscillators(z, k, x0, xd0, ns, w2):
    """``k = f(y)`` becomes ``f(y) - L z`` (``z = y - xbar``): the part of the right-hand side the
    oscillators leave."""
    for i in range(ns):
        k[x0 + i] = 0.0  # f's x rows are x' exactly: all of them is L z
        k[xd0 + i] += w2[i] * z[x0 + i]


@inline_kernel
def stage_rhs(zt, k, m, loads, work, cw, x0, xd0, ns, w2, xbar):
    """``k = f(zt + xbar) - L zt``, ``zt`` left as it was."""
    for i in range(ns):
        zt[x0 + i] += xbar[i]
    rhs(zt, k, m, loads, work, cw)
    for i in range(ns):
        zt[x0 + i] -= xbar[i]
    without_oscillators(zt, k, x0, xd0, ns, w2)


@kernel
def advance(y, t0, dt, n_steps, record_every, m, hist, states, omega_floor):
    """RK4 for ``n_steps`` from time ``t0``; every ``record_every`` steps a history row and the full
    state are written. Returns (steps done, rows written, status): status 0 ok, 1 non-finite state
    or a numerically impossible jump of the rotor speed in one step,
    2 rotor speed below ``omega_floor``. ``y`` is advanced in place.

    With ``p[P_LAWSON] > 0`` (a mass-normalised modal basis) the step is Lawson's
    integrating-factor RK4 (Hochbruck & Ostermann, Acta Numerica 2010, sec. 2.6): the modal
    oscillators ``L: x_i'' = -w_i^2 x_i``, ``w_i^2 = k0_ii + Omega^2 k2_ii`` (the diagonal of the
    stiffness at the rotor speed, in bins of :data:`OSCILLATOR_OMEGA_BIN`), are integrated exactly
    about their static deflection under the step's other forces (so a fixed point of ``f`` stays
    one), and RK4 integrates the rest in their frame: the explicit step no longer follows the
    stiffest retained mode. The method is fourth order for any ``w_i``; what RK4 must resolve is
    the rest (the stiffness off the diagonal, inertial coupling, aerodynamics).

    With ``p[P_LAWSON_LAGS] > 0``, in axial flight (no airspeed), at every level: the Wagner states'
    decay ``x_k' = -lam_k x_k``, ``lam_k = 2 B_k Omega r / c`` at the rotation's section speed (in the
    same rotor-speed bins), is integrated exactly too, about the states' rest under the step's first
    forces (:func:`lag_start`), and RK4 keeps the rest, ``2 B_k (v - Omega r) / c``: the step is no
    longer bound by the fastest lag state at the tip (:func:`amra_core.model.stable_time_step`)."""
    n = y.shape[0]
    ns = int(m.p[P_NS])
    x0 = N_Y_FIXED; xd0 = N_Y_FIXED + ns
    k1 = np.empty(n); k2 = np.empty(n); k3 = np.empty(n); k4 = np.empty(n); yt = np.empty(n); u = np.empty(n)
    loads = np.zeros(8); work, cw = new_work(m)
    osc = m.p[P_LAWSON] > 0.5
    theo = m.p[P_AERO] > 0.5 and m.p[P_QUASI_STATIC] < 0.5 and m.p[P_VACUUM] < 0.5
    nl = 4 * int(m.p[P_NST]) if m.p[P_LAWSON_LAGS] > 0.5 and theo and m.p[P_VH] <= 0.0 else 0
    a0 = N_Y_FIXED + 2 * ns
    w2 = np.zeros(ns); xbar = np.zeros(ns); cr = np.ones(ns); sw = np.full(ns, 0.5 * dt); ws = np.zeros(ns)
    lam = np.ones(nl); inv_lam = np.ones(nl); e2 = np.ones(nl); lz = np.zeros(nl)
    om_l = math.nan  #: the rotor speed the oscillator tables are for (none yet)
    om_g = math.nan  #: and the Wagner tables
    h = dt
    rows = 0
    status = 0
    done = 0
    for s in range(n_steps):
        rhs(y, k1, m, loads, work, cw)
        if s % record_every == 0 and rows < hist.shape[0]:
            record_row(t0 + s * dt, y, m, loads, hist[rows])
            for i in range(n):
                states[rows, i] = y[i]
            rows += 1
        om_old = y[Y_OMEGA]
        finite = True
        if osc:
            om_bin = OSCILLATOR_OMEGA_BIN * round(y[Y_OMEGA] / OSCILLATOR_OMEGA_BIN)
            if om_bin != om_l:
                om_l = om_bin
                oscillator_tables(m, om_l, dt, w2, cr, sw, ws)
        if nl > 0:
            om_bin = LAG_OMEGA_BIN * round(y[Y_OMEGA] / LAG_OMEGA_BIN)
            if om_bin != om_g:
                om_g = om_bin
                lag_tables(m, om_g, dt, lam, inv_lam, e2)
        if osc:
            # about the modes' static deflection xbar under this step's other forces (so a fixed
            # point of f stays one): z = y - xbar, E = exp(hL), E2 = exp(hL/2), N = f - L z:
            # Z2 = E2 (z + h/2 k1), Z3 = E2 z + h/2 k2, Z4 = E2 (E2 z + h k3),
            # z+ = E2 (E2 (z + h/6 k1) + h/3 (k2 + k3)) + h/6 k4 (= E z + h/6 (E k1 + 2 E2 (k2 + k3) + k4))
            for i in range(ns):
                xbar[i] = (k1[xd0 + i] + w2[i] * y[x0 + i]) / w2[i] if w2[i] > 0.0 else 0.0
                y[x0 + i] -= xbar[i]
            without_oscillators(y, k1, x0, xd0, ns, w2)
            for i in range(n):
                yt[i] = y[i] + 0.5 * h * k1[i]
            rotate_modes(yt, x0, xd0, ns, cr, sw, ws)
            lag_start(yt, y, k1, a0, inv_lam, lz, e2)
            stage_rhs(yt, k2, m, loads, work, cw, x0, xd0, ns, w2, xbar)
            for i in range(n):
                u[i] = y[i]
            rotate_modes(u, x0, xd0, ns, cr, sw, ws)
            for i in range(n):
                yt[i] = u[i] + 0.5 * h * k2[i]
            lag_stage(2, yt, y, a0, lam, lz, e2, h, k2, k2, k2)
            stage_rhs(yt, k3, m, loads, work, cw, x0, xd0, ns, w2, xbar)
            for i in range(n):
                yt[i] = u[i] + h * k3[i]
            rotate_modes(yt, x0, xd0, ns, cr, sw, ws)
            lag_stage(3, yt, y, a0, lam, lz, e2, h, k3, k2, k3)
            stage_rhs(yt, k4, m, loads, work, cw, x0, xd0, ns, w2, xbar)
            lag_stage(4, u, y, a0, lam, lz, e2, h, k4, k2, k3)
            for i in range(n):
                y[i] += h / 6.0 * k1[i]
            rotate_modes(y, x0, xd0, ns, cr, sw, ws)
            for i in range(n):
                y[i] += h / 3.0 * (k2[i] + k3[i])
            rotate_modes(y, x0, xd0, ns, cr, sw, ws)
            for i in range(n):
                y[i] += h / 6.0 * k4[i]
            for i in range(ns):
                y[x0 + i] += xbar[i]
        else:
            for i in range(n):
                yt[i] = y[i] + 0.5 * dt * k1[i]
            lag_start(yt, y, k1, a0, inv_lam, lz, e2)
            rhs(yt, k2, m, loads, work, cw)
            for i in range(n):
                yt[i] = y[i] + 0.5 * dt * k2[i]
            lag_stage(2, yt, y, a0, lam, lz, e2, h, k2, k2, k2)
            rhs(yt, k3, m, loads, work, cw)
            for i in range(n):
                yt[i] = y[i] + dt * k3[i]
            lag_stage(3, yt, y, a0, lam, lz, e2, h, k3, k2, k3)
            rhs(yt, k4, m, loads, work, cw)
            lag_stage(4, u, y, a0, lam, lz, e2, h, k4, k2, k3)
            for i in range(n):
                y[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
        for i in range(nl):
            y[a0 + i] = u[a0 + i]
        for i in range(n):
            if not math.isfinite(y[i]):
                finite = False
        done = s + 1
        # a quarter of the rotor speed in one step is beyond any physical torque (the rotor's
        # inertia allows ~0.1 % per step): the explicit step has left its stability region
        if abs(y[Y_OMEGA] - om_old) > 0.25 * abs(om_old) + 1.0:
            finite = False
        if not finite:
            status = 1
            break
        if y[Y_OMEGA] < omega_floor:
            status = 2
            break
    return done, rows, status


@exact_kernel
def jacobian(y0, m, J):
    """``J`` (n - 1, n - 1) = df/dy without the azimuth row and column, by central differences with
    the relative step 1e-6 (the same arithmetic as n - 1 pairs of :func:`evaluate`, in one call)."""
    n = y0.shape[0]
    work, cw = new_work(m)
    loads = np.zeros(N_LOADS)
    dy_p = np.zeros(n); dy_m = np.zeros(n)
    y = y0.copy()
    for i in range(1, n):
        h = 1e-6 * max(1.0, abs(y0[i]))
        y[i] = y0[i] + h
        rhs(y, dy_p, m, loads, work, cw)
        y[i] = y0[i] - h
        rhs(y, dy_m, m, loads, work, cw)
        y[i] = y0[i]
        for k in range(1, n):
            J[k - 1, i - 1] = (dy_p[k] - dy_m[k]) / (2 * h)


@kernel
def evaluate(y, m, dy, loads):
    """One right-hand-side evaluation (for trim residuals, Jacobians and tests)."""
    work, cw = new_work(m)
    rhs(y, dy, m, loads, work, cw)
