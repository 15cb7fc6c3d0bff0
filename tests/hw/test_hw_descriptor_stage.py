"""The descriptor stage (hw.descriptor.DescriptorTable with ``registered``, the pipeline's stages
``request`` and ``descriptor``): ECP5 synthesis of the loadable table reads every LUT RAM from a
register of the unit's own, one copy of the address per memory (none from the ports), and the row
of the address taken two advancing cycles before, under random stalls (pysim)."""

from __future__ import annotations

import json

import numpy as np
from amaranth.back import rtlil
from amaranth.sim import Simulator

from vqtex.golden.geometry import Geometry
from vqtex.golden.register_map import DESCRIPTOR_WORDS, RegisterMap
from vqtex.hw.bus_port import load_layout
from vqtex.hw.descriptor import DescriptorTable
from vqtex.hw.features import Features

from ..support import need_synth_tools, texture_set

SET = "rgba_2x2_b7_mip_w16"


def _table(loadable: bool):
    ts = texture_set(SET)
    g = Geometry.of(ts)
    if loadable:
        return ts, DescriptorTable(ts, features=Features.of_geometry(g), geometry=g,
                                   load=load_layout(RegisterMap(g)), registered=True)
    return ts, DescriptorTable(ts, features=Features.full(ts), registered=True)


def test_row_is_the_address_taken_two_advances_before():
    for loadable in (False, True):
        ts, dut = _table(loadable)
        rng = np.random.default_rng(3)
        n_tex = ts.n_textures
        tex = rng.integers(0, n_tex, 200)
        lvl = rng.integers(0, 16, 200)
        adv = rng.random(200) < 0.7
        seen = []

        async def bench(ctx):
            taken = []                      # addresses in the request register, then the row's
            for t in range(200):
                ctx.set(dut.texture, int(tex[t]))
                ctx.set(dut.level, int(lvl[t]))
                ctx.set(dut.en, int(adv[t]))
                ctx.set(dut.row_en, int(adv[t]))
                await ctx.tick()
                if adv[t]:
                    taken.append((int(tex[t]), int(lvl[t])))
                if len(taken) >= 2 and adv[t]:
                    seen.append((taken[-2], int(ctx.get(dut.row.as_value()))))

        sim = Simulator(dut)
        sim.add_clock(1e-6)
        sim.add_testbench(bench)
        sim.run()
        layout = dut.layout
        assert len(seen) > 100
        for (t, lv), row in seen:
            want = ts.descriptors[t, lv] if lv < ts.descriptors.shape[1] else None
            for name, field in layout:
                got = (row >> field.offset) & ((1 << field.width) - 1)
                exp = 0 if want is None else int(want[name]) & ((1 << field.width) - 1)
                assert got == exp, (loadable, t, lv, name, got, exp)


def test_synthesis_reads_each_lut_ram_from_its_own_address_register(tmp_path):
    need_synth_tools()
    from vqtex.sim.reports.synth import tools
    _, dut = _table(True)
    (tmp_path / "design.il").write_text(rtlil.convert(dut, name="top", emit_src=False))
    (tmp_path / "synth.ys").write_text("read_rtlil design.il\nsynth_ecp5 -top top -json netlist.json\n")
    tools.run_yowasp("yosys", ["-q", "-s", "synth.ys"], str(tmp_path), "yosys.out")
    top = json.loads((tmp_path / "netlist.json").read_text())["modules"]["top"]
    ports = {b for p in top["ports"].values() for b in p["bits"]}
    driver = {}
    for name, c in top["cells"].items():
        for p, d in c.get("port_directions", {}).items():
            if d == "output":
                for b in c["connections"][p]:
                    driver[b] = c
    rams = [c for c in top["cells"].values() if c["type"] == "TRELLIS_DPR16X4"]
    assert rams
    groups = set()
    for c in rams:
        rad = tuple(c["connections"]["RAD"])
        assert not set(rad) & ports                                  # not from the unit's ports
        assert all(driver[b]["type"] == "TRELLIS_FF" for b in rad)    # from flip-flops
        groups.add(rad)
    # one copy of the address per memory (a register word of a row holding a field): none merged
    w = dut.widths
    words = [word for word in DESCRIPTOR_WORDS if any(min(w[name], width) for name, _, width in word)]
    assert len(groups) == len(words) > 1, (groups, len(words))
