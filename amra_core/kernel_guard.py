"""Checked entry points into the jitted kernels: every array shape is verified once per call.

Numba does not check bounds (unless ``NUMBA_BOUNDSCHECK=1``): a state vector one entry short, or a
``ModelArrays`` whose matrices belong to another modal basis, makes :func:`kernels.advance` read and
write past its arrays and silently corrupt the heap. The Python layer therefore calls the kernels
only through the thin wrappers here, which check, before the kernel runs (once per call, never per
time step):

* the model arrays are internally consistent (:func:`check_model_arrays`): the counts in ``p``
  (``P_NS`` structural coordinates, ``P_NST`` stations) agree with ``minv``/``k0``/``k2``/``c``
  (n_s x n_s), ``st`` (n_st x N_S_COLS), ``shw``/``shd``/``sht`` (2, n_st, n_s) and their station-major
  copies ``sv``/``kin`` (equal numbers, checked), ``tip``
  (2, 2, n_s), ``teeter`` (n_s,), ``lag_inv`` (3 x 3) and the airfoil grids;
* the state has the length the arrays imply, ``8 + 2 n_s + 4 n_st (+ 2 with three-state inflow)``;
* the output buffers (derivative, loads, history rows, recorded states) have the shapes and dtype
  the kernel writes into.

A failed check raises :class:`KernelShapeError` (a ``ValueError`` naming the array, its shape and
the shape expected). Validated model arrays are remembered by identity (the arrays inside a
``ModelArrays`` cannot change shape while it holds them), so the per-call cost in a trim's residual
loop is a few attribute lookups; the counts in ``p``, which can be edited in place, are re-checked
every call. A new ``ModelArrays`` holding the same arrays with another ``p`` (a model with changed
controls, :meth:`~amra_core.model.CompiledModel.with_controls`) is recognised by the arrays'
identity and not checked again.
"""
from __future__ import annotations

import math
import threading
from collections import OrderedDict

import numpy as np

from . import kernels
from .layout import (N_LOADS, N_P, N_S_COLS, N_SV_ROWS, N_Y_FIXED, P_LAWSON, P_LAWSON_LAGS, P_INFLOW3, P_NS, P_NST,
                     P_UNIT_MASS, STATION_STRIDE, N_XQ, N_XQD, ModelArrays, coordinate_products, station_shapes,
                     station_vectors)


class KernelShapeError(ValueError):
    """An array handed to a kernel has the wrong shape, dtype or layout for the model."""


#: id(sv) -> (the ModelArrays last seen, its arrays other than p (kept alive, compared by identity),
#: (n_s, n_st, inflow3, unit_mass))
_VALIDATED: "OrderedDict[int, tuple]" = OrderedDict()
_MAX_VALIDATED = 16
_LOCK = threading.Lock()  # kernels release the GIL: Panel sessions and thread pools call in parallel


_F64 = np.dtype(np.float64)


def _float_array(name: str, a, ndim: int) -> np.ndarray:
    if not isinstance(a, np.ndarray):
        raise KernelShapeError(f"{name} must be a numpy array, got {type(a).__name__}")
    if a.dtype is not _F64 and a.dtype != _F64:
        raise KernelShapeError(f"{name} must be float64, got {a.dtype}")
    if a.ndim != ndim:
        raise KernelShapeError(f"{name} must have {ndim} dimension(s), got shape {a.shape}")
    return a


def _shape(name: str, a, shape: tuple) -> None:
    if isinstance(a, np.ndarray) and a.shape == shape and (a.dtype is _F64 or a.dtype == _F64):
        return  # the common case, fast
    _float_array(name, a, len(shape))
    raise KernelShapeError(f"{name} has shape {a.shape}, expected {shape}")


def _counts(m: ModelArrays):
    p = m.p
    _shape("ModelArrays.p", p, (N_P,))
    ns_f, nst_f, in3, unit = p.item(P_NS), p.item(P_NST), p.item(P_INFLOW3), p.item(P_UNIT_MASS)
    if not (1.0 <= ns_f < 1e9 and ns_f == int(ns_f)):  # NaN fails the range test
        raise KernelShapeError(f"ModelArrays.p[P_NS] (structural coordinates) = {ns_f!r} must be a positive whole number")
    if not (1.0 <= nst_f < 1e9 and nst_f == int(nst_f)):
        raise KernelShapeError(f"ModelArrays.p[P_NST] (stations) = {nst_f!r} must be a positive whole number")
    for slot, name in ((P_LAWSON, "P_LAWSON"), (P_LAWSON_LAGS, "P_LAWSON_LAGS")):
        if p.item(slot) not in (0.0, 1.0):
            raise KernelShapeError(f"ModelArrays.p[{name}] = {p.item(slot)!r} must be 0 (RK4) or 1 (Lawson)")
    return int(ns_f), int(nst_f), in3 > 0.5, unit > 0.5


