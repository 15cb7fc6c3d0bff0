"""hw.memory.reader.CachedReader on pysim: its AXI master answered by the golden memory models
(golden.memory.external, dram), its responses equal to what memory holds (the texture set's index and
raw words), its cycles equal to golden.memory.timing's (address_stages=0, a stream sink behind it):
input acceptance (into the lookup, the tag check's first cycle), every AR (the cycle after its tag
check), every response transfer."""

import numpy as np
import pytest
from amaranth import ClockDomain, Module
from amaranth.sim import Simulator

from vqtex.golden.fetch import random_requests
from vqtex.golden.memory.cache import CacheShape
from vqtex.golden.memory.system import Layout, MemoryConfig, request_words
from vqtex.golden.memory.timing import StreamSink, plan, run
from vqtex.hw.memory.reader import CachedReader
from vqtex.sim.backends.axi_memory import AxiMemory
from vqtex.sim.streams import ready_pattern

from tests.support import texture_set


def simulate(ts, req, cfg, stall, seed, prelude=None, offer=None, arready=None):
    """``prelude``: (requests, cycles, latency): run those requests for that many cycles first (cut
    off with a burst in flight), then hold reset for a cycle; the checked run follows. ``offer``:
    request n is offered from that cycle on (default back to back). ``arready``: the memory's
    ``arready`` per cycle (default always high)."""
    layout = Layout.of(ts)
    comp, word, strad, raw = request_words(ts, req)
    n = len(req)
    dut = CachedReader(cfg, word_bits=ts.word_bits, raw_base=layout.raw_base, word_addr_bits=24, tag_width=8)
    slave = AxiMemory(layout.image(ts), cfg.make_memory(), cfg.bus_bytes, arready=arready)
    ready = ready_pattern(seed, stall, 200000).tolist()
    rows = [(int(not c), int(w if c else r), int(s), k & 255) for k, (c, w, s, r) in
            enumerate(zip(comp.tolist(), word.tolist(), strad.tolist(), raw.tolist()))]
    lay = dut.i.p.shape()
    packed = [sum(v << lay[f].offset for f, v in zip(("raw", "word", "straddle", "tag"), row)) for row in rows]
    olay = dut.o.p.shape()
    got = {"accept": [], "transfer": [], "ar": [], "words": []}
    top = Module()
    top.submodules.dut = dut
    top.domains.sync = sync = ClockDomain()

    def pack(rows):
        return [sum(v << lay[f].offset for f, v in zip(("raw", "word", "straddle", "tag"), row)) for row in rows]

    async def bench(ctx):
        if prelude is not None:
            before, cycles, latency = prelude
            pc, pw, ps, pr = request_words(ts, before)
            early = pack([(int(not c), int(w if c else r), int(s), k & 255) for k, (c, w, s, r) in
                          enumerate(zip(pc.tolist(), pw.tolist(), ps.tolist(), pr.tolist()))])
            first = AxiMemory(layout.image(ts), cfg.make_memory(), cfg.bus_bytes)
            first.start(ctx, dut.axi)
            sent = 0
            for cycle in range(cycles):
                ctx.set(dut.i.valid, int(sent < len(early)))
                if sent < len(early):
                    ctx.set(dut.i.p.as_value(), early[sent])
                ctx.set(dut.o.ready, 1)
                first.step(ctx, dut.axi, cycle)
                if sent < len(early) and ctx.get(dut.i.ready):
                    sent += 1
                await ctx.tick()
            assert first.ar and first.ar[-1] + latency > cycles     # cut off with a burst in flight
            ctx.set(dut.i.valid, 0)
            ctx.set(dut.axi.rvalid, 0)
            ctx.set(sync.rst, 1)
            await ctx.tick()
            ctx.set(sync.rst, 0)
        n_in = n_out = cycle = 0
        slave.start(ctx, dut.axi)
        while n_out < n:
            assert cycle < 20 * n + 4000, (cycle, n_in, n_out, got)
            if n_in < n and (offer is None or cycle >= offer[n_in]):
                ctx.set(dut.i.valid, 1)
                ctx.set(dut.i.p.as_value(), packed[n_in])
            else:
                ctx.set(dut.i.valid, 0)
            ctx.set(dut.o.ready, int(ready[cycle]))
            slave.step(ctx, dut.axi, cycle)
            if ctx.get(dut.o.valid) and ready[cycle]:
                p = ctx.get(dut.o.p.as_value())
                f = {name: (p >> olay[name].offset) & ((1 << olay[name].width) - 1) for name in ("raw", "word0", "word1", "tag")}
                assert f["tag"] == n_out & 255
                got["words"].append((f["raw"], f["word0"], f["word1"]))
                got["transfer"].append(cycle)
                n_out += 1
            if n_in < n and (offer is None or cycle >= offer[n_in]) and ctx.get(dut.i.ready):
                got["accept"].append(cycle)
                n_in += 1
            cycle += 1
            await ctx.tick()

    sim = Simulator(top)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    got["ar"] = slave.ar
    got["addresses"] = slave.addresses
    got["ar_offered"] = slave.offered
    return got


def words_equal_memory(ts, req, got):
    """Every response is the memory's word (and ``w + 1``) at its request's address, in order."""
    comp, word, strad, raw = request_words(ts, req)
    assert len(got["words"]) == len(req)
    idx = np.asarray(ts.index_words).astype(np.int64)
    rw = np.asarray(ts.raw_words).astype(np.int64)
    for k, (r, w0, w1) in enumerate(got["words"]):
        if comp[k]:
            assert (r, w0) == (0, idx[word[k]]), k
            if strad[k]:
                assert w1 == idx[word[k] + 1], k
        else:
            assert (r, w0) == (1, rw[raw[k]]), k


