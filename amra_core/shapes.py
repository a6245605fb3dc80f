"""Spanwise shape functions for one blade at the three fidelity levels.

A blade's out-of-plane displacement ``w(r)`` (up positive) and elastic twist
``theta(r)`` (nose up positive) are ``w = Phi_w(r) @ q`` and ``theta = Phi_t(r) @ q``
with the blade's generalised coordinates ``q``, clamped at the root cut-out ``r0``:

* ``rigid``       q = [flap angle about a root spring at r0, uniform twist] (paper §3, Lagrange form);
* ``fem-torsion`` q = [flap angle about a root spring, nodal twist of linear torsion elements];
* ``fem-coupled`` q = [nodal (w, w') of Hermite cubic beam elements, nodal twist of linear torsion
  elements], coupled with torsion through the CG offset (see :mod:`amra_core.structure`).

Torsion uses linear (2-node) elements, the consistent form of the seed's eq. 11-12 (errata,
model-notes §3): stiffness ``GJ/l [[1,-1],[-1,1]]``; the mass matrix is the average of the
consistent ``i l/6 [[2,1],[1,2]]`` and the lumped one, which raises the frequency convergence of
linear elements from order 2 to order 4 (Hughes, *The Finite Element Method*, §9.2; tested in
``tests/core/test_structure.py``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

FIDELITIES = ("rigid", "fem-torsion", "fem-coupled")
#: root torsion springs of the ``rigid`` level (:mod:`amra_core.rigid_equivalence`)
TORSION_SPRINGS = ("frequency", "static")


@dataclass(frozen=True)
class BladeMesh:
    """Generalised-coordinate layout of one blade.

    ``nodes_m``: FE node radii from the root cut-out to the tip [m] (also used for the rigid
    level as integration breakpoints).
    """

    fidelity: str
    nodes_m: tuple
    n_flap: int  #: number of flap coordinates
    n_torsion: int  #: number of torsion coordinates
    #: root torsion spring of the ``rigid`` level: ``frequency`` | ``static``
    #: (:mod:`amra_core.rigid_equivalence`)
    torsion_spring: str = "frequency"

    @property
    def n_q(self) -> int:
        return self.n_flap + self.n_torsion

    @property
    def n_elements(self) -> int:
        return len(self.nodes_m) - 1

    @property
    def root_m(self) -> float:
        return self.nodes_m[0]

    @property
    def tip_m(self) -> float:
        return self.nodes_m[-1]

    def shapes(self, r):
        """Shape matrices at radii ``r`` [m]: (Phi_w, Phi_w', Phi_w'', Phi_t, Phi_t'),
        each of shape (len(r), n_q); primes are d/dr."""
        r = np.atleast_1d(np.asarray(r, dtype=float))
        n = len(r)
        pw = np.zeros((n, self.n_q)); dpw = np.zeros_like(pw); ddpw = np.zeros_like(pw)
        pt = np.zeros_like(pw); dpt = np.zeros_like(pw)
        r0 = self.root_m
        nodes = np.asarray(self.nodes_m)
        if self.fidelity == "fem-coupled":
            _hermite(r, nodes, pw, dpw, ddpw)
        else:  # root flap spring: rigid rotation about r0
            pw[:, 0] = r - r0
            dpw[:, 0] = 1.0
        t0 = self.n_flap
        if self.fidelity == "rigid":
            pt[:, t0] = 1.0
        else:
            _linear(r, nodes, pt[:, t0:], dpt[:, t0:])
        return pw, dpw, ddpw, pt, dpt


def _element_index(r, nodes):
    e = np.clip(np.searchsorted(nodes, r, side="right") - 1, 0, len(nodes) - 2)
    l = nodes[e + 1] - nodes[e]
    xi = (r - nodes[e]) / l
    return e, l, xi


def _linear(r, nodes, pt, dpt):
    """Linear torsion elements; node 0 (root) clamped, columns = nodes 1..N."""
    e, l, xi = _element_index(r, nodes)
    rows = np.arange(len(r))
    left, right = e - 1, e  # column of node e is e-1 (node 0 has no column)
    m = left >= 0
    pt[rows[m], left[m]] += 1.0 - xi[m]
    dpt[rows[m], left[m]] += -1.0 / l[m]
    pt[rows, right] += xi
    dpt[rows, right] += 1.0 / l


def _hermite(r, nodes, pw, dpw, ddpw):
    """Hermite cubic beam elements; root node clamped (w = w' = 0), columns (w_i, w'_i), i = 1..N."""
    e, l, x = _element_index(r, nodes)
    rows = np.arange(len(r))
    # standard Hermite polynomials in xi and their derivatives wrt r
    N = [1 - 3 * x**2 + 2 * x**3, l * (x - 2 * x**2 + x**3), 3 * x**2 - 2 * x**3, l * (-x**2 + x**3)]
    dN = [(-6 * x + 6 * x**2) / l, 1 - 4 * x + 3 * x**2, (6 * x - 6 * x**2) / l, -2 * x + 3 * x**2]
    ddN = [(-6 + 12 * x) / l**2, (-4 + 6 * x) / l, (6 - 12 * x) / l**2, (-2 + 6 * x) / l]
    cols = [2 * (e - 1), 2 * (e - 1) + 1, 2 * e, 2 * e + 1]
    for k in range(4):
        c = cols[k]
        m = c >= 0
        pw[rows[m], c[m]] += N[k][m]
        dpw[rows[m], c[m]] += dN[k][m]
        ddpw[rows[m], c[m]] += ddN[k][m]


def make_mesh(fidelity: str, root_m: float, tip_m: float, n_elements: int = 10,
              torsion_spring: str = "frequency") -> BladeMesh:
    """Uniform mesh of ``n_elements`` from the root cut-out to the tip; ``torsion_spring``: the
    ``rigid`` level's root torsion spring (``frequency`` or ``static``, ignored by the FEM levels)."""
    if torsion_spring not in TORSION_SPRINGS:
        raise ValueError(f"rigid_spring = {torsion_spring!r} is not allowed: choose one of {', '.join(TORSION_SPRINGS)}")
    if fidelity not in FIDELITIES:
        raise ValueError(f"fidelity = {fidelity!r} is not allowed: choose one of {', '.join(FIDELITIES)}")
    if not (isinstance(n_elements, int) and 1 <= n_elements <= 200):
        raise ValueError(f"elements = {n_elements!r} is not allowed: must be an integer in [1, 200]")
    nodes = tuple(np.linspace(root_m, tip_m, n_elements + 1))
    if fidelity == "rigid":
        return BladeMesh(fidelity, nodes, 1, 1, torsion_spring)
    if fidelity == "fem-torsion":
        return BladeMesh(fidelity, nodes, 1, n_elements)
    return BladeMesh(fidelity, nodes, 2 * n_elements, n_elements)
