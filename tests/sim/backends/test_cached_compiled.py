"""The cached unit (hw.memory.unit.CachedTexelFetch) on the compiled backends, CXXRTL and Verilator,
its AXI4 master answered by the drivers' slave (drivers/axi_slave.h) from the C++ twin of the golden
memory models: responses equal golden.fetch bit for bit, and every input acceptance, every AR, every
response transfer, the cycles and the stall counts equal the golden cycle model
(golden.memory.timing with the texel pipeline's LATENCY). Random streams of a few thousand requests
with locality and a scene frame; random output backpressure; memory latencies 1 to 300, the DDR3
model; the blocking and the prefetching cache. The configurations are few on purpose: the memory
model is the driver's, chosen per run, so one build per cache shape serves every latency and model
(three builds per backend; tests/sim/cli/test_memory_cli.py uses the same shapes)."""

from __future__ import annotations

import pytest

from tests.support import assert_cached_run, locality_stream, need, shared_cache, texture_set
from vqtex.golden.memory.cache import CacheShape
from vqtex.golden.memory.system import Layout, MemoryConfig
from vqtex.sim.backends.memory import run_compiled
from vqtex.sim.backends.toolchain import ToolchainError

BACKENDS = ["cxxrtl", "verilator"]
#: Caches smaller than the set's index and raw memories (lines are replaced, under waiting references
#: too): vqtex sim's --cache-size 128 --raw-cache-size 64 --cache-line 16 --cache-ways 2.
SMALL = dict(index_cache=CacheShape(128, 16, 2), raw_cache=CacheShape(64, 16, 2), bus_bytes=16)
#: test_memory_cli's render: 512- and 256-byte caches of 32-byte lines, a 4-entry FIFO.
SCENE = dict(index_cache=CacheShape(512, 32, 4), raw_cache=CacheShape(256, 32, 4), prefetch=4)


@pytest.fixture(scope="module", autouse=True)
def cache():
    with shared_cache():
        yield


def _need(backend):
    need("g++", *(["verilator"] if backend == "verilator" else []))


def check(ts, req, cfg, backend, stall, seed):
    """Run on ``backend`` and compare everything with golden; returns the model's dict."""
    got = run_compiled(ts, req, cfg, backend, stall, seed, trace=True)
    return assert_cached_run(got, ts, req, cfg, stall, seed)


@pytest.mark.parametrize("backend", BACKENDS)
def test_prefetching_equals_golden(backend):
    _need(backend)
    ts = texture_set("yuv_4x4_b12_mip")             # 12-bit indices (straddles) and raw levels
    req = locality_stream(ts, 3000, seed=5)
    for latency, bandwidth, stall in ((1, 16, 0.0), (37, 4, 0.4), (300, 16, 0.2)):
        m = check(ts, req, MemoryConfig(**SMALL, prefetch=16, latency=latency, bandwidth=bandwidth), backend, stall,
                  latency)
        assert m["bursts"] > 200 and m["stall_cycles"]["miss"] > 0 and m["stall_cycles"]["victim"] > 0
    m = check(ts, req, MemoryConfig(**SMALL, prefetch=16, kind="dram", controller_cycles=9), backend, 0.3, 7)
    assert m["memory"].refreshes > 0                 # refresh in the loop too


@pytest.mark.parametrize("backend", BACKENDS)
def test_blocking_equals_golden(backend):
    _need(backend)
    ts = texture_set("yuv_4x4_b12_mip")
    req = locality_stream(ts, 1500, seed=8)
    for latency, stall in ((1, 0.5), (300, 0.0)):
        m = check(ts, req, MemoryConfig(**SMALL, prefetch=1, latency=latency), backend, stall, latency)
        assert m["stall_cycles"]["fifo_full"] > 0
    check(ts, req, MemoryConfig(**SMALL, prefetch=1, kind="dram"), backend, 0.1, 2)


