"""The loadable texture filter through the memory system (hw.memory.filter.CachedTextureFilter(
geometry=, loadable=True)) on the compiled backends: one library per geometry and cache
configuration loads one set after another by bus writes (sim.backends.filter_memory.run_phases, the
loadable cached unit's load path: descriptors, codebook, matrix, base registers), the drivers' AXI
slave holding each set's memory image at the layout its base registers name; every phase's colours
equal golden's, and the cycles, every AR's cycle, the bytes read and the lanes' fill waits equal the
cycle model of the cached filter (golden.memory.filter) with that layout; each load takes golden's
load_cycles. CXXRTL: topspin's then town's pixels on one build of the ``paper`` geometry; Verilator:
small sets, the first reloaded after the second, fixed latency and DDR3; with output backpressure
(the model's ready pattern) on both."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from tests.support import edge_pixels, filter_set, need, scene_set, shared_cache, texture_set
from vqtex.golden import filter as spec
from vqtex.golden.geometry import Geometry, preset
from vqtex.golden.memory.cache import CacheShape
from vqtex.golden.memory.system import Layout, MemoryConfig
from vqtex.golden.register_map import load_cycles, load_writes
from vqtex.hw.filter.footprint import level_table
from vqtex.sim.backends.filter import golden_colors
from vqtex.sim.backends.filter_memory import run_phases, simulate_cached_filter

#: The CXXRTL test's one build: one lane (the build stays short: four lanes of ``paper`` take minutes;
#: the Verilator test runs four lanes) with 1 KB and 512-byte caches (32-byte lines, 2 ways), an
#: 8-entry FIFO, a 16-byte bus (the memory model is chosen per run).
PAPER = MemoryConfig(index_cache=CacheShape(1024, 32, 2), raw_cache=CacheShape(512, 32, 2), prefetch=8, latency=100)


@pytest.fixture(scope="module", autouse=True)
def cache():
    with shared_cache():
        yield


def frame_pixels(name, n, mode="bilinear"):
    """``n`` consecutive pixels from the middle of the scene's frame 0 (filter inputs, the set's frac)."""
    from vqtex.golden.render import plan_frame
    from vqtex.golden.render.pyramid import VQSource
    from vqtex.golden.render.scene import load_scene
    ts = scene_set(name)
    sampler = plan_frame(load_scene(name), 0, VQSource(ts), mode)
    sampler.requests(sampler.fragments)
    px = sampler.filter_inputs(sampler.fragments, sampler.frac)
    start = len(px["texture"]) // 2
    return ts, {k: np.asarray(v)[start:start + n] for k, v in px.items()}, sampler.frac


def check_phases(geometry, cfg, phases, backend, lanes, stall=0.0, seed=0):
    out = run_phases(geometry, cfg, phases, backend=backend, lanes=lanes, stall=stall, seed=seed)
    assert len(out) == len(phases)
    for (ts, px, layout, frac), got in zip(phases, out):
        model = simulate_cached_filter(ts, px, cfg, backend="golden", lanes=lanes, frac=frac, geometry=geometry,
                                       layout=layout, stall=stall, seed=seed)
        assert (got.colors == golden_colors(ts, px, frac)).all()
        assert got.cycles == model.cycles and got.stall_cycles == model.stall_cycles
        assert got.memory["ar"].tolist() == model.memory["ar"].tolist()
        assert got.memory["memory_bytes"] == model.memory["memory_bytes"]
        assert got.memory["fill_waits"] == model.memory["fill_waits"] > 0
        assert got.load_cycles == load_cycles(len(load_writes(ts, geometry, layout or Layout.of(ts))))
        assert model.memory["bursts"] > 0
    return out


def test_topspin_then_town_one_cxxrtl_build():
    """The ``paper`` geometry's loadable filter through memory, one CXXRTL library: topspin's set
    loaded and 1,000 of its frame's bilinear pixels filtered, then town's (another codebook,
    descriptor table, level table, matrix; its layout 1 MB up) and 600 trilinear pixels."""
    need("g++")
    a, pa, fa = frame_pixels("topspin", 1000)
    b, pb, fb = frame_pixels("town", 600, "trilinear")
    check_phases(preset("paper"), PAPER, [(a, pa, None, fa), (b, pb, Layout.at(b, 0x100000), fb)], "cxxrtl", 1,
                 stall=0.2, seed=5)


def test_verilator_small_sets_reloaded():
    """filter_set, a YUV set of other shapes, then filter_set again at other addresses; 4 lanes,
    caches smaller than the sets (lines replaced), fixed memory of 40 cycles, then DDR3."""
    need("g++", "verilator")
    a, b = filter_set(), texture_set("yuv_4x4_b12_mip", images=2)
    g = Geometry.of(a).union(Geometry.of(b))
    cfg = MemoryConfig(index_cache=CacheShape(128, 16, 2), raw_cache=CacheShape(64, 16, 2), bus_bytes=16,
                       prefetch=4, latency=40)

    def pixels(ts, n, seed):
        frac = spec.coordinate_frac_bits(level_table(ts).max_log2)
        return edge_pixels(level_table(ts), frac, n, seed), frac

    (pa, fa), (pb, fb) = pixels(a, 300, 1), pixels(b, 300, 2)
    phases = [(a, pa, Layout.at(a, 0x3000), fa), (b, pb, None, fb), (a, pa, Layout.at(a, 0x44, 0x9000), fa)]
    check_phases(g, cfg, phases, "verilator", 4, stall=0.3, seed=4)
    check_phases(g, dataclasses.replace(cfg, kind="dram"), phases[:2], "verilator", 4)
