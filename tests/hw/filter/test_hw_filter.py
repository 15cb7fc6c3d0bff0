"""hw.filter against golden.filter on Amaranth's simulator: the footprint stage alone (many cases:
no memories), the whole TextureFilter (tiny cases) with 1, 2, 4 and 8 lanes, backpressure, cycle counts."""

import numpy as np
import pytest
from amaranth.sim import Simulator

from tests import support
from vqtex.golden import filter as spec
from vqtex.hw.filter import LATENCY, TextureFilter
from vqtex.hw.filter.footprint import Footprint, level_table
from vqtex.sim.backends.filter import golden_colors, simulate_filter
from vqtex.sim.streams import ready_pattern


def test_footprint_stage_against_golden():
    shapes = [[(32, 4), (16, 2), (8, 1), (4, 1), (2, 1), (1, 1)], [(1, 16), (1, 8), (1, 4), (1, 2), (1, 1)],
              [(64, 64)], [(1, 1)], [(8, 8), (4, 4), (2, 2)]]
    table = spec.LevelTable(shapes)
    frac = spec.coordinate_frac_bits(table.max_log2) + 1
    n = 600
    px = support.edge_pixels(table, frac, n, 1)
    want = spec.footprint(table, px["texture"], px["s"], px["t"], px["lod"], px["mode"], px["address_s"],
                          px["address_t"], frac)
    dut = Footprint(table, texture_bits=3, frac=frac, tag_width=10)
    layout = dut.i.p.shape()
    payloads = []
    for k in range(n):
        v = k << layout["tag"].offset
        for name in ("texture", "s", "t", "lod", "mode", "address_s", "address_t"):
            v |= (int(px[name][k]) & ((1 << layout[name].width) - 1)) << layout[name].offset
        payloads.append(v)
    got = []
    ready = ready_pattern(7, 0.3, 4 * n + 100).tolist()

    async def bench(ctx):
        sent, cycle = 0, 0
        while len(got) < n:
            ctx.set(dut.i.valid, sent < n)
            if sent < n:
                ctx.set(dut.i.p.as_value(), payloads[sent])
            ctx.set(dut.o.ready, ready[cycle])
            if ctx.get(dut.o.valid) and ready[cycle]:
                o = ctx.get(dut.o.p)
                assert o.tag == len(got) % 1024
                got.append(([(t.level, t.i, t.j) for t in o.texels], list(o.weights), o.used))
            if sent < n and ctx.get(dut.i.ready):
                sent += 1
            cycle += 1
            await ctx.tick()

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    level, i, j, weight = want
    for k, (texels, weights, used) in enumerate(got):
        assert texels == list(zip(level[k].tolist(), i[k].tolist(), j[k].tolist())), k
        assert weights == weight[k].tolist(), k
        assert used == spec.TEXELS[spec.MODES[px["mode"][k]]]


@pytest.mark.parametrize("lanes,stall", [(1, 0.0), (1, 0.3), (2, 0.2), (4, 0.0), (4, 0.4), (8, 0.0)])
def test_filter_against_golden(lanes, stall):
    ts = support.filter_set()
    table = level_table(ts)
    frac = spec.coordinate_frac_bits(table.max_log2)
    px = support.edge_pixels(table, frac, 60 if lanes > 1 else 40, lanes * 10 + int(stall * 10))
    res = simulate_filter(ts, px, backend="pysim", lanes=lanes, stall=stall, seed=lanes)
    want = golden_colors(ts, px, frac)
    assert (res.colors == want).all()
    if stall == 0:
        # throughput: one group of ``lanes`` slots per clock (1, 4, 8 slots per point, bilinear,
        # trilinear pixel); latency 23
        groups = -(-np.array([1, 4, 8])[px["mode"]] // lanes)
        assert res.cycles == int(groups.sum()) + LATENCY and LATENCY == 24
        assert res.stall_cycles["output_backpressure"] == 0
    else:
        assert res.stall_cycles["output_backpressure"] > 0


def test_filter_with_more_fractional_bits_and_small_banks():
    """A wider s and t (frac above the minimum) and 8-word memory banks give the same colours."""
    ts = support.filter_set()
    table = level_table(ts)
    frac = spec.coordinate_frac_bits(table.max_log2) + 3
    px = support.edge_pixels(table, frac, 30, 5)
    res = simulate_filter(ts, px, backend="pysim", lanes=2, frac=frac)
    assert (res.colors == golden_colors(ts, px, frac)).all()
    from vqtex.sim.backends.filter import run_pysim
    small = run_pysim(ts, px, lanes=1, frac=frac, bank_depth=8, stall=0.2, seed=3)
    assert (small.colors == res.colors).all()


def test_filter_rejects_bad_configuration():
    ts = support.filter_set()
    with pytest.raises(ValueError):
        TextureFilter(ts, lanes=3)
    with pytest.raises(ValueError):
        TextureFilter(ts, frac=spec.coordinate_frac_bits(level_table(ts).max_log2) - 1)
    with pytest.raises(TypeError):
        TextureFilter("not a texture set")
    px = {"texture": [0], "s": [0], "t": [0], "lod": [0], "mode": [0], "address_s": [0], "address_t": [0]}
    for field, bad in (("texture", [9]), ("lod", [5 * 256 + 1]), ("mode", [3]), ("address_t", [-1]),
                       ("s", [1 << 20])):
        with pytest.raises(ValueError):
            simulate_filter(ts, {**px, field: bad})
