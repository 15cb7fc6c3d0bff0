"""TexelFetch end to end (pysim) against golden.fetch and the golden cycle model."""

import numpy as np
import pytest
from amaranth.sim import Simulator

from tests import support
from vqtex.golden.fetch import RequestError, block_address, decode, fetch, lookup_descriptor, straddles
from vqtex.hw.texel_fetch import LATENCY, STAGES, TexelFetch
from vqtex.sim.backends.interface import simulate
from tests.support import compare_with_golden, stream_get, stream_put


def _straddle_count(ts, req):
    d = lookup_descriptor(ts, req[:, 0], req[:, 1])
    comp = d["compressed"].astype(bool)
    k, _, _ = block_address(d[comp], req[comp, 2], req[comp, 3])
    return int(straddles(d[comp], k, ts.word_bits).sum())


SETS = list(support.CONFIGS) + ["combined"]


def _set(name):
    return support.combined_set() if name == "combined" else support.texture_set(name)


@pytest.mark.parametrize("one_port", [False, True], ids=["two_bank", "one_port"])
@pytest.mark.parametrize("name", SETS)
def test_bit_exact_random_and_adversarial_with_backpressure(name, one_port):
    ts = _set(name)
    adv = support.adversarial_requests(ts, seed=1)
    req = np.concatenate([support.random_requests(ts, 300, seed=2 + one_port), adv])
    # the adversarial set reaches every bit offset an index of each compressed level can start at
    d = lookup_descriptor(ts, adv[:, 0], adv[:, 1])
    for b in set(d["index_bits"][d["compressed"].astype(bool)].tolist()):
        reachable = {(k * b) % ts.word_bits for k in range(ts.word_bits)}
        sel = d["compressed"].astype(bool) & (d["index_bits"] == b)
        small = any((1 << int(r["log2w"]) >> int(r["log2bw"])) * (1 << int(r["log2h"]) >> int(r["log2bh"]))
                    < ts.word_bits for r in d[sel])
        assert small or reachable <= support.straddle_offsets(ts, adv[sel])
    p = compare_with_golden(ts, req, "pysim", stall=0.3 if one_port else 0.25, seed=3, one_port=one_port)
    assert p.straddles == _straddle_count(ts, req)
    assert p.stall_cycles["one_port_straddle"] == (p.straddles if one_port else 0)


@pytest.mark.parametrize("one_port", [False, True], ids=["two_bank", "one_port"])
def test_small_banks_end_to_end(one_port):
    """Every memory split into many small banks (the bank selects at work): same responses and cycles."""
    from vqtex.sim.backends import pysim as pysim_backend
    ts = _set("combined")
    req = np.concatenate([support.random_requests(ts, 200, seed=12), support.adversarial_requests(ts, seed=13)])
    p = pysim_backend.run(ts, req, stall=0.3, seed=14, one_port=one_port, bank_depth=8)
    g = simulate(ts, req, backend="golden", stall=0.3, seed=14, one_port=one_port)
    assert np.array_equal(p.responses, g.responses)
    assert (p.cycles, p.stall_cycles, p.straddles) == (g.cycles, g.stall_cycles, g.straddles)


@pytest.mark.parametrize("name", ["rgb_4x4_b8_mip", "yuv_4x4_b12_mip", "rgb_4x4_b12_w16"])
def test_throughput_one_per_cycle(name):
    """N requests with no backpressure complete in exactly N + LATENCY cycles, 8- and 12-bit alike."""
    ts = _set(name)
    req = support.random_requests(ts, 250, seed=7)
    p = compare_with_golden(ts, req, "pysim")
    assert p.cycles == len(req) + LATENCY
    assert p.stall_cycles == {"output_backpressure": 0, "one_port_straddle": 0}
    assert p.straddles == _straddle_count(ts, req)
    if ts.textures[0].index_bits == 12:
        assert p.straddles > 0            # straddles are free with the even/odd banks


@pytest.mark.parametrize("name", ["yuv_4x4_b12_mip", "rgb_4x4_b12_w16", "rgb_4x4_b8_mip"])
def test_one_port_penalty_exactly_one_cycle_per_straddle(name):
    ts = _set(name)
    req = support.random_requests(ts, 250, seed=8)
    s = _straddle_count(ts, req)
    p = compare_with_golden(ts, req, "pysim", one_port=True)
    assert p.cycles == len(req) + LATENCY + s
    assert p.stall_cycles == {"output_backpressure": 0, "one_port_straddle": s}
    if ts.textures[0].index_bits == 8:
        assert s == 0


