"""The loadable texture filter through the memory system (hw.memory.filter.CachedTextureFilter(
geometry=, loadable=True)) on pysim: two sets of different formats loaded by bus writes into one
simulation, each placed by the host at its own base addresses in external memory, then the first
again elsewhere: colours equal golden's, and the cycles, every AR's cycle, the bytes read, the
lanes' fill waits and the load's cycles equal golden's cycle model of the cached filter with that
layout (golden.memory.filter) and golden.register_map.load_cycles; a reload empties every lane's
caches; the base registers read back over the bus; with output backpressure, colours and order."""

from __future__ import annotations

import numpy as np
import pytest
from amaranth.sim import Simulator

from tests import support
from tests.support import edge_pixels, filter_set
from tests.support.reload import reload_mid_stream
from vqtex.golden import filter as spec
from vqtex.golden.geometry import Geometry
from vqtex.golden.memory.cache import CacheShape
from vqtex.golden.memory.system import Layout, MemoryConfig
from vqtex.golden.register_map import RegisterMap, load_cycles, load_writes
from vqtex.hw.filter.footprint import level_table
from vqtex.hw.memory.filter import CachedTextureFilter
from vqtex.sim.backends import pysim
from vqtex.sim.backends.filter import golden_colors
from vqtex.sim.backends.filter_memory import run_phases, simulate_cached_filter

CONFIG = MemoryConfig(index_cache=CacheShape(128, 16, 2), raw_cache=CacheShape(64, 16, 2), prefetch=4,
                      latency=20, bus_bytes=16, bandwidth=8)


def _pixels(ts, n, seed):
    frac = spec.coordinate_frac_bits(level_table(ts).max_log2)
    return edge_pixels(level_table(ts), frac, n, seed), frac


def _check(ts, px, frac, layout, got, geometry, cfg=CONFIG, lanes=2):
    model = simulate_cached_filter(ts, px, cfg, backend="golden", lanes=lanes, frac=frac, geometry=geometry,
                                   layout=layout)
    assert (got.colors == golden_colors(ts, px, frac)).all()
    assert got.cycles == model.cycles
    assert got.memory["ar"].tolist() == model.memory["ar"].tolist()
    assert got.memory["memory_bytes"] == model.memory["memory_bytes"]
    assert got.memory["fill_waits"] == model.memory["fill_waits"] > 0
    assert got.load_cycles == model.load_cycles == load_cycles(len(load_writes(ts, geometry, layout)))
    return model


def test_two_sets_one_simulation_and_a_reload():
    """filter_set (rgb, yuv411 12-bit, rgba; raw levels) at 0x2000, a second set of other formats
    at 0x10044 (not line-aligned) with its raw memory at 0x25000, then the first again where it was:
    each phase as golden's model from empty caches; the reload's bursts are the first phase's, at
    the same cycles (caches that kept the first phase's lines would not read them again)."""
    a, b = filter_set(), support.texture_set("yuv_4x4_b12_mip", images=2)
    g = Geometry.of(a).union(Geometry.of(b))
    (pa, fa), (pb, fb) = _pixels(a, 14, 1), _pixels(b, 10, 2)
    phases = [(a, pa, Layout.at(a, 0x2000), fa), (b, pb, Layout.at(b, 0x10044, 0x25000), fb),
              (a, pa, Layout.at(a, 0x2000), fa)]
    out = run_phases(g, CONFIG, phases, backend="pysim", lanes=2)
    for (ts, px, layout, frac), got in zip(phases, out):
        _check(ts, px, frac, layout, got, g)
    assert out[0].memory["bursts"] > 0
    assert out[2].memory["ar"].tolist() == out[0].memory["ar"].tolist()     # a reload empties the caches
    assert out[2].cycles == out[0].cycles


def test_base_registers_read_back():
    """After a load over the filter's one port: INDEX_BASE and RAW_BASE read back the layout's."""
    ts = filter_set()
    g = Geometry.of(ts)
    layout = Layout.at(ts, 0x1000, 0x20000)
    dut = CachedTextureFilter(None, CONFIG, lanes=2, geometry=g, loadable=True)
    rmap = RegisterMap(g, external=True)
    assert dut.register_map.addr_bits == rmap.addr_bits
    writes = load_writes(ts, g, layout).astype(np.int64)
    reads = [(int(rmap.address("control", rmap.control[n][0])), 0, 0) for n in ("INDEX_BASE", "RAW_BASE")]
    bad = [(int(rmap.address("index", 0)), 0, 0)]
    got = {}

    async def bench(ctx):
        await pysim.load_over_bus(ctx, dut.bus, writes)
        got["data"], got["err"], _ = await pysim.bus_transfers(ctx, dut.bus, reads + bad)

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    assert got["data"][:2] == [0x1000, 0x20000] and got["err"] == [False, False, True]


