"""The loadable cached unit (hw.memory.unit.CachedTexelFetch(geometry=, loadable=True)) on the compiled
backends: one library per geometry and cache configuration loads one set after another by bus writes
(sim.backends.memory.run_phases: descriptors, codebook, matrix, base registers), the drivers' AXI
slave holding each set's memory image at the layout its base registers name; every phase's
responses equal golden.fetch and every input acceptance, AR (cycle and address), response transfer,
the cycles and the stall counts equal golden's cycle model with that layout; each load takes golden's
load_cycles. CXXRTL: topspin then town on one build of the ``paper`` geometry; both backends: small
sets, a set reloaded after another at other addresses, DDR3."""

from __future__ import annotations

import dataclasses

import pytest

from tests.support import assert_cached_run, locality_stream, need, scene_set, shared_cache, texture_set
from vqtex.golden.geometry import Geometry, preset
from vqtex.golden.memory.cache import CacheShape
from vqtex.golden.memory.system import Layout, MemoryConfig
from vqtex.golden.register_map import load_cycles, load_writes
from vqtex.sim.backends.memory import run_phases


#: The CXXRTL tests' one build: the ``paper`` geometry behind 1 KB and 512-byte caches (32-byte lines,
#: 2 ways), a 16-entry FIFO, a 16-byte bus (the memory model is chosen per run).
PAPER = MemoryConfig(index_cache=CacheShape(1024, 32, 2), raw_cache=CacheShape(512, 32, 2), prefetch=16, latency=37)


@pytest.fixture(scope="module", autouse=True)
def cache():
    with shared_cache():
        yield


def check_phases(geometry, cfg, phases, backend, stall, seed):
    out = run_phases(geometry, cfg, phases, backend=backend, stall=stall, seed=seed, trace=True)
    assert len(out) == len(phases)
    for (ts, req, layout), got in zip(phases, out):
        layout = layout or Layout.of(ts)
        model = assert_cached_run(got, ts, req, cfg, stall, seed, layout)
        assert got["load_cycles"] == load_cycles(len(load_writes(ts, geometry, layout)))
        assert model["bursts"] > 0
    return out


def test_topspin_then_town_one_cxxrtl_build():
    """The ``paper`` geometry's loadable cached unit, one CXXRTL library: topspin's set loaded and
    fetched, then town's (another codebook, descriptor table, matrix, and a layout 1 MB up)."""
    need("g++")
    a, b = scene_set("topspin"), scene_set("town")
    out = check_phases(preset("paper"), PAPER, [(a, locality_stream(a, 3000, 1), None),
                                              (b, locality_stream(b, 3000, 2), Layout.at(b, 0x100000))], "cxxrtl", 0.2, 4)
    assert min(out[1]["addresses"]) >= 0x100000


@pytest.mark.parametrize("backend", ["cxxrtl", "verilator"])
def test_small_sets_reloaded(backend):
    """Two small sets, then the first again at other addresses; fixed memory of 100 cycles, then DDR3.
    CXXRTL: the ``paper`` build of the test above; Verilator: the sets' own geometry behind caches
    smaller than their index memories (lines replaced)."""
    need("g++", *(["verilator"] if backend == "verilator" else []))
    a, b = texture_set("yuv_4x4_b12_mip"), texture_set("rgb_4x4_b8_mip")
    if backend == "cxxrtl":
        g, cfg = preset("paper"), PAPER
    else:
        g = Geometry.of(a).union(Geometry.of(b))
        cfg = MemoryConfig(index_cache=CacheShape(128, 16, 2), raw_cache=CacheShape(64, 16, 2), bus_bytes=16,
                           prefetch=16)
    phases = [(a, locality_stream(a, 1500, 1), Layout.at(a, 0x3000)), (b, locality_stream(b, 1500, 2), None),
              (a, locality_stream(a, 1500, 3), None)]
    check_phases(g, dataclasses.replace(cfg, latency=100), phases, backend, 0.3, 4)
    check_phases(g, dataclasses.replace(cfg, kind="dram"), phases[:2], backend, 0.1, 5)
