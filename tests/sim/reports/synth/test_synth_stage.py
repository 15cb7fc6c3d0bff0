"""One block of the unit alone (``vqtex report area ... --stage NAME``, :func:`synth.stage_rtlil`):
the block cut out of the unit's RTLIL into a harness of its own, a flip-flop on every port.

The RTLIL tests need no tools; the synthesis test needs the ``synth`` extra (skipped without it,
required under ``VQTEX_REQUIRE_TOOLS``) and takes seconds (a tiny geometry, synthesis only)."""

from __future__ import annotations

import json
import re

import pytest

from vqtex.sim.reports import synth
from tests.support import builtin_set, need_synth_tools as _need_tools, run_cli as _run


@pytest.fixture(scope="module")
def tiny_rtlil():
    from vqtex.golden.geometry import Geometry
    return synth.Harness(None, geometry=Geometry.of(builtin_set("tiny"))).rtlil()


def _module(il, name):
    m = re.search(rf"^module \\{re.escape(name)}\n(.*?)^end\n", il, re.S | re.M)
    assert m, name
    return m.group(1)


def test_stage_rtlil_keeps_the_block_and_registers_its_ports(tiny_rtlil):
    names = synth.stage_names(tiny_rtlil)
    assert {"fetch.front.descriptor", "fetch.back.codebook_rom", "fetch.back.color_matrix",
            "fetch.front.index_reader", "fetch.bus_port"} <= set(names)
    il, path, bits = synth.stage_rtlil(tiny_rtlil, "codebook_rom")       # a unique tail names the block
    assert path == "fetch.back.codebook_rom"
    block = _module(tiny_rtlil, f"{synth.UNIT_NAME}.{path}")
    modules = re.findall(r"^module \\(\S+)$", il, re.M)
    # the block is the unit now, its submodules under it; nothing else of the unit is left
    assert sorted(modules) == sorted([synth.HARNESS_NAME, synth.UNIT_NAME, f"{synth.UNIT_NAME}.codebook",
                                      f"{synth.UNIT_NAME}.raw"])
    assert _module(il, synth.UNIT_NAME) == block.replace(f"\\{synth.UNIT_NAME}.{path}.", f"\\{synth.UNIT_NAME}.")
    ports = [ln.split() for ln in block.splitlines() if re.match(r"  wire .*\b(input|output)\b", ln)]
    width = {p[-1].lstrip("\\"): int(p[p.index("width") + 1]) for p in ports}
    assert bits == sum(w for n, w in width.items() if n not in ("clk", "rst")) > 0
    top = _module(il, synth.HARNESS_NAME)
    assert top.count("cell $dff ") == len(width) - 2               # one per port but clk and rst
    assert re.search(r"connect \\D \\load\n\s+connect \\Q \\load\$q\n", top)         # an input registered
    assert re.search(r"connect \\D \\samples\$q\n\s+connect \\Q \\samples\n", top)   # an output registered


@pytest.mark.parametrize("stage, why", [("nope", "is not a block"), ("bank", "is not a block"),
                                        ("front", None)])
def test_stage_names(tiny_rtlil, stage, why):
    if why is None:
        assert synth.stage_rtlil(tiny_rtlil, stage)[1] == "fetch.front"
        return
    with pytest.raises(synth.StageError, match=why):
        synth.stage_rtlil(tiny_rtlil, stage)


def test_unknown_stage_one_line_exit_2(capsys):
    _need_tools()
    code, out, err = _run(capsys, "report", "area", "--builtin", "tiny", "--unit", "loadable", "--stage", "nope",
                          "--no-pnr", "--json")
    assert code == 2 and out == "" and err.count("\n") == 1
    assert "'nope' is not a block" in err and "fetch.back.color_matrix" in err


def test_report_area_stage_synthesis(capsys):
    """The colour matrix alone: its multipliers and registers, none of the unit's memories."""
    _need_tools()
    code, out, err = _run(capsys, "report", "area", "--builtin", "tiny", "--unit", "loadable", "--stage",
                          "color_matrix", "--no-pnr", "--json")
    assert code == 0, err
    rep = json.loads(out)
    assert rep["stage"] == "fetch.back.color_matrix" and rep["unit"] == "loadable"
    u = rep["utilisation"]
    assert u["dsps"] > 0 and u["brams"] == 0 and u["dist_ram"] == 0 and u["ffs"] > 0
    assert 0 < rep["harness_ffs"] <= rep["port_bits"] < 200
    assert rep["memories"] == {}
    assert "block fetch.back.color_matrix alone" in synth.area_text(rep)
