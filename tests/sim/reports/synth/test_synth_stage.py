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


def test_chain_harness_when_ports_exceed_the_pins(tiny_rtlil, monkeypatch):
    """A block with more port bits than the package has pins (the cached unit's reader, ~365): its
    inputs are one shift chain from a pin, its outputs registered and XORed into one pin."""
    plain, path, bits = synth.stage_rtlil(tiny_rtlil, "color_matrix")
    monkeypatch.setattr(synth.harness, "PACKAGE_IOS", bits - 1)
    il, path2, chain_bits = synth.stage_rtlil(tiny_rtlil, "color_matrix")
    assert path2 == path and chain_bits == bits + 1            # every port bit and the XOR's flip-flop
    top = _module(il, synth.HARNESS_NAME)
    pins = re.findall(r"^  wire width (\d+) (input|output) \d+ \\(\S+)$", top, re.M)
    assert sorted(n for _, _, n in pins) == ["clk", "rst", "si", "so"] and all(w == "1" for w, _, _ in pins)
    assert top.count("cell $dff ") == 3 and "cell $reduce_xor" in top
    assert re.search(r"connect \\D \{ \\in_chain \[\d+:0\] \\si \}", top)
    # each port of the block gets its own slice of the chain or of the output register, no bit twice
    block = _module(tiny_rtlil, f"{synth.UNIT_NAME}.{path}")
    widths = {p[-1].lstrip("\\"): (int(p[p.index("width") + 1]), "input" in p)
              for p in (ln.split() for ln in block.splitlines() if re.match(r"  wire .*\b(input|output)\b", ln))}
    seen = {"\\in_chain": set(), "\\out_d": set()}
    for name, wire, hi, lo in re.findall(r"connect \\(\S+) (\\in_chain|\\out_d) \[(\d+)(?::(\d+))?\]", top):
        lo = int(lo or hi)
        assert int(hi) - lo + 1 == widths[name][0] and (wire == "\\in_chain") == widths[name][1]
        assert not seen[wire] & set(range(lo, int(hi) + 1))
        seen[wire] |= set(range(lo, int(hi) + 1))
    assert len(seen["\\in_chain"]) + len(seen["\\out_d"]) == bits


def test_report_area_stage_chain_synthesis(capsys, monkeypatch):
    """The chain harness goes through Yosys: the colour matrix keeps its multipliers."""
    _need_tools()
    monkeypatch.setattr(synth.harness, "PACKAGE_IOS", 8)
    code, out, err = _run(capsys, "report", "area", "--builtin", "tiny", "--unit", "loadable", "--stage",
                          "color_matrix", "--no-pnr", "--json")
    assert code == 0, err
    rep = json.loads(out)
    # more flip-flops than pins: the chain and the output register, kept (their bits feed the block)
    assert 8 < rep["harness_ffs"] <= rep["port_bits"] and rep["utilisation"]["dsps"] > 0
