"""The import contract of ``amra_core`` (issue 21 §8), read from the sources (no import runs):

* ``amra_core`` never imports the dashboard (``app``) or its frameworks (Panel, HoloViews, Bokeh, param),
  at module level or inside a function;
* the jitted core imports only the array layout and the jit policy (and other jitted modules):
  ``kernels`` -> ``layout``, ``jit``, ``airfoil_kernel``; ``airfoil_kernel`` -> ``jit``;
  ``trim_kernels`` -> ``kernels``, ``jit``; ``layout`` and ``jit`` -> nothing of AMRA;
* no import circles among the modules' top-level imports.
"""
from __future__ import annotations

import ast
from pathlib import Path

import amra_core

ROOT = Path(amra_core.__file__).resolve().parent
FORBIDDEN = ("app", "panel", "holoviews", "bokeh", "param")
KERNEL_DEPS = {
    "amra_core.kernels": {"amra_core.layout", "amra_core.jit", "amra_core.airfoil_kernel", "amra_core.atan2_kernel",
                          "amra_core.sincos_kernel"},
    "amra_core.airfoil_kernel": {"amra_core.jit"},
    "amra_core.atan2_kernel": {"amra_core.jit"},
    "amra_core.sincos_kernel": {"amra_core.jit"},
    "amra_core.trim_kernels": {"amra_core.kernels", "amra_core.jit"},
    "amra_core.layout": set(),
    "amra_core.jit": set(),
}


def _module_name(path: Path) -> str:
    rel = path.relative_to(ROOT.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _imports(path: Path, top_level_only: bool) -> set:
    """Absolute names of the modules ``path`` imports (``from . import x`` counts as ``pkg.x``)."""
    tree = ast.parse(path.read_text())
    name = _module_name(path)
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    nodes = tree.body if top_level_only else list(ast.walk(tree))
    out = set()
    for node in nodes:
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - (node.level - 1)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            if node.module is None or node.level and (ROOT / Path(*mod.split(".")[1:])).is_dir():
                # ``from . import kernels`` / ``from .boundary import x``: submodules or names of a package
                for a in node.names:
                    sub = f"{mod}.{a.name}"
                    out.add(sub if _exists(sub) else mod)
            else:
                out.add(mod)
    return out


def _exists(mod: str) -> bool:
    rel = Path(*mod.split(".")[1:])
    return (ROOT / rel).with_suffix(".py").is_file() or (ROOT / rel / "__init__.py").is_file()


def _sources():
    return sorted(p for p in ROOT.rglob("*.py") if "__pycache__" not in p.parts)


def test_core_never_imports_the_app_or_its_frameworks():
    bad = []
    for p in _sources():
        for mod in _imports(p, top_level_only=False):
            if mod.split(".")[0] in FORBIDDEN:
                bad.append(f"{_module_name(p)} imports {mod}")
    assert not bad, "\n".join(bad)


def test_kernels_import_only_the_layout_and_jit():
    bad = []
    for name, allowed in KERNEL_DEPS.items():
        path = ROOT / (name.split(".", 1)[1] + ".py")
        assert path.is_file(), name
        got = {m for m in _imports(path, top_level_only=False) if m.split(".")[0] == "amra_core"}
        extra = got - allowed
        if extra:
            bad.append(f"{name} imports {sorted(extra)} (allowed: {sorted(allowed)})")
    assert not bad, "\n".join(bad)


def test_no_import_circles():
    graph = {}
    for p in _sources():
        graph[_module_name(p)] = {m for m in _imports(p, top_level_only=True)
                                  if m.startswith("amra_core.") and m != _module_name(p)}
    cycles = []
    state = {}

    def visit(n, stack):
        state[n] = 1
        for m in sorted(graph.get(n, ())):
            if m not in graph:
                continue
            if state.get(m) == 1:
                cycles.append(" -> ".join(stack[stack.index(m):] + [m]) if m in stack else f"{n} -> {m}")
            elif m not in state:
                visit(m, stack + [m])
        state[n] = 2

    for n in sorted(graph):
        if n not in state:
            visit(n, [n])
    # a package's __init__ re-exporting its own submodules is not a circle
    cycles = [c for c in cycles if not all(x.startswith(c.split(" -> ")[0]) for x in c.split(" -> "))]
    assert not cycles, "\n".join(cycles)


def test_the_contract_sees_imports():
    """The reader is not vacuous: it finds the kernels' real imports and the app's frameworks in app/."""
    assert _imports(ROOT / "kernels.py", False) >= {"amra_core.layout", "amra_core.jit"}
    app_view = ROOT.parent / "app" / "map_view.py"
    if app_view.is_file():
        tree = ast.parse(app_view.read_text())
        names = {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
        assert "panel" in names