def check_model_arrays(m: ModelArrays) -> tuple:
    """Verify that ``m`` is internally consistent; return ``(n_s, n_st, n_y)``."""
    if not isinstance(m, ModelArrays):
        raise KernelShapeError(f"model arrays must be a ModelArrays, got {type(m).__name__}")
    ns, nst, inflow3, unit_mass = _counts(m)
    counts = (ns, nst, inflow3, unit_mass)
    with _LOCK:
        hit = _VALIDATED.get(id(m.sv))
    if hit is not None and hit[2] == counts and hit[0] is not m and all(a is b for a, b in zip(hit[1], m[1:])):
        hit = (m, hit[1], counts)  # the same arrays under another p: remembered for the fast test
        with _LOCK:
            _VALIDATED[id(m.sv)] = hit
    if hit is None or hit[0] is not m or hit[2] != counts:
        for name in ("minv", "k0", "k2", "c", "gyh", "ugyh"):
            _shape(f"ModelArrays.{name}", getattr(m, name), (ns, ns))
        for name in ("sf", "gy0", "ugy0"):
            _shape(f"ModelArrays.{name}", getattr(m, name), (ns,))
        for name in ("ls2", "li2", "glh", "uglh"):
            _shape(f"ModelArrays.{name}", getattr(m, name), (2, ns, ns))
        for name in ("gl0", "ugl0"):
            _shape(f"ModelArrays.{name}", getattr(m, name), (2, ns))
        _shape("ModelArrays.st", m.st, (nst, N_S_COLS))
        for name in ("shw", "shd", "sht"):
            _shape(f"ModelArrays.{name}", getattr(m, name), (2, nst, ns))
        if 2 * nst > STATION_STRIDE:
            raise KernelShapeError(f"{nst} stations per blade: at most {STATION_STRIDE // 2}")
        _shape("ModelArrays.sv", m.sv, (N_SV_ROWS, STATION_STRIDE))
        _shape("ModelArrays.kin", m.kin, (ns, 3 * STATION_STRIDE))
        # the station-major copies the right-hand side reads must be the same numbers as st and
        # shw/shd/sht (arrays mixed from two models would otherwise pass every shape check)
        if not np.array_equal(m.sv, station_vectors(m.st)):
            raise KernelShapeError("ModelArrays.sv is not the station table st laid out per blade")
        if not np.array_equal(m.kin, station_shapes(m.shw, m.shd, m.sht)):
            raise KernelShapeError("ModelArrays.kin is not shw, shd, sht laid out per coordinate")
        # and the side-by-side copies of the structural matrices the same numbers as the matrices
        _shape("ModelArrays.xq", m.xq, (ns, N_XQ * ns))
        _shape("ModelArrays.xqd", m.xqd, (ns, N_XQD * ns))
        xq, xqd = coordinate_products(m)
        if not (np.array_equal(m.xq, xq) and np.array_equal(m.xqd, xqd)):
            raise KernelShapeError("ModelArrays.xq, xqd are not k0, k2, c, gyh, ls2, li2, glh, ugyh, uglh "
                                   "side by side (arrays mixed from two models, or one side edited)")
        # the kernel then skips minv, ugyh and uglh: they must be what it assumes
        if unit_mass and not (np.array_equal(m.minv, np.eye(ns)) and np.array_equal(m.ugyh, m.gyh)
                              and np.array_equal(m.uglh, m.glh)):
            raise KernelShapeError("ModelArrays.p[P_UNIT_MASS] is set but minv is not the identity "
                                   "(or ugyh, uglh are not gyh, glh)")
        _shape("ModelArrays.tip", m.tip, (2, 2, ns))
        _shape("ModelArrays.teeter", m.teeter, (ns,))
        _shape("ModelArrays.lag_inv", m.lag_inv, (3, 3))
        n_af = None
        for name in ("af_cl", "af_cd", "af_cm"):
            a = _float_array(f"ModelArrays.{name}", getattr(m, name), 1)
            if n_af is None:
                n_af = a.shape[0]
            if a.shape[0] != n_af or n_af < 2:
                raise KernelShapeError(f"ModelArrays.{name} has {a.shape[0]} entries: the airfoil grids must "
                                       f"have one common length >= 2 (af_cl has {n_af})")
        if not (math.isfinite(m.af_dalpha) and m.af_dalpha > 0 and math.isfinite(m.af_alpha0)):
            raise KernelShapeError(f"ModelArrays.af_dalpha = {m.af_dalpha!r} must be a positive finite grid step")
        with _LOCK:
            _VALIDATED[id(m.sv)] = (m, tuple(m[1:]), counts)
            _VALIDATED.move_to_end(id(m.sv))
            while len(_VALIDATED) > _MAX_VALIDATED:
                _VALIDATED.popitem(last=False)
    n_y = N_Y_FIXED + 2 * ns + 4 * nst + (2 if inflow3 else 0)
    return ns, nst, n_y


