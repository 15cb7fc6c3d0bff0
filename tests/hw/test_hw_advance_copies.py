"""``hw.pipeline.advance_copies``: the loadable unit's copies of ``advance`` (docs/area.md, "Timing
closure of the loadable unit"). Each equals ``advance`` from the second cycle after a reset on,
under any output backpressure and a reset in the middle (pysim); and ECP5 synthesis keeps every copy
a flip-flop of its own (Yosys's opt_merge would fold copies of the same kind into one)."""

from __future__ import annotations

import json
import numpy as np
from amaranth import *
from amaranth.back import rtlil
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out
from amaranth.sim import Simulator

from vqtex.hw.pipeline import ADVANCE_COPIES, advance_copies

from ..support import need_synth_tools

N = len(ADVANCE_COPIES)


class _Copies(wiring.Component):
    """``advance`` as the front end makes it, beside its copies; each copy drives a register of its
    own (so that synthesis keeps the copies)."""

    def __init__(self):
        super().__init__({"stall": In(1), "advance": Out(1), "copies": Out(N), "d": In(N), "q": Out(N)})

    def elaborate(self, platform):
        m = Module()
        advance = Signal(init=1)
        m.d.sync += advance.eq(~self.stall)
        copies = advance_copies(m, self.stall, N)
        m.d.comb += [self.advance.eq(advance), self.copies.eq(Cat(*copies))]
        for k, en in enumerate(copies):
            with m.If(en):
                m.d.sync += self.q[k].eq(self.d[k])
        return m


def test_copies_equal_advance_after_the_first_cycle():
    rng = np.random.default_rng(7)
    stall = rng.random(300) < 0.4
    resets = {120, 121, 200}                # a two-cycle reset and a one-cycle one, after stalls
    stall[119] = stall[199] = True
    dut = _Copies()
    top = Module()
    top.domains.sync = cd = ClockDomain("sync")
    top.submodules.dut = dut
    seen = []

    async def bench(ctx):
        for t in range(len(stall)):
            ctx.set(dut.stall, int(stall[t]))
            ctx.set(cd.rst, int(t in resets))
            seen.append((t, ctx.get(dut.advance), ctx.get(dut.copies)))
            await ctx.tick()

    sim = Simulator(top)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    first = {0} | {t + 1 for t in resets if t + 1 not in resets}     # first cycles after a reset
    differ = 0
    for t, adv, copies in seen:
        if t in resets:
            continue
        if t in first:
            differ |= copies ^ (adv * ((1 << N) - 1))
            assert adv == 1
            continue
        assert copies == adv * ((1 << N) - 1), (t, adv, bin(copies))
    assert differ, "no copy differs from advance in a first cycle: the kinds are not apart"


def test_synthesis_keeps_every_copy(tmp_path):
    need_synth_tools()
    from vqtex.sim.reports.synth import tools
    text = rtlil.convert(_Copies(), name="top", emit_src=False)
    (tmp_path / "design.il").write_text(text)
    (tmp_path / "synth.ys").write_text("read_rtlil design.il\nsynth_ecp5 -top top -json netlist.json\n")
    tools.run_yowasp("yosys", ["-q", "-s", "synth.ys"], str(tmp_path), "yosys.out")
    top = json.loads((tmp_path / "netlist.json").read_text())["modules"]["top"]
    ffs = [c for c in top["cells"].values() if c["type"] == "TRELLIS_FF"]
    # advance, its N copies, and the N registers they enable
    assert len(ffs) == 1 + N + N, len(ffs)


def test_loadable_unit_with_many_banks_under_backpressure():
    """The loadable unit on its copies of ``advance`` with 4-word banks (several codebook banks,
    the bank select behind the block RAMs) and the output stalled 40% of the time: every response
    bit for bit as golden's, cycles as its model's."""
    from vqtex.golden.fetch import fetch, random_requests
    from vqtex.golden.geometry import Geometry
    from vqtex.sim.backends import pysim
    from vqtex.sim.backends.interface import simulate
    from ..support import texture_set

    ts = texture_set("yuv_4x4_b12_mip")
    g = Geometry.of(ts)
    assert g.codebook_entries > 3 * 4           # at least four banks of 4 entries
    req = random_requests(ts, 120, seed=5)
    (r,) = pysim.run_phases(g, [(ts, req)], stall=0.4, seed=3, bank_depth=4)
    assert np.array_equal(r.responses, fetch(ts, req[:, 0], req[:, 1], req[:, 2], req[:, 3]))
    golden = simulate(ts, req, backend="golden", stall=0.4, seed=3)
    assert (r.cycles, r.stall_cycles) == (golden.cycles, golden.stall_cycles)
