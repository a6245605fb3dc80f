"""Stability boundary map over CG x GJ (issues 4 and 8, paper Fig. 14), computed column by column.

For a fixed rotor, fidelity, aerodynamic model, advance ratio and elastic axis, every CG column
[chord fraction] is walked down its trim branch by :func:`amra_core.column.walk_column`: from the
stiffest blade (``gj_max``) downward in log GJ by continuation (never a cold restart on the
branch, so the windmill-brake root cannot take over), with the modes at every point and every sign
change of the largest real part, and the fold, bracketed to ``gj_rel_tol``. Below a fold the column
is probed by cold starts on the ``n_coarse`` log grid. Each point becomes a cell; verdicts:
``stable``, ``flutter``, ``divergence`` (unstable, non-oscillatory), ``overspeed`` /
``no-autorotation`` (no normal-branch trim: below a fold where the rotor speed was rising /
falling), ``windmill-brake`` (an equilibrium with V_c/v_h beyond the turbulent-wake region: not
autorotation, never counted stable) and ``failed`` (a numerical failure or a crashed worker).

Progression: one task per column (the columns run in parallel on the executor); with the
in-process serial executor (``workers=1``) the cells of a column are handed out as each point is
found, with a pool when the column is finished. ``on_cell``/:func:`iter_map` hand out every cell;
a ``threading.Event`` ``cancel`` is checked between cells (and at least every 0.1 s) and a
cancelled map returns what it has. With a :class:`~amra_core.store.CellStore`, finished columns are
kept (each cell under its case key as before; the cell at ``gj_max`` also carries the column record:
the walk's GJ values and intervals), so a repeated map is read back at once; an interrupted map
resumes with the columns it had not finished (a column walk restarts from its top: continuation needs
the trimmed states, which the store does not keep). A column whose worker crashed
(``Outcome.ok`` False) or that contains a failed cell is never stored: it is shown as failed in
that run only.

Outputs (:class:`BoundaryMap`): ``cells``; ``columns``: per column ``critical_gj`` (the *upper end*
of the final bracket: the lowest computed GJ from which the column is stable all the way up to
``gj_max``; ``None`` when stable over the whole range, ``math.inf`` when unstable at ``gj_max``),
``bracket``, ``status``, ``kind``, ``fold_gj`` and ``intervals`` (every stable / flutter / fold /
windmill-brake interval); ``boundaries``: every transition between neighbouring cells with its kind.
"""
from __future__ import annotations

from .result import BoundaryMap
from .runner import CELLS_PER_COLUMN_GUESS, MapRun, iter_map, run_map
from .spec import DEFAULT_CG, METHODS, VERDICTS, MapSpec, MapSpecError, solver_fingerprint
from .tasks import ColumnResult, ColumnTask, cell_class, cells_of_walk, compute_column, failed_cell

__all__ = ["BoundaryMap", "CELLS_PER_COLUMN_GUESS", "ColumnResult", "ColumnTask", "DEFAULT_CG", "METHODS", "MapRun",
           "MapSpec", "MapSpecError", "VERDICTS", "cell_class", "cells_of_walk", "compute_column", "failed_cell",
           "iter_map", "run_map", "solver_fingerprint"]