@pytest.mark.parametrize("backend", BACKENDS)
def test_scene_frame_equals_golden(backend):
    """A frame of a scene (trilinear: the requests of a rendered image, in raster order)."""
    _need(backend)
    from vqtex.golden.render.frame import frame_requests
    from vqtex.golden.render.scene import build_texture_set, parse_scene
    from tests.support import NEED_SCENE as SCENE_TOML
    scene = parse_scene(SCENE_TOML, "small.toml")
    ts = build_texture_set(scene)
    req, _ = frame_requests(scene, 1, ts, "trilinear")
    assert len(req) > 5000
    for latency, stall in ((100, 0.0), (13, 0.25)):
        m = check(ts, req, MemoryConfig(**SCENE, latency=latency), backend, stall, 1)
        assert m["bursts"] > 0
    check(ts, req, MemoryConfig(**SCENE, kind="dram"), backend, 0.0, 0)


def test_default_caches_equal_golden():
    """The command line's default caches (16 KB index, 4 KB raw, 32-byte lines, 4 ways: 640 lines)
    build on CXXRTL (in about 30 s: the caches' state is LUT RAM, hw.memory.reader) and match golden
    on a stream over a set larger than both caches (every set's lines replaced)."""
    need("g++")
    from vqtex.golden.encode import encode
    from tests.support.sets import image
    ts = encode([image((256, 256), 20), image((256, 256), 21)], block=(2, 2), codebook_size=16, color="rgb",
                index_bits=12, mipmaps=True, raw_below=64, seed=3)
    assert len(ts.index_words) * 4 > 2 * 16384 and len(ts.raw_words) * 4 > 2 * 4096
    req = locality_stream(ts, 8000, seed=9)
    for latency, stall in ((1, 0.0), (60, 0.3)):
        m = check(ts, req, MemoryConfig(latency=latency), "cxxrtl", stall, latency)
        assert m["bursts"] > (16384 + 4096) // 32 and m["stall_cycles"]["miss"] > 0     # more fills than lines


def test_axi_slave_refuses_what_it_does_not_hold():
    """The drivers' slave checks the master's side: a memory image shorter than the bursts the
    stream needs stops the run with the protocol error (as sim.backends.axi_memory does on pysim)."""
    need("g++")
    from vqtex.sim.backends.cxxrtl import batch_layout, open_design, run_checked
    from vqtex.sim.backends.memory import build_cached
    from vqtex.sim.backends.memory_model_cxx import model_params
    ts = texture_set("yuv_4x4_b12_mip")
    cfg = MemoryConfig(**SMALL, prefetch=16, latency=5)
    req = locality_stream(ts, 200, seed=1)
    lib, info, _ = open_design(build_cached(ts, cfg, "cxxrtl"))
    try:
        with pytest.raises(ToolchainError, match="no external memory configured"):
            run_checked(lib, req, batch_layout(info), n=len(req), transfers=len(req), latency=info.latency,
                        worst=100000, stall=0.0, seed=0, tag_width=8)
        kind, params = model_params(cfg.make_memory())
        lib.configure_axi(Layout.of(ts).image(ts)[:4096], cfg.bus_bytes, kind, params)
        with pytest.raises(ToolchainError, match="AXI protocol: cycle [0-9]+: burst at 0x[0-9a-f]+ of 1 beats "
                                                 "outside the memory"):
            run_checked(lib, req, batch_layout(info), n=len(req), transfers=len(req), latency=info.latency,
                        worst=100000, stall=0.0, seed=0, tag_width=8)
    finally:
        lib.close()


def test_verilator_sees_no_combinational_cycle(tmp_path):
    """Verilator lints the exported cached unit without UNOPTFLAT (a combinational cycle as it orders
    wires: hw.memory.reader once packed the FIFO entry, with bits of ``a1`` and bits computed from
    them, into one wire)."""
    need("verilator")
    import subprocess
    from vqtex.sim.backends.toolchain import find_tool
    from vqtex.sim.backends.verilog import export_cached_verilog
    ts = texture_set("yuv_4x4_b12_mip")
    for prefetch in (1, 16):
        src = tmp_path / f"cached{prefetch}.v"
        src.write_text(export_cached_verilog(ts, MemoryConfig(**SMALL, prefetch=prefetch))[0])
        out = subprocess.run([find_tool("verilator"), "--lint-only", "-Wno-fatal", "-Wno-lint", "-Wno-style",
                              "--top-module", "cached_texel_fetch", str(src)], capture_output=True, text=True)
        assert out.returncode == 0, out.stderr[-2000:]
        assert "UNOPTFLAT" not in out.stderr and "%Warning" not in out.stderr, out.stderr[-2000:]