def test_decode_every_texel_of_a_level():
    """An independent path: every texel of a 32x32 yuv411 level equals golden.fetch.decode."""
    ts = support.combined_set()
    t = 2
    h, w = 32, 32
    jj, ii = np.mgrid[0:h, 0:w]
    req = np.stack([np.full(h * w, t), np.zeros(h * w, np.int64), ii.ravel(), jj.ravel()], axis=1)
    p = simulate(ts, req, backend="pysim", stall=0.1, seed=9)
    assert np.array_equal(p.responses.reshape(h, w, 4), decode(ts, t, 0))


def test_latency_of_a_single_request():
    ts = support.texture_set("rgb_4x4_b8_mip")
    dut = TexelFetch(ts)
    assert dut.latency == LATENCY == len(STAGES) == 15
    req = (0, 1, 5, 7)
    seen = {}

    async def bench(ctx):
        ctx.set(dut.o.ready, 1)
        ctx.set(dut.i.p.texture, req[0])
        ctx.set(dut.i.p.level, req[1])
        ctx.set(dut.i.p.i, req[2])
        ctx.set(dut.i.p.j, req[3])
        ctx.set(dut.i.p.tag, 0x5A)
        ctx.set(dut.i.valid, 1)
        assert ctx.get(dut.i.ready)
        await ctx.tick()
        ctx.set(dut.i.valid, 0)
        for cycle in range(1, 20):
            if ctx.get(dut.o.valid):
                seen["cycle"] = cycle
                seen["rgba"] = [ctx.get(getattr(dut.o.p, c)) for c in "rgba"]
                seen["tag"] = ctx.get(dut.o.p.tag)
                break
            await ctx.tick()

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    assert seen["cycle"] == LATENCY
    assert seen["tag"] == 0x5A
    assert seen["rgba"] == fetch(ts, *[np.array([v]) for v in req])[0].tolist()


def test_irregular_input_and_output_never_lose_duplicate_or_reorder():
    """Requests with idle gaps, responses taken with random backpressure (stream helpers)."""
    ts = support.combined_set()
    req = support.random_requests(ts, 120, seed=10)
    dut = TexelFetch(ts, one_port=True, tag_width=7)
    rng = np.random.default_rng(11)
    gaps_in = rng.integers(0, 3, len(req)).tolist()
    gaps_out = rng.integers(0, 4, len(req)).tolist()
    got = []

    async def producer(ctx):
        for n, (t, L, i, j) in enumerate(req.tolist()):
            for _ in range(gaps_in[n]):
                await ctx.tick()
            await stream_put(ctx, dut.i, {"texture": t, "level": L, "i": i, "j": j, "tag": n % 128})

    async def consumer(ctx):
        for n in range(len(req)):
            for _ in range(gaps_out[n]):
                await ctx.tick()
            p = await stream_get(ctx, dut.o)
            got.append((p.tag, p.r, p.g, p.b, p.a))
        for _ in range(2 * LATENCY):      # nothing more comes out
            ctx.set(dut.o.ready, 1)
            assert not ctx.get(dut.o.valid)
            await ctx.tick()

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(producer)
    sim.add_testbench(consumer)
    sim.run()
    got = np.array(got)
    assert got[:, 0].tolist() == [n % 128 for n in range(len(req))]
    assert np.array_equal(got[:, 1:], fetch(ts, req[:, 0], req[:, 1], req[:, 2], req[:, 3]))


def test_simulate_rejects_bad_requests():
    ts = support.texture_set("rgb_4x4_b8_mip")
    with pytest.raises(RequestError):
        simulate(ts, np.array([[0, 0, 64, 0]]), backend="golden")
    with pytest.raises(RequestError):
        simulate(ts, np.array([[1, 0, 0, 0]]), backend="pysim")
    with pytest.raises(ValueError):
        simulate(ts, np.array([[0, 0, 0, 0]]), backend="nonesuch")
    with pytest.raises(ValueError):
        simulate(ts, np.array([[0, 0, 0, 0]]), stall=1.0)
    empty = simulate(ts, np.zeros((0, 4), np.int64), backend="pysim")
    assert (empty.cycles, empty.requests, empty.responses.shape) == (0, 0, (0, 4))
