"""In-vacuo natural modes of the teetering two-bladed rotor, their labels and fan plots.

The structure is the one the solver integrates (:mod:`amra_core.structure`), with the rotor speed
held constant: the flap/torsion system ``M x'' + (K0 + Omega^2 K2) x = 0`` over
``x = [beta, q_blade0, q_blade1]`` plus one rigid lead-lag angle per blade,
``I_lag zeta'' + (k_lag + Omega^2 k2_lag) zeta = 0``. The lag block is block-diagonal with the
flap/torsion system. (With the rotor speed free the collective lag mode also couples with the
rotor-speed degree of freedom through ``S_lag``; that drive-train mode is not part of this
held-speed analysis.)

Symmetry. The two blades are identical and the teeter angle moves them oppositely (blade 0 by
``+beta r``, blade 1 by ``-beta r``), so in the coordinates ``(x_0 + x_1)/sqrt 2`` (collective:
both blades move alike) and ``[beta, (x_0 - x_1)/sqrt 2]`` (cyclic: opposite) the mass and
stiffness matrices are block-diagonal. Each block is solved on its own with
:func:`scipy.linalg.eigh`; this keeps every mode purely collective or purely cyclic even where
the two families are degenerate (the two lag modes are exactly so, the two torsion modes
nearly). If the blocks ever failed to decouple (an asymmetric rotor), the whole system would be
solved and each mode classified by the larger of its collective and cyclic parts.

Labels come from the modal kinetic-energy participation ``phi_i (M phi)_i / phi^T M phi``
summed per coordinate kind (teeter, flap, torsion, lag). A teeter-dominated mode is ``teeter``;
every other mode is ``"{kind} {n} (collective)"`` or ``"{kind} {n} (cyclic)"``, ``n`` counting in
frequency order within its kind and symmetry. (The rigid tilt of the whole rotor,
``x = [1, 0, 0]``, is an exact eigenvector at every rotor speed, with ``omega = Omega``; every
other mode is mass-orthogonal to it and so has no teeter participation, hence exactly one
``teeter`` mode. Should a second teeter-dominated mode ever appear it is ``teeter 2``.)

At ``Omega = 0`` the teeter mode is the rigid-body mode with a zero eigenvalue. It is **kept** and
reported as ``teeter`` with 0 Hz (``per_rev`` is ``None`` at ``Omega = 0`` anyway): an eigenvalue
whose magnitude is below 100 machine epsilons times the largest one (round-off) is treated as
exactly zero, which is what the assembled matrices give (``K0`` has an exactly zero teeter row
and column). A negative
eigenvalue (static divergence, possible when centrifugal flap-torsion coupling overwhelms the
stiffness) is reported with a negative ``frequency_hz = -sqrt(-lambda)/(2 pi)`` so that it is
visible and sorts first.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sl
from scipy.optimize import linear_sum_assignment

from .rotor import Rotor
from .shapes import make_mesh
from .structure import assemble

KINDS = ("teeter", "flap", "torsion", "lag")
#: |lambda| below this fraction of max |lambda| counts as a zero eigenvalue: 100 machine epsilons,
#: the round-off level of a symmetric-definite eigensolver (the exact zero comes out ~1e-17 of it)
_ZERO_TOL = 100.0 * np.finfo(float).eps
_DECOUPLE_TOL = 1e-10  #: relative size of the collective/cyclic cross blocks treated as zero
_REPORT_MODES = 12


@dataclass(frozen=True)
class ModalSolution:
    """Eigen-solution of the held-speed rotor over the physical coordinates ``[x, zeta0, zeta1]``.

    ``eigenvalues`` [rad^2/s^2] ascending; ``vectors`` columns mass-normalised
    (``vectors.T @ M @ vectors = I``); ``M`` the mass and ``K`` the stiffness at this speed,
    ``K2`` the stiffness per Omega^2 (``K = K0 + Omega^2 K2``); ``symmetry`` per mode
    ``'collective'`` or ``'cyclic'``; ``kinds``/``blade_of`` per physical coordinate (lag
    coordinates are last)."""

    omega_rad_s: float
    eigenvalues: np.ndarray
    vectors: np.ndarray
    M: np.ndarray
    K: np.ndarray
    K2: np.ndarray
    symmetry: tuple
    kinds: tuple
    blade_of: tuple
    structure: object


def _resolve_rotor(rotor) -> Rotor:
    if isinstance(rotor, str):
        from .rotor_io import load_preset
        return load_preset(rotor)
    return rotor


def _full_matrices(s, omega_rad_s: float):
    """Block-diagonal (M, K, K2, kinds, blade_of) with the two lag coordinates appended."""
    n = s.n
    M = np.zeros((n + 2, n + 2))
    K0 = np.zeros((n + 2, n + 2))
    K2 = np.zeros((n + 2, n + 2))
    M[:n, :n] = s.M
    K0[:n, :n] = s.K0
    K2[:n, :n] = s.K2
    for j in (n, n + 1):
        M[j, j] = s.I_lag
        K0[j, j] = s.k_lag
        K2[j, j] = s.k2_lag
    kinds = tuple(s.kinds) + ("lag", "lag")
    blade_of = tuple(s.blade_of) + (0, 1)
    return M, K0 + omega_rad_s**2 * K2, K2, kinds, blade_of


def _symmetry_basis(kinds, blade_of):
    """Orthogonal T = [T_collective | T_cyclic] over the physical coordinates."""
    idx0 = [i for i, b in enumerate(blade_of) if b == 0]
    idx1 = [i for i, b in enumerate(blade_of) if b == 1]
    shared = [i for i, b in enumerate(blade_of) if b == -1]  # teeter: cyclic by construction
    n = len(kinds)
    h = 1.0 / np.sqrt(2.0)
    Tc = np.zeros((n, len(idx0)))
    Ts = np.zeros((n, len(idx0) + len(shared)))
    for k, (i, j) in enumerate(zip(idx0, idx1)):
        Tc[i, k] = Tc[j, k] = h
        Ts[i, k] = h
        Ts[j, k] = -h
    for k, i in enumerate(shared):
        Ts[i, len(idx0) + k] = 1.0
    return Tc, Ts


def solve_modes(rotor, fidelity: str = "fem-coupled", n_elements: int = 10,
                omega_rad_s: float = 0.0, rigid_spring: str = "frequency") -> ModalSolution:
    """Solve the held-speed in-vacuo eigenproblem (lower-level companion of :func:`natural_modes`).

    Parameters
    ----------
    rotor : Rotor or str
        Rotor description, or a preset name.
    fidelity : {"rigid", "fem-torsion", "fem-coupled"}
        Structural fidelity level (model-notes §2).
    n_elements : int
        Finite elements per blade (integration breakpoints only at the ``rigid`` level).
    omega_rad_s : float
        Rotor speed Omega [rad/s].
    rigid_spring : {"frequency", "static"}
        Root torsion spring of the ``rigid`` level (:mod:`amra_core.rigid_equivalence`).

    Returns
    -------
    ModalSolution
        Eigenvalues [rad^2/s^2] ascending and mass-normalised eigenvectors over
        ``[beta, q_blade0, q_blade1, zeta0, zeta1]``.
    """
    rotor = _resolve_rotor(rotor)
    omega = float(omega_rad_s)
    if not np.isfinite(omega) or omega < 0.0:
        raise ValueError(f"omega_rad_s = {omega_rad_s!r} is not allowed: must be finite and >= 0")
    mesh = make_mesh(fidelity, rotor.root_cutout_m, rotor.radius_m, n_elements, rigid_spring)
    s = assemble(rotor, mesh)
    M, K, K2, kinds, blade_of = _full_matrices(s, omega)
    Tc, Ts = _symmetry_basis(kinds, blade_of)
    cross = max(np.abs(Tc.T @ M @ Ts).max(), np.abs(Tc.T @ K @ Ts).max())
    scale = max(np.abs(M).max(), np.abs(K).max())
    lams, vecs, sym = [], [], []
    if cross <= _DECOUPLE_TOL * scale:
        for T, name in ((Tc, "collective"), (Ts, "cyclic")):
            w, V = sl.eigh(T.T @ K @ T, T.T @ M @ T)
            lams.append(w)
            vecs.append(T @ V)
            sym += [name] * len(w)
        lam = np.concatenate(lams)
        vec = np.hstack(vecs)
        sym = np.array(sym)
    else:  # not expected for two identical blades; classify by projection
        lam, vec = sl.eigh(K, M)
        pc = np.sum((Tc.T @ vec) ** 2, axis=0)
        ps = np.sum((Ts.T @ vec) ** 2, axis=0)
        sym = np.where(pc >= ps, "collective", "cyclic")
    order = np.argsort(lam, kind="stable")
    return ModalSolution(omega, lam[order], vec[:, order], M, K, K2, tuple(sym[order]), kinds,
                         blade_of, s)


def _frequencies_hz(lam: np.ndarray) -> np.ndarray:
    tol = _ZERO_TOL * max(np.abs(lam).max(), 1e-300)
    lam = np.where(np.abs(lam) <= tol, 0.0, lam)
    return np.sign(lam) * np.sqrt(np.abs(lam)) / (2.0 * np.pi)


def participation(sol: ModalSolution) -> dict:
    """Kinetic-energy fraction of every mode per coordinate kind.

    Returns
    -------
    dict
        ``{kind: array (n_modes,)}`` for kinds teeter, flap, torsion, lag; the fractions of a mode
        sum to 1 (individual entries may fall slightly outside [0, 1] where inertial coupling
        makes cross terms negative).
    """
    V = sol.vectors
    e = V * (sol.M @ V)  # phi_i (M phi)_i per coordinate and mode
    tot = e.sum(axis=0)
    kinds = np.array(sol.kinds)
    return {k: e[kinds == k].sum(axis=0) / tot for k in KINDS}


def mode_labels(sol: ModalSolution) -> list:
    """Labels of the modes of ``sol`` in its (ascending) order, see the module docstring."""
    part = participation(sol)
    P = np.vstack([part[k] for k in KINDS])
    dominant = [KINDS[i] for i in np.argmax(P, axis=0)]
    counts = {}
    labels = []
    for kind, sym in zip(dominant, sol.symmetry):
        if kind == "teeter":
            n = counts["teeter"] = counts.get("teeter", 0) + 1
            labels.append("teeter" if n == 1 else f"teeter {n}")
        else:
            n = counts[(kind, sym)] = counts.get((kind, sym), 0) + 1
            labels.append(f"{kind} {n} ({sym})")
    return labels


def _shape(sol: ModalSolution, j: int, n_points: int) -> dict:
    """Physical shape of mode ``j`` along both blades, normalised for plotting."""
    s = sol.structure
    mesh = s.mesh
    nq = mesh.n_q
    phi = sol.vectors[:, j]
    r = np.linspace(mesh.root_m, mesh.tip_m, n_points)
    pw, _, _, pt, _ = mesh.shapes(r)
    beta = phi[0]
    q = (phi[1:1 + nq], phi[1 + nq:1 + 2 * nq])
    zeta = phi[s.n:s.n + 2]
    w = np.array([beta * r + pw @ q[0], -beta * r + pw @ q[1]])
    th = np.array([pt @ q[0], pt @ q[1]])
    R = mesh.tip_m
    amp = max(np.abs(w).max() / R, np.abs(th).max(), np.abs(zeta).max(), abs(beta))
    cand = [w.ravel()[np.abs(w).argmax()] / R, th.ravel()[np.abs(th).argmax()],
            zeta[np.abs(zeta).argmax()], beta]
    big = max(cand, key=abs)
    scale = (1.0 / amp) * (1.0 if big >= 0 else -1.0) if amp > 0 else 1.0
    part = participation(sol)
    return {
        "r_m": r,
        "teeter_rad": float(beta * scale),
        "flap_m": w * scale,
        "twist_rad": th * scale,
        "lag_rad": zeta * scale,
        "symmetry": sol.symmetry[j],
        "energy": {k: float(part[k][j]) for k in KINDS},
        "vector": phi,
    }


def natural_modes(rotor, fidelity: str = "fem-coupled", n_elements: int = 10,
                  omega_rad_s: float = 0.0, rigid_spring: str = "frequency") -> list:
    """Natural modes of the in-vacuo rotor at a held rotor speed, sorted by frequency.

    Parameters
    ----------
    rotor : Rotor or str
        Rotor description, or a preset name (``"mccutcheon"``, ``"paper-boundary"``).
    fidelity : {"rigid", "fem-torsion", "fem-coupled"}
        Structural fidelity level (model-notes §2).
    n_elements : int
        Finite elements per blade.
    omega_rad_s : float
        Rotor speed Omega [rad/s], >= 0.
    rigid_spring : {"frequency", "static"}
        Root torsion spring of the ``rigid`` level.

    Returns
    -------
    list of dict
        One dict per mode (teeter, flap/torsion and the two lag modes), ascending in frequency:

        ``label`` : str
            ``teeter``, or ``"{kind} {n} (collective|cyclic)"`` with kind flap, torsion or lag.
        ``frequency_hz`` : float
            Natural frequency [Hz]; 0.0 for the rigid teeter mode at Omega = 0, negative for a
            statically divergent mode (see the module docstring).
        ``per_rev`` : float or None
            Frequency in multiples of the rotor speed, ``omega / Omega``; ``None`` at Omega = 0.
        ``shape`` : dict
            ``r_m`` radii [m] from the root cut-out to the tip; ``flap_m`` (2, n) blade
            displacement including the teeter contribution, ``twist_rad`` (2, n) elastic twist,
            ``lag_rad`` (2,), ``teeter_rad``; all scaled together so that the largest of
            |flap|/R, |twist|, |lag| and |teeter| is 1 (dimensionless amplitude, positive at
            that entry). Also ``symmetry``, ``energy`` (kinetic-energy fractions per kind) and
            ``vector`` (the mass-normalised eigenvector over ``[beta, q0, q1, zeta0, zeta1]``).
    """
    sol = solve_modes(rotor, fidelity, n_elements, omega_rad_s, rigid_spring)
    f = _frequencies_hz(sol.eigenvalues)
    labels = mode_labels(sol)
    n_points = 4 * max(sol.structure.mesh.n_elements, 1) + 1
    out = []
    for j in range(len(f)):
        per_rev = float(2.0 * np.pi * f[j] / sol.omega_rad_s) if sol.omega_rad_s > 0 else None
        out.append({"label": labels[j], "frequency_hz": float(f[j]), "per_rev": per_rev,
                    "shape": _shape(sol, j, n_points)})
    return out


def modes_report(rotor, fidelity: str = "fem-coupled", n_elements: int = 10,
                 omega_rad_s: float = 0.0, n_modes: int = _REPORT_MODES, rigid_spring: str = "frequency") -> dict:
    """JSON-ready summary of :func:`natural_modes` (first ``n_modes`` modes, no shapes).

    Parameters
    ----------
    rotor : Rotor or str
        Rotor description, or a preset name.
    fidelity : {"rigid", "fem-torsion", "fem-coupled"}
        Structural fidelity level.
    n_elements : int
        Finite elements per blade.
    omega_rad_s : float
        Rotor speed [rad/s].
    n_modes : int
        Number of lowest modes to list (default 12).
    rigid_spring : {"frequency", "static"}
        Root torsion spring of the ``rigid`` level.

    Returns
    -------
    dict
        ``{"rotor": name, "fidelity", "elements", "omega_rad_s", "modes": [{"label",
        "frequency_hz" (rounded to 0.001 Hz), "per_rev" (4 decimals, or None)}, ...]}``.
    """
    rotor = _resolve_rotor(rotor)
    modes = natural_modes(rotor, fidelity, n_elements, omega_rad_s, rigid_spring)[:n_modes]
    return {
        "rotor": rotor.name,
        "fidelity": fidelity,
        "elements": int(n_elements),
        "omega_rad_s": float(omega_rad_s),
        "modes": [{"label": m["label"],
                   "frequency_hz": round(m["frequency_hz"], 3),
                   "per_rev": None if m["per_rev"] is None else round(m["per_rev"], 4)}
                  for m in modes],
    }


def track_modes(vectors: list, M: np.ndarray) -> np.ndarray:
    """Follow modes across a sequence of eigen-solutions by mass-weighted modal assurance.

    Parameters
    ----------
    vectors : list of ndarray
        Eigenvector matrices (columns = modes, same number of columns everywhere), one per step,
        each mass-normalised with respect to ``M``.
    M : ndarray
        Mass matrix (the same at every step: the in-vacuo mass does not depend on Omega).

    Returns
    -------
    ndarray of int, shape (n_steps, n_modes)
        ``index[k, i]`` is the column at step ``k`` that continues mode ``i`` of step 0. Consecutive
        steps are matched by maximising the total ``|phi_i^T M phi_j|`` with
        :func:`scipy.optimize.linear_sum_assignment`, so a mode keeps its identity through
        crossings (and follows its own eigenvector through veerings).
    """
    n_steps = len(vectors)
    n = vectors[0].shape[1]
    index = np.zeros((n_steps, n), dtype=int)
    index[0] = np.arange(n)
    for k in range(1, n_steps):
        prev = vectors[k - 1][:, index[k - 1]]
        mac = np.abs(prev.T @ M @ vectors[k])
        rows, cols = linear_sum_assignment(-mac)
        index[k, rows] = cols
    return index


def fan_plot(rotor, omegas_rad_s, fidelity: str = "fem-coupled", n_elements: int = 10,
             n_modes: int = 8) -> dict:
    """Natural frequencies against rotor speed (Campbell / fan diagram), modes tracked.

    All modes are solved at every speed and followed from speed to speed with
    :func:`track_modes` (not re-sorted), so crossing and veering modes keep their identity. The
    ``n_modes`` lowest modes at the first speed are returned, labelled there.

    Parameters
    ----------
    rotor : Rotor or str
        Rotor description, or a preset name.
    omegas_rad_s : array_like
        Rotor speeds [rad/s], >= 0, in the order to follow (normally ascending and finely enough
        spaced that a mode's shape changes little between neighbours).
    fidelity : {"rigid", "fem-torsion", "fem-coupled"}
        Structural fidelity level.
    n_elements : int
        Finite elements per blade.
    n_modes : int
        Number of modes to return.

    Returns
    -------
    dict
        ``omega_rad_s`` (ndarray [rad/s]) and ``modes``: list of dicts, each with

        ``label``, ``symmetry`` : str
            Taken at the first speed.
        ``frequency_hz`` : ndarray
            Frequency [Hz] of the tracked mode at every speed.
        ``southwell`` : ndarray
            Southwell coefficient ``kappa = phi^T K2 phi`` (mass-normalised ``phi``,
            dimensionless) at every speed: ``d(omega^2)/d(Omega^2) = kappa`` along the branch
            (Hellmann-Feynman), so ``omega^2 ~ omega_0^2 + kappa Omega^2`` locally.
        ``assurance`` : ndarray
            ``|phi^T M phi_previous|`` of the match with the previous speed (1 at the first);
            values well below 1 mean the speed step is too coarse to follow the mode.
    """
    rotor = _resolve_rotor(rotor)
    omegas = np.asarray(omegas_rad_s, dtype=float).ravel()
    if omegas.size == 0:
        raise ValueError("omegas_rad_s is empty: give at least one rotor speed [rad/s]")
    sols = [solve_modes(rotor, fidelity, n_elements, w) for w in omegas]
    index = track_modes([s.vectors for s in sols], sols[0].M)
    labels = mode_labels(sols[0])
    freqs = np.array([_frequencies_hz(s.eigenvalues) for s in sols])  # (n_steps, n_all)
    n = min(int(n_modes), freqs.shape[1])
    steps = np.arange(len(omegas))
    modes = []
    for i in range(n):
        phis = [s.vectors[:, index[k, i]] for k, s in enumerate(sols)]
        kappa = np.array([p @ s.K2 @ p for p, s in zip(phis, sols)])
        mac = np.ones(len(omegas))
        for k in range(1, len(omegas)):
            mac[k] = abs(phis[k - 1] @ sols[0].M @ phis[k])
        modes.append({
            "label": labels[i],
            "symmetry": sols[0].symmetry[i],
            "frequency_hz": freqs[steps, index[:, i]],
            "southwell": kappa,
            "assurance": mac,
        })
    return {"omega_rad_s": omegas, "modes": modes}