def check_state(y, m: ModelArrays, name: str = "state y") -> tuple:
    """Verify ``m`` and that ``y`` is a float64 vector of the length ``m`` implies."""
    ns, nst, n_y = check_model_arrays(m)
    _shape(name, y, (n_y,))
    return ns, nst, n_y


def _loads(loads) -> None:
    _float_array("loads", loads, 1)
    if loads.shape[0] < N_LOADS:
        raise KernelShapeError(f"loads has {loads.shape[0]} entries, the kernel writes {N_LOADS}")


# --------------------------------------------------------------------------- checked wrappers
def advance(y, t0, dt, n_steps, record_every, m, hist, states, omega_floor):
    """:func:`kernels.advance` after the shape checks (see the module docstring)."""
    _, _, n_y = check_state(y, m)
    _float_array("hist", hist, 2)
    if hist.shape[1] != kernels.N_HIST:
        raise KernelShapeError(f"hist has shape {hist.shape}, expected (rows, {kernels.N_HIST})")
    _float_array("states", states, 2)
    if states.shape[1] != n_y or states.shape[0] < hist.shape[0]:
        raise KernelShapeError(f"states has shape {states.shape}, expected at least ({hist.shape[0]}, {n_y}) "
                               f"(one full state per history row)")
    n_steps, record_every = int(n_steps), int(record_every)
    if n_steps < 0 or record_every < 1:
        raise KernelShapeError(f"n_steps = {n_steps} must be >= 0 and record_every = {record_every} >= 1")
    if not (math.isfinite(dt) and dt > 0):
        raise KernelShapeError(f"dt = {dt!r} must be a positive finite time step [s]")
    return kernels.advance(y, float(t0), float(dt), n_steps, record_every, m, hist, states, float(omega_floor))


def evaluate(y, m, dy, loads):
    """:func:`kernels.evaluate` (one right-hand side) after the shape checks."""
    _, _, n_y = check_state(y, m)
    _shape("derivative dy", dy, (n_y,))
    _loads(loads)
    return kernels.evaluate(y, m, dy, loads)


def jacobian(y0, m, J):
    """:func:`kernels.jacobian` (the whole finite-difference Jacobian) after the shape checks, once."""
    _, _, n_y = check_state(y0, m)
    _shape("Jacobian J", J, (n_y - 1, n_y - 1))
    return kernels.jacobian(y0, m, J)


def station_loads(y, m, out):
    """:func:`kernels.station_loads` after the shape checks (``out`` is (2, n_st, 5))."""
    _, nst, _ = check_state(y, m)
    _shape("out", out, (2, nst, 5))
    return kernels.station_loads(y, m, out)


def record_row(t, y, m, loads, row):
    """:func:`kernels.record_row` after the shape checks (``row`` is one history row)."""
    check_state(y, m)
    _loads(loads)
    _shape("row", row, (kernels.N_HIST,))
    return kernels.record_row(float(t), y, m, loads, row)


def steady_wagner_states(y, m):
    """:func:`kernels.steady_wagner_states` after the shape checks."""
    check_state(y, m)
    return kernels.steady_wagner_states(y, m)
