"""hw.memory.unit.CachedTexelFetch on pysim, its AXI master answered by the golden memory models
(sim.backends.axi_memory): responses equal golden.fetch bit for bit, and the input acceptances, every
AR and every response transfer equal the golden cycle model (sim.backends.cycle_model.run_cached's
golden.memory.timing with the texel pipeline's LATENCY), with memory latencies 1 to 300, the
blocking and the prefetching cache, fixed memory and DDR3, random output backpressure."""

import numpy as np
import pytest
from amaranth import Module
from amaranth.sim import Simulator

from vqtex.golden.fetch import fetch, random_requests
from vqtex.golden.memory.cache import CacheShape
from vqtex.golden.memory.system import Layout, MemoryConfig
from vqtex.golden.memory.timing import plan, run
from vqtex.hw.memory.unit import CachedTexelFetch
from vqtex.hw.texel_fetch import LATENCY
from vqtex.sim.backends.axi_memory import AxiMemory
from vqtex.sim.backends.pysim import pack_rows
from vqtex.sim.streams import ready_pattern

from tests.support import texture_set


def simulate(ts, req, cfg, stall, seed):
    dut = CachedTexelFetch(ts, cfg, tag_width=8)
    slave = AxiMemory(Layout.of(ts).image(ts), cfg.make_memory(), cfg.bus_bytes)
    n = len(req)
    packed = pack_rows(dut.i.p.shape(), ("texture", "level", "i", "j"), req, 8)
    ready = ready_pattern(seed, stall, 200000).tolist()
    rlay = dut.o.p.shape()
    got = {"accept": [], "transfer": [], "rgba": []}
    top = Module()
    top.submodules.dut = dut

    async def bench(ctx):
        n_in = n_out = cycle = 0
        slave.start(ctx, dut.axi)
        while n_out < n:
            assert cycle < 40 * n + 6000, (cycle, n_in, n_out)
            ctx.set(dut.i.valid, int(n_in < n))
            if n_in < n:
                ctx.set(dut.i.p.as_value(), packed[n_in])
            ctx.set(dut.o.ready, int(ready[cycle]))
            slave.step(ctx, dut.axi, cycle)
            if ctx.get(dut.o.valid) and ready[cycle]:
                p = ctx.get(dut.o.p.as_value())
                assert (p >> rlay["tag"].offset) & 255 == n_out & 255
                got["rgba"].append([(p >> rlay[c].offset) & 255 for c in "rgba"])
                got["transfer"].append(cycle)
                n_out += 1
            if n_in < n and ctx.get(dut.i.ready):
                got["accept"].append(cycle)
                n_in += 1
            cycle += 1
            await ctx.tick()

    sim = Simulator(top)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    got["ar"] = slave.ar
    return got


def check(ts, req, cfg, stall, seed):
    got = simulate(ts, req, cfg, stall, seed)
    assert (np.array(got["rgba"], np.uint8) == fetch(ts, *np.asarray(req).T)).all()
    p = plan(ts, req, cfg)
    model = run(p, cfg, LATENCY, lambda m: ready_pattern(seed, stall, m))
    assert got["accept"] == model["accept"].tolist()
    assert got["ar"] == [g + 1 + j for g, m in zip(model["tag"].tolist(), p.misses.tolist()) for j in range(m)]
    assert got["transfer"] == model["transfer"].tolist()
    return model


@pytest.mark.parametrize("prefetch", [1, 8])
def test_cached_unit_equals_golden(prefetch):
    ts = texture_set("yuv_4x4_b12_mip")              # compressed levels (12-bit indices) and raw levels
    rng = np.random.default_rng(prefetch)
    req = random_requests(ts, 40, seed=prefetch)
    req = np.repeat(req, rng.integers(1, 4, len(req)), axis=0)
    ic, rc = CacheShape(256, 16, 2), CacheShape(128, 16, 2)
    for latency, stall in ((1, 0.3), (25, 0.0), (60, 0.5)):
        m = check(ts, req, MemoryConfig(index_cache=ic, raw_cache=rc, prefetch=prefetch, latency=latency,
                                        bus_bytes=16, bandwidth=8), stall, latency)
        assert m["bursts"] > 0 and m["stall_cycles"]["miss"] > 0


def test_cached_unit_dram_and_300_cycles():
    ts = texture_set("rgba_2x2_b7_mip_w16")
    req = random_requests(ts, 40, seed=4)
    ic, rc = CacheShape(128, 16, 2), CacheShape(64, 16, 2)
    check(ts, req, MemoryConfig(index_cache=ic, raw_cache=rc, prefetch=8, latency=300, bus_bytes=16), 0.2, 3)
    check(ts, req, MemoryConfig(index_cache=ic, raw_cache=rc, prefetch=4, kind="dram", bus_bytes=16), 0.4, 4)
