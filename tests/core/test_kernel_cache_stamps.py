"""Numba's on-disk cache knows only a function's own file: machine code that inlines or calls a
kernel from another module (trim_kernels calls kernels.evaluate; kernels inlines the atan2, sincos
and airfoil kernels) is loaded unchanged after that other module changes, and computes with the old
code. A stale Newton kernel of this kind once "trimmed" a fem-torsion rotor to a state whose
residual was 400 (caught while the station loops were rewritten). So every jitted module carries
``CACHE_STAMP``, a hash of the amra_core modules it imports: changing one of them fails this test
until the stamp is updated, which changes the importing file and so invalidates its cache."""
import ast
import hashlib
import re
from pathlib import Path

import pytest

CORE = Path(__file__).resolve().parents[2] / "amra_core"
JITTED = sorted(p for p in CORE.glob("*.py")
                if re.search(r"^@(kernel|inline_kernel|exact_kernel)\b", p.read_text(), re.M))


def _imported_core_modules(path: Path) -> list:
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.level == 1:
            if node.module:
                names.add(node.module.split(".")[0])
            else:
                names.update(a.name for a in node.names)
    return sorted(names)


def expected_stamp(path: Path) -> str:
    h = hashlib.sha256()
    for name in _imported_core_modules(path):
        h.update(name.encode() + b"\0" + (CORE / f"{name}.py").read_bytes())
    return h.hexdigest()[:16]


def _stamp_in(path: Path):
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", "") == "CACHE_STAMP" for t in node.targets):
            return node.value.value
    return None


def test_the_jitted_modules_are_the_expected_ones():
    assert {p.name for p in JITTED} >= {"kernels.py", "trim_kernels.py", "airfoil_kernel.py", "atan2_kernel.py",
                                         "sincos_kernel.py"}


@pytest.mark.parametrize("path", JITTED, ids=lambda p: p.name)
def test_every_jitted_module_stamps_the_modules_it_imports(path):
    want = expected_stamp(path)
    assert _stamp_in(path) == want, (
        f"amra_core/{path.name}: set CACHE_STAMP = \"{want}\" (a module it imports, "
        f"{', '.join(_imported_core_modules(path))}, changed: without a new stamp Numba keeps loading "
        f"machine code compiled with the old one)")


_SAME_BITS = """
import sys
import numpy as np
from amra_core import kernel_guard, kernels
from amra_core.flight import FlightCondition, SolverSettings
from amra_core.model import compile_model
from amra_core.rotor_io import load_preset
out = {}
for fid in ("rigid", "fem-coupled"):
    m = compile_model(load_preset("mccutcheon"), FlightCondition(mu=0.1), SolverSettings(fid))
    y = np.zeros(m.n_y); y[1] = 38.0; y[2] = 9.0; y[3] = 4.0
    y[4:] += np.random.default_rng(0).normal(0, 0.01, m.n_y - 4)
    dy = np.zeros(m.n_y); kernel_guard.evaluate(y.copy(), m.arrays, dy, np.zeros(8))
    ya = y.copy(); h = np.zeros((51, kernels.N_HIST)); st = np.zeros((51, m.n_y))
    kernel_guard.advance(ya, 0.0, 1e-3, 50, 1, m.arrays, h, st, 1.0)
    J = np.zeros((m.n_y - 1, m.n_y - 1)); kernel_guard.jacobian(y.copy(), m.arrays, J)
    out[fid] = np.concatenate([dy, ya, J.ravel()])
np.savez(sys.argv[1], **out)
"""


def test_code_compiled_in_a_process_and_loaded_from_the_cache_give_the_same_bits(tmp_path):
    """A map in a process pool (workers load the kernels from the cache) must equal the serial map
    (the kernels JIT-compiled in this process): the first of two processes compiles into an empty
    cache, the second loads from it, and the right-hand side, a march and the Jacobian agree bit
    for bit. (With LLVM's ``contract`` flag they did not: see amra_core/jit.py.)"""
    import os
    import subprocess
    import sys

    import numpy as np

    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    for name in ("compiled", "cached"):
        subprocess.run([sys.executable, "-c", _SAME_BITS, str(tmp_path / f"{name}.npz")], env=env, check=True,
                       timeout=600, cwd=CORE.parent)
    a, b = np.load(tmp_path / "compiled.npz"), np.load(tmp_path / "cached.npz")
    for fid in a.files:
        assert np.array_equal(a[fid], b[fid]), f"{fid}: {np.abs(a[fid] - b[fid]).max():.3g}"