def check(ts, req, cfg, stall, seed, prelude=None, offer=None):
    got = simulate(ts, req, cfg, stall, seed, prelude, offer)
    words_equal_memory(ts, req, got)
    sink = StreamSink(lambda m: ready_pattern(seed, stall, m))
    p = plan(ts, req, cfg)
    model = run(p, cfg, 0, None, address_stages=0, consumer=sink, offer=offer)
    assert got["accept"] == model["accept"].tolist()
    assert (model["tag"] >= model["accept"] + 2).all()       # the buffer and the lookup take a cycle each
    assert len(got["ar"]) == model["bursts"]
    ar = [g + 1 + j for g, m in zip(model["tag"].tolist(), p.misses.tolist()) for j in range(m)]
    assert got["ar"] == ar
    assert got["transfer"] == sink.transfer
    return model


SHAPES = [
    (CacheShape(128, 16, 1), CacheShape(64, 16, 2), 16),
    (CacheShape(256, 32, 2), CacheShape(128, 32, 2), 16),
    (CacheShape(256, 16, 4), CacheShape(64, 16, 1), 4),
]


@pytest.mark.parametrize("shape", range(len(SHAPES)))
@pytest.mark.parametrize("prefetch", [1, 2, 4])
def test_reader_equals_golden(shape, prefetch):
    ic, rc, bus = SHAPES[shape]
    ts = texture_set("yuv_4x4_b12_mip")
    rng = np.random.default_rng(shape * 10 + prefetch)
    req = random_requests(ts, 40, seed=shape)
    req = np.repeat(req, rng.integers(1, 4, len(req)), axis=0)
    for latency, stall in ((1, 0.0), (9, 0.4), (40, 0.2)):
        cfg = MemoryConfig(index_cache=ic, raw_cache=rc, prefetch=prefetch, latency=latency, bandwidth=bus // 2,
                           bus_bytes=bus)
        model = check(ts, req, cfg, stall, seed=latency)
        assert model["bursts"] > 0


@pytest.mark.parametrize("prefetch, gaps", [(1, (0, 16)), (2, (1, 6))])
def test_reader_with_idle_input(prefetch, gaps):
    """Requests offered with idle cycles between them (``i.valid`` low): cycles equal golden's with
    the offer times. Idle input lets a request arrive while the check ahead of it is failing, so it
    is taken into the buffer in the cycle a kill resets the lookup (``lookup_kill``; a few times
    in each of these streams), or in the failing try's: the lookup must count it and look it up
    after the request killed (counting it not at the kill fails here on ``accept``)."""
    ts = texture_set("yuv_4x4_b12_mip")
    rng = np.random.default_rng(20 + prefetch)
    req = random_requests(ts, 60, seed=7 + prefetch)
    offer = np.cumsum(rng.integers(*gaps, len(req)))
    cfg = MemoryConfig(index_cache=CacheShape(128, 16, 2), raw_cache=CacheShape(64, 16, 2), prefetch=prefetch,
                       latency=12, bus_bytes=16)
    model = check(ts, req, cfg, 0.2, 4, offer=offer)
    a = model["accept"]
    assert (a > offer).any() and (a == offer).any()          # the offer binds, and the buffer does
    assert model["stall_cycles"]["fifo_full"] > 0             # checks not taken: kills


@pytest.mark.parametrize("prefetch", [1, 4])
def test_reader_with_arready_low(prefetch):
    """The memory holds ``arready`` low in random cycles (golden's timing assumes it high, so only
    what does not depend on it is checked): the responses are the memory's words, the bursts are
    golden's lines in golden's order, and an AR held by ``arready`` low keeps its address (the AR
    slots load the check's bursts whenever they are free, so the rule binds: loading a slot that
    waits for ``arready`` fails here)."""
    ts = texture_set("yuv_4x4_b12_mip")
    req = random_requests(ts, 60, seed=13)
    cfg = MemoryConfig(index_cache=CacheShape(128, 16, 2), raw_cache=CacheShape(64, 16, 2), prefetch=prefetch,
                       latency=6, bus_bytes=16)
    arready = (np.random.default_rng(prefetch).random(20000) < 0.4).tolist()
    got = simulate(ts, req, cfg, 0.2, 5, arready=arready)
    words_equal_memory(ts, req, got)
    p = plan(ts, req, cfg)
    assert len(got["ar"]) == len(p.address) > 0
    assert got["addresses"] == p.address.tolist()
    assert len(got["ar"]) < len(got["ar_offered"])        # arready low held some AR


def test_reader_long_latency_and_dram():
    ts = texture_set("rgba_2x2_b7_mip_w16")          # 16-bit index words
    req = random_requests(ts, 50, seed=3)
    ic, rc = CacheShape(128, 16, 2), CacheShape(64, 16, 2)
    check(ts, req, MemoryConfig(index_cache=ic, raw_cache=rc, prefetch=8, latency=300, bus_bytes=16), 0.3, 5)
    check(ts, req, MemoryConfig(index_cache=ic, raw_cache=rc, prefetch=4, kind="dram", bus_bytes=16), 0.3, 6)


def test_reset_empties_the_caches():
    """A reset with misses in flight and references waiting (the per-line state in LUT RAM is not
    reset: only the valid bits are) leaves the caches empty and consistent: the next stream's
    cycles, bursts and words equal golden's from an empty cache."""
    ts = texture_set("yuv_4x4_b12_mip")
    req = random_requests(ts, 60, seed=11)
    cfg = MemoryConfig(index_cache=CacheShape(128, 16, 2), raw_cache=CacheShape(64, 16, 2), prefetch=4,
                       latency=20, bus_bytes=16)
    # the same requests first: a cache that kept their lines (or their counts) would differ
    check(ts, req, cfg, 0.2, 3, prelude=(req, 45, cfg.latency))
