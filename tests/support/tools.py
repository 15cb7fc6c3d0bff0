"""The environment tests run in: the repository, the external tools a test needs (skipped without
them, failed with ``VQTEX_REQUIRE_TOOLS=1``), the build cache every test shares, and ``vqtex`` run
in this process."""

from __future__ import annotations

import contextlib
import os
import shutil

import pytest

from vqtex.sim.backends.toolchain import using_cache

#: The repository's root folder; tests reach files through it (or :data:`PVRTEX_DATA`), never
#: relative to their own file, so a test module can move with its package.
REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

#: pvrtex's Dreamcast textures and previews (tests/data/pvrtex/, see its README.md).
PVRTEX_DATA = os.path.join(REPO, "tests", "data", "pvrtex")


def need(*tools):
    """Skip (or, with VQTEX_REQUIRE_TOOLS=1, fail) unless every tool is on the PATH."""
    missing = [t for t in tools if shutil.which(os.environ.get("CXX", t) if t == "g++" else t) is None]
    if missing:
        msg = f"needs {', '.join(missing)} (scripts/install-sim-tools)"
        if os.environ.get("VQTEX_REQUIRE_TOOLS") == "1":
            pytest.fail(msg + " and VQTEX_REQUIRE_TOOLS=1")
        pytest.skip(msg)


def need_python(*modules):
    """Skip (or, with VQTEX_REQUIRE_TOOLS=1, fail) unless the Python modules import (the ``test``
    extra installs them)."""
    import importlib
    missing = []
    for name in modules:
        try:
            importlib.import_module(name)
        except ImportError as e:
            missing.append(f"{name} ({e})")
    if missing:
        msg = f"needs {', '.join(missing)} (pip install '.[test]')"
        if os.environ.get("VQTEX_REQUIRE_TOOLS") == "1":
            pytest.fail(msg + " and VQTEX_REQUIRE_TOOLS=1")
        pytest.skip(msg)


def need_synth_tools():
    """Skip (or, with VQTEX_REQUIRE_TOOLS set, fail) unless Yosys and nextpnr-ecp5 (the ``synth``
    extra) are installed."""
    from vqtex.sim.reports import synth
    missing = [name for name, ok in synth.tools_available().items() if not ok]
    if missing:
        msg = f"{', '.join(missing)} not installed (pip install '.[synth]')"
        if os.environ.get("VQTEX_REQUIRE_TOOLS"):
            pytest.fail(msg)
        pytest.skip(msg)


def shared_cache_dir():
    """Builds shared by test runs: $VQTEX_CACHE if set, else the repository's .vqtex-cache/."""
    return os.environ.get("VQTEX_CACHE") or os.path.join(REPO, ".vqtex-cache")


@contextlib.contextmanager
def shared_cache():
    """``$VQTEX_CACHE`` set to :func:`shared_cache_dir` inside the block (the builds of every test
    run shared), restored after. Test modules use it as an autouse fixture: ``with shared_cache(): yield``."""
    with using_cache(shared_cache_dir()):
        yield


def run_cli(capsys, *argv):
    """``vqtex ARGV`` in this process: (exit status, stdout, stderr) of that call alone."""
    from vqtex.sim.cli import main
    capsys.readouterr()
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def assert_one_error(capsys, argv, pattern):
    """``vqtex ARGV`` ends with exit status 2, nothing on stdout and one ``vqtex: error:`` line on
    stderr containing ``pattern``."""
    code, out, err = run_cli(capsys, *argv)
    assert code == 2 and out == "", (argv, out)
    assert err.count("\n") == 1 and err.startswith("vqtex: error: ") and pattern in err, (argv, err)