def test_backpressure_keeps_colours_and_order():
    ts = filter_set()
    px, frac = _pixels(ts, 12, 5)
    got = simulate_cached_filter(ts, px, CONFIG, backend="pysim", lanes=4, frac=frac, stall=0.4, seed=2,
                                 geometry=Geometry.of(ts))
    assert (got.colors == golden_colors(ts, px, frac)).all()       # (run_stream checks every tag's order)
    assert got.stall_cycles["output_backpressure"] > 0 and got.load_cycles > 0


def test_refusals():
    ts = filter_set()
    px, frac = _pixels(ts, 4, 0)
    with pytest.raises(ValueError, match="layout needs the loadable"):
        simulate_cached_filter(ts, px, CONFIG, backend="golden", layout=Layout.of(ts))
    with pytest.raises(TypeError, match="Geometry"):
        CachedTextureFilter(None, CONFIG, loadable=True)
    small = Geometry(**{**Geometry.of(ts).to_dict(), "codebook_entries": 2})
    from vqtex.golden.register_map import LoadError
    with pytest.raises(LoadError, match="codebook"):
        simulate_cached_filter(ts, px, CONFIG, backend="pysim", geometry=small)


def test_drain_rule_with_misses_in_flight():
    """A host reloads the set at another place in external memory 20 cycles into a stream whose
    references wait on 100-cycle fills: no write is accepted until every pixel accepted before it
    has left the filter; no pixel enters during the load; every colour is golden's, in order; the
    bursts before the load read the old place, those after it the new one. (Without the pixel count
    in the drain rule the writes go in, and empty the caches, while references wait: this fails.)"""
    from vqtex.hw.address import COORD_BITS
    from vqtex.sim.backends.axi_memory import AxiMemory
    from vqtex.sim.backends.design import FIELDS
    ts = filter_set()
    g = Geometry.of(ts)
    old, new = Layout.of(ts), Layout.at(ts, 0x10000)
    image = bytearray(new.image(ts))                # one external memory holding the set twice
    image[:old.end] = old.image(ts)[:old.end]
    cfg = MemoryConfig(index_cache=CacheShape(128, 16, 2), raw_cache=CacheShape(64, 16, 2), prefetch=4,
                       latency=100, bus_bytes=16)
    dut = CachedTextureFilter(None, cfg, lanes=2, tag_width=16, geometry=g, loadable=True)
    px, frac = _pixels(ts, 24, 9)
    shift = spec.coordinate_frac_bits(COORD_BITS) - frac
    rows = np.stack([np.asarray(px[f], np.int64) << (shift if f in ("s", "t") else 0) for f in FIELDS], 1)
    packed = pysim.pack_rows(dut.i.p.shape(), FIELDS, rows, 16)
    slave = AxiMemory(bytes(image), cfg.make_memory(), cfg.bus_bytes)
    log, k = reload_mid_stream(dut, slave, packed, load_writes(ts, g, old).astype(np.int64),
                               load_writes(ts, g, new).astype(np.int64), tag_bits=16, limit=30000)
    assert (np.array(log["rgba"], np.uint8) == golden_colors(ts, px, frac)).all()
    first_ack = min(log["ack"])
    ar, addresses = np.array(slave.ar), np.array(slave.addresses)
    assert (addresses[ar < first_ack] < 0x10000).all() and (addresses[ar > max(log["ack"])] >= 0x10000).all()
    assert (ar > max(log["ack"])).any()


def test_initial_contents_serve_without_a_load():
    """A loadable filter given a set as initial contents (tables, codebook, matrix, level table, the
    bases of ``Layout.of``) filters it before any load, in the baked filter's cycles."""
    from vqtex.hw.address import COORD_BITS
    from vqtex.sim.backends.design import FIELDS
    from vqtex.sim.backends.filter_memory import _pysim
    ts = filter_set()
    px, frac = _pixels(ts, 10, 4)
    dut = CachedTextureFilter(ts, CONFIG, lanes=2, tag_width=16, geometry=Geometry.of(ts), loadable=True)
    shift = spec.coordinate_frac_bits(COORD_BITS) - frac
    rows = np.stack([np.asarray(px[f], np.int64) << (shift if f in ("s", "t") else 0) for f in FIELDS], 1)
    got = _pysim(dut, [(None, ts, rows, Layout.of(ts), px["mode"])], CONFIG, 2, 0.0, 0)[0]
    baked = simulate_cached_filter(ts, px, CONFIG, backend="golden", lanes=2, frac=frac)
    assert (got.colors == golden_colors(ts, px, frac)).all()
    assert got.cycles == baked.cycles and got.memory["ar"].tolist() == baked.memory["ar"].tolist()
    assert got.load_cycles is None
