"""The texture filter through the memory system (hw.memory.filter.CachedTextureFilter) compiled with
CXXRTL, its AXI4 master answered by the drivers' slave (drivers/axi_slave.h) from the C++ twin of the
golden memory models, on a scene frame (and on Verilator, from the exported Verilog, on random
edge-case pixels of a small set with two lanes): colours equal golden's frame bit for bit, and the cycles,
every AR's cycle, the bytes read and the lanes' fill waits equal the cycle model
(golden.memory.filter) exactly; fixed latency and DDR3 from one build (the memory model is the
driver's, chosen per run); with random output backpressure too (golden.memory.filter's ready pattern)."""

from __future__ import annotations

import numpy as np
import pytest

from tests.support import need, shared_cache
from vqtex.golden.memory.cache import CacheShape
from vqtex.golden.memory.system import MemoryConfig
from vqtex.sim.backends.filter import golden_colors
from vqtex.sim.backends.filter_memory import simulate_cached_filter

#: test_cached_compiled's scene caches: 512- and 256-byte caches of 32-byte lines, a 4-entry FIFO.
SCENE = dict(index_cache=CacheShape(512, 32, 4), raw_cache=CacheShape(256, 32, 4), prefetch=4)


@pytest.fixture(scope="module", autouse=True)
def cache():
    with shared_cache():
        yield


def scene_pixels(mode):
    from vqtex.golden.render import plan_frame
    from vqtex.golden.render.pyramid import VQSource
    from vqtex.golden.render.scene import build_texture_set, parse_scene
    from tests.support import NEED_SCENE as SCENE_TOML
    scene = parse_scene(SCENE_TOML, "small.toml")
    ts = build_texture_set(scene)
    sampler = plan_frame(scene, 1, VQSource(ts), mode)
    sampler.requests(sampler.fragments)
    return ts, sampler.filter_inputs(sampler.fragments, sampler.frac), sampler.frac


def test_scene_frame_equals_the_cycle_model():
    need("g++")
    ts, px, frac = scene_pixels("trilinear")
    assert len(px["texture"]) > 500
    want = golden_colors(ts, px, frac)
    for cfg in (MemoryConfig(**SCENE, latency=100), MemoryConfig(**SCENE, kind="dram", controller_cycles=20)):
        rtl = simulate_cached_filter(ts, px, cfg, backend="cxxrtl", lanes=4)
        model = simulate_cached_filter(ts, px, cfg, backend="golden", lanes=4)
        assert (rtl.colors == want).all()
        assert rtl.cycles == model.cycles
        assert rtl.memory["ar"].tolist() == model.memory["ar"].tolist()
        assert rtl.memory["memory_bytes"] == model.memory["memory_bytes"]
        assert rtl.memory["fill_waits"] == model.memory["fill_waits"] > 0
        assert model.memory["bursts"] > 0 and rtl.cycles > model.memory["on_chip_cycles"] + 4
    cfg = MemoryConfig(**SCENE, latency=13)
    rtl = simulate_cached_filter(ts, px, cfg, backend="cxxrtl", lanes=4, stall=0.25, seed=2)
    model = simulate_cached_filter(ts, px, cfg, backend="golden", lanes=4, stall=0.25, seed=2)
    assert (rtl.colors == want).all() and rtl.stall_cycles["output_backpressure"] > 0
    assert rtl.cycles == model.cycles and rtl.stall_cycles == model.stall_cycles
    assert rtl.memory["ar"].tolist() == model.memory["ar"].tolist()


def test_verilator_equals_the_cycle_model():
    need("g++", "verilator")
    from tests.support import edge_pixels, filter_set
    from vqtex.golden import filter as spec
    from vqtex.hw.filter.footprint import level_table
    ts = filter_set()
    frac = spec.coordinate_frac_bits(level_table(ts).max_log2)
    px = edge_pixels(level_table(ts), frac, 500, 4)
    small = dict(index_cache=CacheShape(128, 16, 2), raw_cache=CacheShape(64, 16, 2), prefetch=4, bus_bytes=16)
    for cfg in (MemoryConfig(**small, latency=20), MemoryConfig(**small, kind="dram")):
        rtl = simulate_cached_filter(ts, px, cfg, backend="verilator", lanes=2)
        model = simulate_cached_filter(ts, px, cfg, backend="golden", lanes=2)
        assert (rtl.colors == golden_colors(ts, px, frac)).all()
        assert rtl.cycles == model.cycles
        assert rtl.memory["ar"].tolist() == model.memory["ar"].tolist()
        assert rtl.memory["fill_waits"] == model.memory["fill_waits"] > 0
