"""The loadable cached unit (hw.memory.unit.CachedTexelFetch(geometry=, loadable=True)) on pysim: two
different sets loaded by bus writes into one simulation, each placed by the host at its own base
addresses in external memory; responses equal golden.fetch and every input acceptance, AR, response
transfer, cycle count, output backpressure and fill wait equals golden's cycle model with that
layout; the load takes golden's load_cycles; a reload empties the caches; the register map's base
registers read back, the index and raw regions answer with err."""

from __future__ import annotations

import numpy as np
import pytest
from amaranth.sim import Simulator

from vqtex.golden.fetch import fetch, random_requests
from vqtex.golden.geometry import Geometry
from vqtex.golden.memory.cache import CacheShape
from vqtex.golden.memory.system import Layout, MemoryConfig
from vqtex.golden.memory.timing import plan, run
from vqtex.golden.register_map import (BASE_REGISTERS, CONTROL, RegisterMap, expected_reads, load_cycles,
                                       load_writes, mapped)
from vqtex.hw.memory.unit import CachedTexelFetch
from vqtex.hw.texel_fetch import LATENCY
from vqtex.sim.backends import pysim
from vqtex.sim.backends.memory import run_phases
from vqtex.sim.streams import ready_pattern

from tests.support import texture_set
from tests.support.reload import reload_mid_stream

CONFIG = MemoryConfig(index_cache=CacheShape(256, 16, 2), raw_cache=CacheShape(128, 16, 2), prefetch=4,
                      latency=13, bus_bytes=16, bandwidth=8)


def _model(ts, req, cfg, layout, stall, seed):
    p = plan(ts, req, cfg, layout=layout)
    return p, run(p, cfg, LATENCY, lambda m: ready_pattern(seed, stall, m))


def _check(ts, req, cfg, layout, got, geometry, stall, seed, loaded=True):
    assert (got["responses"] == fetch(ts, *np.asarray(req).T)).all()
    p, model = _model(ts, req, cfg, layout, stall, seed)
    assert got["accept"] == model["accept"].tolist()
    assert got["ar"] == [g + 1 + j for g, m in zip(model["tag"].tolist(), p.misses.tolist()) for j in range(m)]
    assert got["addresses"] == p.address.tolist()
    assert got["transfer"] == model["transfer"].tolist()
    assert got["cycles"] == model["cycles"]
    assert got["backpressure"] == model["stall_cycles"]["output_backpressure"]
    assert got["fill_waits"] == model["stall_cycles"]["miss"] + model["stall_cycles"]["bandwidth"]
    assert got["load_cycles"] == (load_cycles(len(load_writes(ts, geometry, layout))) if loaded else None)
    return model


def test_two_sets_one_simulation():
    """Two sets of different formats (12-bit YUV indices with raw levels; 7-bit RGBA, 16-bit words
    would not share: both 32-bit here) at different base addresses, then the first again at a third
    place: each phase equal to golden from empty caches."""
    a, b = texture_set("yuv_4x4_b12_mip"), texture_set("rgb_4x4_b8_mip")
    g = Geometry.of(a).union(Geometry.of(b))
    ra, rb = random_requests(a, 30, seed=1), random_requests(b, 30, seed=2)
    phases = [(a, ra, Layout.at(a, 0x3000)), (b, rb, Layout.at(b, 0x10040, 0x25000)),
              (a, ra, Layout.at(a, 0x8, 0x9004))]
    out = run_phases(g, CONFIG, phases, backend="pysim", stall=0.2, seed=3)
    for (ts, req, layout), got in zip(phases, out):
        model = _check(ts, req, CONFIG, layout, got, g, 0.2, 3)
        assert model["bursts"] > 0
    # the bases moved the bursts: the third phase reads the first's words at other addresses (and,
    # its bases not line-aligned, in other lines)
    assert min(out[0]["addresses"]) >= 0x3000 and min(out[2]["addresses"]) < 0x1000


def test_reload_empties_the_caches():
    """The same set and stream twice, the set reloaded between: the second run misses as the first
    (a cache that kept its lines would run it with no burst)."""
    ts = texture_set("yuv_4x4_b12_mip")
    req = random_requests(ts, 25, seed=7)
    layout = Layout.of(ts)
    big = MemoryConfig(index_cache=CacheShape(4096, 16, 2), raw_cache=CacheShape(4096, 16, 2), prefetch=4,
                       latency=20, bus_bytes=16)
    out = run_phases(Geometry.of(ts), big, [(ts, req, layout), (ts, req, layout)], backend="pysim")
    for got in out:
        _check(ts, req, big, layout, got, Geometry.of(ts), 0.0, 0)
    assert out[0]["ar"] == out[1]["ar"] and len(out[1]["ar"]) > 0


