"""vqtex uses Amaranth through its public interfaces only (issue: public interfaces).

The sources of golden/, hw/ and sim/ are scanned for Amaranth's private modules and attributes."""

import pathlib
import re

from tests.support import REPO

PRIVATE = re.compile(r"amaranth(?:\.\w+)*\._(?!_)\w|from amaranth(?:\.\w+)* import _\w|\._data\b|_MustUse|_convert_rtlil_text"
                     r"|\._init\._raw|_toolchain")
#: file -> a line allowed there (none: every use of Amaranth is public).
ALLOWED: dict = {}


def _hits():
    for pkg in ("golden", "hw", "sim"):
        for path in sorted((pathlib.Path(REPO) / pkg).rglob("*.py")):
            rel = path.relative_to(REPO).as_posix()
            for n, line in enumerate(path.read_text().splitlines(), 1):
                if PRIVATE.search(line) and ALLOWED.get(rel) != line:
                    yield f"{rel}:{n}: {line.strip()}"


def test_no_amaranth_internals():
    hits = list(_hits())
    assert not hits, "Amaranth internals used:\n" + "\n".join(hits)


def test_the_pattern_finds_what_it_is_for():
    for line in ("from amaranth.hdl import _ast", "x = f._data", "amaranth._toolchain.yosys",
                 "self._MustUse__silence = True", "verilog._convert_rtlil_text(il)", "d._init._raw"):
        assert PRIVATE.search(line), line
    for line in ("from amaranth.hdl import Fragment", "from amaranth.lib import memory", "self._bits = 3",
                 "amaranth.__version__"):
        assert not PRIVATE.search(line), line
