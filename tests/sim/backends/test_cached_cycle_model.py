"""The cached unit's cycle model (golden.memory.timing, sim.backends.cycle_model.run_cached) against
what is already tied to the RTL: the on-chip unit's cycle model when every reference hits, and
TexelFetch itself on pysim for the part of the model that is today's hardware (the texel pipeline
taking requests offered with gaps, under random backpressure)."""

import numpy as np
import pytest
from amaranth import Module
from amaranth.sim import Simulator

from vqtex.golden.fetch import fetch, random_requests
from vqtex.golden.memory.cache import CacheShape
from vqtex.golden.memory.system import MemoryConfig
from vqtex.golden.memory.timing import FRONT_LATENCY, TexelPipeline
from vqtex.hw.texel_fetch import LATENCY, TexelFetch
from vqtex.sim.backends.cycle_model import run_cached, transfer_cycles
from vqtex.sim.backends.pysim import pack_rows
from vqtex.sim.streams import ready_pattern

from tests.support import texture_set


@pytest.mark.parametrize("stall", [0.0, 0.25, 0.6])
def test_perfect_cache_is_the_on_chip_pipeline_later(stall):
    """Every reference a hit: requests reach the texel pipeline back to back, FRONT_LATENCY cycles
    later than on the on-chip unit; the transfers are the on-chip model's with that latency."""
    ts = texture_set("yuv_4x4_b12_mip")
    for seed in range(4):
        req = random_requests(ts, 50 + 100 * seed, seed=seed)
        out = run_cached(ts, req, MemoryConfig(), stall=stall, seed=seed)
        ready = ready_pattern(seed, stall, 20 * len(req) + 200)
        T = transfer_cycles(np.zeros(len(req), bool), ready, LATENCY + FRONT_LATENCY)
        assert out["zero_latency_cycles"] == int(T[-1]) + 1
        assert out["cycles"] >= out["zero_latency_cycles"]
        assert 0 < out["of_zero_latency"] <= 1


def test_run_cached_reports(capsys):
    ts = texture_set("rgb_4x4_b8_mip")
    req = random_requests(ts, 400, seed=3)
    cfg = MemoryConfig(index_cache=CacheShape(512, 32, 2), raw_cache=CacheShape(256, 32, 2), latency=50)
    out = run_cached(ts, req, cfg, stall=0.2, seed=1)
    assert set(out["stall_cycles"]) == {"output_backpressure", "miss", "bandwidth", "fifo_full", "victim"}
    assert out["stall_cycles"]["miss"] > 0
    for name in ("index", "raw"):
        assert out["hit_rate"][name] is None or 0 <= out["hit_rate"][name] <= 1
    assert out["bytes_per_texel"] == (out["memory_bytes"]["index"] + out["memory_bytes"]["raw"]) / len(req)
    assert out["texels_per_clock"] == len(req) / out["cycles"]


def pysim_gappy(ts, req, offer, stall, seed):
    """TexelFetch with request n offered (i.valid) from cycle ``max(offer[n], accept[n-1] + 1)`` and
    held until taken; returns the accept and transfer cycles, and the responses."""
    dut = TexelFetch(ts, tag_width=8)
    n = len(req)
    packed = pack_rows(dut.i.payload.shape(), ("texture", "level", "i", "j"), req, 8)
    ready = ready_pattern(seed, stall, 64 + 40 * (n + LATENCY) + int(offer[-1])).tolist()
    accept, transfer, out = [], [], []
    top = Module()
    top.submodules.dut = dut
    rlay = dut.o.payload.shape()

    async def bench(ctx):
        n_in = n_out = cycle = 0
        while n_out < n:
            avail = n_in < n and cycle >= offer[n_in] and (not accept or cycle > accept[-1])
            ctx.set(dut.i.valid, int(avail))
            if avail:
                ctx.set(dut.i.payload.as_value(), packed[n_in])
            ctx.set(dut.o.ready, int(ready[cycle]))
            if ctx.get(dut.o.valid) and ready[cycle]:
                p = ctx.get(dut.o.payload.as_value())
                assert (p >> rlay["tag"].offset) & 255 == n_out & 255
                out.append([(p >> rlay[c].offset) & 255 for c in "rgba"])
                transfer.append(cycle)
                n_out += 1
            if avail and ctx.get(dut.i.ready):
                accept.append(cycle)
                n_in += 1
            cycle += 1
            await ctx.tick()

    sim = Simulator(top)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    return accept, transfer, np.array(out, np.uint8)


@pytest.mark.parametrize("stall", [0.0, 0.3, 0.6])
def test_texel_pipeline_timing_equals_texelfetch_on_pysim(stall):
    """TexelPipeline.take (the model of how the texel pipeline takes a request offered late) against
    the RTL: gaps of 0-20 cycles between offers (a miss's bubbles), random backpressure."""
    ts = texture_set("rgb_4x4_b8_mip")
    rng = np.random.default_rng(int(stall * 10))
    n = 60
    req = random_requests(ts, n, seed=int(stall * 10))
    gaps = np.where(rng.random(n) < 0.3, rng.integers(0, 21, n), 0)
    offer = np.cumsum(gaps).tolist()
    seed = 11
    accept, transfer, rgba = pysim_gappy(ts, req, offer, stall, seed)
    pipe = TexelPipeline(LATENCY, lambda m: ready_pattern(seed, stall, m))
    e = []
    for k in range(n):
        e.append(pipe.take(offer[k] if k == 0 else max(offer[k], e[-1] + 1)))
    assert e == accept
    assert pipe.transfer == transfer
    assert (rgba == fetch(ts, *req.T)).all()