def test_register_map_and_errors():
    """After a load: the base registers, the matrix and descriptor words read back as golden's
    expected_reads says; the index and raw regions (in external memory) and region 5 answer err for
    reads and writes, as ``mapped`` says; a base written unaligned reads back with its low bits 0."""
    ts = texture_set("yuv_4x4_b12_mip")
    g = Geometry.of(ts)
    layout = Layout.at(ts, 0x1000, 0x20000)
    rmap = RegisterMap(g, external=True)
    dut = CachedTexelFetch(None, CONFIG, geometry=g, loadable=True)
    writes = load_writes(ts, g, layout).astype(np.int64)
    assert not np.isin(writes[:, 0] >> rmap.offset_bits, [2, 4]).any()        # no index or raw words
    ctrl = rmap.control
    reads = [rmap.address("control", ctrl[n][0]) for n in ("INDEX_BASE", "RAW_BASE", "MATRIX_RY", "ID")]
    reads += [rmap.address("descriptors", k) for k in (0, 1, 5)]
    bad = [rmap.address("index", 0), rmap.address("raw", 3), (5 << rmap.offset_bits)]
    addrs = [int(a) for a in reads + bad]
    ops = [(a, 0, 0) for a in addrs] + [(a, 1, 1) for a in (int(x) for x in bad)]
    ops += [(int(rmap.address("control", ctrl["INDEX_BASE"][0])), 0x12347, 1),
            (int(rmap.address("control", ctrl["INDEX_BASE"][0])), 0, 0)]
    got = {}

    async def bench(ctx):
        w = np.concatenate([writes, np.ones((len(writes), 1), np.int64)], axis=1)
        _, err, _ = await pysim.bus_transfers(ctx, dut.bus, w)
        assert not any(err)
        got["data"], got["err"], _ = await pysim.bus_transfers(ctx, dut.bus, ops)

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    data, err = expected_reads(ts, g, addrs, layout)
    n = len(addrs)
    assert got["data"][:n] == data.tolist() and got["err"][:n] == err.tolist()
    assert got["data"][0] == 0x1000 and got["data"][1] == 0x20000
    assert got["err"][n:n + len(bad)] == [True] * len(bad)
    assert [mapped(rmap, a, True) for a in bad] == [False] * len(bad)
    assert got["data"][-1] == 0x12344 and not got["err"][-1]            # 32-bit words: bits 0, 1 dropped
    assert set(BASE_REGISTERS) <= set(ctrl) and not set(BASE_REGISTERS) & set(CONTROL)


def test_layout_refusals():
    ts = texture_set("yuv_4x4_b12_mip")
    with pytest.raises(ValueError, match="multiple of 4 bytes"):
        Layout.at(ts, 2)
    with pytest.raises(ValueError, match="at or above"):
        Layout.at(ts, 0x1000, 0x1000)
    with pytest.raises(ValueError, match="4 GB"):
        Layout.at(ts, 0xFFFFF000)


def _valid_in(req, *sets):
    """The requests of ``req`` inside their level in every one of ``sets``."""
    ok = np.ones(len(req), bool)
    for ts in sets:
        inside = req[:, 0] < ts.n_textures
        d = ts.descriptors[np.where(inside, req[:, 0], 0), req[:, 1]]
        ok &= inside & d["valid"].astype(bool) & (req[:, 2] < (1 << d["log2w"].astype(np.int64))) & (
            req[:, 3] < (1 << d["log2h"].astype(np.int64)))
    return req[ok]


def test_drain_rule_with_misses_in_flight():
    """A host loads another set (at other addresses of the same external memory) while requests wait
    on line fills (100 cycles of latency): no write is accepted (``stall``) until every request
    accepted before it has left the unit; those responses are the old set's, the later ones the new
    set's; none is lost or reordered. (Without the reader's count in the drain rule the writes go in,
    and their cache flush resets the reader, while references wait in its FIFO: this test fails.)"""
    from vqtex.sim.backends.axi_memory import AxiMemory
    from vqtex.sim.backends.pysim import pack_rows
    a, b = texture_set("yuv_4x4_b12_mip"), texture_set("rgb_4x4_b8_mip")
    g = Geometry.of(a).union(Geometry.of(b))
    la, lb = Layout.of(a), Layout.at(b, 0x10000)
    image = bytearray(lb.image(b))                  # one external memory holding both sets
    image[:la.end] = la.image(a)[:la.end]
    cfg = MemoryConfig(index_cache=CacheShape(256, 16, 2), raw_cache=CacheShape(128, 16, 2), prefetch=8,
                       latency=100, bus_bytes=16)
    dut = CachedTexelFetch(None, cfg, geometry=g, loadable=True)
    req = _valid_in(random_requests(a, 200, seed=5), a, b)[:40]
    old, new = fetch(a, *req.T), fetch(b, *req.T)
    packed = pack_rows(dut.i.p.shape(), ("texture", "level", "i", "j"), req, 8)
    slave = AxiMemory(bytes(image), cfg.make_memory(), cfg.bus_bytes)
    log, k = reload_mid_stream(dut, slave, packed, load_writes(a, g, la).astype(np.int64),
                               load_writes(b, g, lb).astype(np.int64), tag_bits=8, limit=20000)
    rgba = np.array(log["rgba"], np.uint8)
    assert (rgba[:k] == old[:k]).all() and (rgba[k:] == new[k:]).all()
    assert not (old[k:] == new[k:]).all()


def test_initial_contents_serve_without_a_load():
    """A loadable cached unit given a set as initial contents (tables, codebook, matrix, and the bases
    of ``Layout.of``) serves it before any load, as golden's model says."""
    from vqtex.sim.backends.memory import _pysim
    ts = texture_set("rgb_4x4_b8_mip")
    req = random_requests(ts, 25, seed=11)
    dut = CachedTexelFetch(ts, CONFIG, geometry=Geometry.of(ts), loadable=True)
    got = _pysim(dut, [(None, ts, req, Layout.of(ts))], CONFIG, 0.0, 0)[0]
    _check(ts, req, CONFIG, Layout.of(ts), got, Geometry.of(ts), 0.0, 0, loaded=False)
