"""hw.filter.index_banks: the bank map against golden.index_banks.bank_address, the conflict strobe
(a negative control), and the texture filter with shared banked index memories against golden on
paper and PowerVR2 (twiddled, non-square) sets, on pysim and the compiled backend."""

import numpy as np
import pytest
from amaranth import Module, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out
from amaranth.sim import Simulator

from tests import support
from tests.support import edge_pixels
from vqtex.golden import filter as spec
from vqtex.golden import index_banks as golden_banks
from vqtex.golden.format import TextureSet
from vqtex.hw.filter import TextureFilter
from vqtex.hw.filter.footprint import level_table
from vqtex.hw.filter.index_banks import IndexBanks, bank_map
from vqtex.hw.index_reader import IndexRequestLayout
from vqtex.hw.memories import elaborate, memories
from vqtex.sim.backends.filter import golden_colors, simulate_filter


def paper_and_pvr2(n: int, seed: int):
    """(set, frac, pixels): the paper's rgb12 set and tiny PowerVR2 rectangles and mip chain, and ``n``
    edge-case pixels (tests.hw.filter.test_hw_filter.edge_pixels)."""
    ts = TextureSet.combine([support.texture_sets()["rgb12"], support.pvr2_small_sets()["rectangles_and_mip8"]])
    table = level_table(ts)
    frac = spec.coordinate_frac_bits(table.max_log2)
    return ts, frac, edge_pixels(table, frac, n, seed)


class _Map(wiring.Component):
    def __init__(self, banks):
        self._banks = banks
        super().__init__({"req": In(IndexRequestLayout(16, 4)), "bank": Out(2), "kq": Out(16)})

    def elaborate(self, platform):
        m = Module()
        bank, kq = bank_map(m, self.req, self._banks, twiddle=True)
        m.d.comb += [self.bank.eq(bank), self.kq.eq(kq)]
        return m


@pytest.mark.parametrize("banks", [2, 4])
def test_bank_map_like_golden(banks):
    rng = np.random.default_rng(banks)
    n = 400
    gw, gh = rng.integers(0, 8, n), rng.integers(0, 8, n)
    tw = rng.integers(0, 2, n)
    k = rng.integers(0, 1 << 16, n) & ((1 << (gw + gh)) - 1)
    want_bank, want_kq = golden_banks.bank_address(k, gw, gh, tw.astype(bool), banks)
    dut = _Map(banks)
    got = []

    async def bench(ctx):
        for x in range(n):
            ctx.set(dut.req.k, int(k[x]))
            ctx.set(dut.req.gw, int(gw[x]))
            ctx.set(dut.req.gh, int(gh[x]))
            ctx.set(dut.req.twiddled, int(tw[x]))
            got.append((ctx.get(dut.bank), ctx.get(dut.kq)))

    sim = Simulator(dut)
    sim.add_testbench(bench)
    sim.run()
    assert [b for b, _ in got] == want_bank.tolist()
    assert [q for _, q in got] == want_kq.tolist()


def test_conflict_strobe_negative_control():
    """Two lanes on blocks 0 and 2 of one row (both even: bank 0) conflict; blocks 0 and 1 do not, nor
    two lanes on one block."""
    ts = support.texture_sets()["rgb12"]
    bi = golden_banks.banked_index(ts, 4)
    dut = IndexBanks(bi, k_bits=12, base_bits=12, widths=(12,), straddle=True)
    seen = []

    async def bench(ctx):
        for k1 in (2, 1, 0):
            for n in range(4):
                ctx.set(dut.requests[n].en, 1)
                ctx.set(dut.requests[n].gw, 4)
                ctx.set(dut.requests[n].b, 12)
            ctx.set(dut.requests[0].valid, 1)
            ctx.set(dut.requests[1].valid, 1)
            ctx.set(dut.requests[0].k, 0)
            ctx.set(dut.requests[1].k, k1)
            seen.append(ctx.get(dut.conflict))
            await ctx.tick()

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    assert seen == [1, 0, 0]


@pytest.mark.parametrize("lanes", [2, 4, 8])
def test_banked_filter_on_pvr2_and_paper_textures_pysim(lanes):
    ts, frac, px = paper_and_pvr2(50, 40 + lanes)
    res = simulate_filter(ts, px, backend="pysim", lanes=lanes, stall=0.2, seed=lanes)
    assert (res.colors == golden_colors(ts, px, frac)).all()
    assert res.bank_conflicts == 0


def test_banked_and_per_lane_memories_give_the_same_pixels_and_cycles():
    ts, frac, px = paper_and_pvr2(40, 7)
    a = simulate_filter(ts, px, backend="pysim", lanes=4, index_banks="parity", stall=0.3, seed=1)
    b = simulate_filter(ts, px, backend="pysim", lanes=4, index_banks="lane", stall=0.3, seed=1)
    assert (a.colors == b.colors).all() and a.cycles == b.cycles and a.stall_cycles == b.stall_cycles
    with pytest.raises(ValueError):
        TextureFilter(ts, lanes=4, index_banks="odd")


@pytest.mark.parametrize("lanes,index_banks,readers", [(1, "parity", ["lane0"]), (2, "parity", ["index_banks0"] * 2),
                                                       (4, "lane", [f"lane{k}" for k in range(4)]),
                                                       (8, "parity", ["index_banks0"] * 4 + ["index_banks1"] * 4)])
def test_who_holds_the_index_memory(lanes, index_banks, readers):
    """The index memories of the elaborated filter: a bank per parity in each set of lanes, or a copy
    per lane; either way the contents are golden.index_banks' images or the set's map."""
    ts = support.texture_sets()["rgb12"]
    top = TextureFilter(ts, lanes=lanes, index_banks=index_banks)
    mems = [mc for mc in memories(elaborate(top)) if "even_bank" in mc.path or "odd_bank" in mc.path]
    even = [mc for mc in mems if "even_bank" in mc.path]
    assert [mc.path[0] for mc in even] == readers
    banks = top.banks
    assert banks == (golden_banks.lane_banks(lanes) if index_banks == "parity" else 1)
    words = golden_banks.banked_index(ts, banks).words if banks > 1 else [ts.index_words]
    for n, mc in enumerate(even):
        image = [int(w) for w in words[n % banks][0::2]]
        got = list(mc.words) + [0] * max(0, len(image) - len(mc.words))   # trailing zeros may be left out
        assert got[:len(image)] == image and not any(got[len(image):])     # a partial bank padded with zeros


@pytest.mark.parametrize("lanes", [4, 8])
def test_banked_filter_on_the_compiled_backend(lanes):
    support.need("g++")
    with support.shared_cache():
        ts, frac, px = paper_and_pvr2(20000, 50 + lanes)
        res = simulate_filter(ts, px, backend="cxxrtl", lanes=lanes, stall=0.25, seed=lanes)
        assert (res.colors == golden_colors(ts, px, frac)).all()
        assert res.bank_conflicts == 0 and res.stall_cycles["output_backpressure"] > 0
