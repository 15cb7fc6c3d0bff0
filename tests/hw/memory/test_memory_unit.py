"""hw.memory.unit.CachedTexelFetch on pysim (sim.backends.memory's test bench), its AXI master
answered by the golden memory models (sim.backends.axi_memory): responses equal golden.fetch bit for bit, and the input acceptances, every
AR and every response transfer equal the golden cycle model (sim.backends.cycle_model.run_cached's
golden.memory.timing with the texel pipeline's LATENCY), with memory latencies 1 to 300, the
blocking and the prefetching cache, fixed memory and DDR3, random output backpressure."""

import numpy as np
import pytest

from vqtex.golden.fetch import fetch, random_requests
from vqtex.golden.memory.cache import CacheShape
from vqtex.golden.memory.system import MemoryConfig
from vqtex.golden.memory.timing import plan, run
from vqtex.hw.texel_fetch import LATENCY
from vqtex.sim.backends.memory import run_pysim
from vqtex.sim.streams import ready_pattern

from tests.support import texture_set


def check(ts, req, cfg, stall, seed):
    got = run_pysim(ts, req, cfg, stall, seed)
    assert (got["responses"] == fetch(ts, *np.asarray(req).T)).all()
    p = plan(ts, req, cfg)
    model = run(p, cfg, LATENCY, lambda m: ready_pattern(seed, stall, m))
    assert got["accept"] == model["accept"].tolist()
    assert got["ar"] == [g + 1 + j for g, m in zip(model["tag"].tolist(), p.misses.tolist()) for j in range(m)]
    assert got["transfer"] == model["transfer"].tolist()
    assert got["cycles"] == model["cycles"]
    assert got["backpressure"] == model["stall_cycles"]["output_backpressure"]
    assert got["fill_waits"] == model["stall_cycles"]["miss"] + model["stall_cycles"]["bandwidth"]
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


def test_latency_is_golden_front_latency():
    """The cached unit's all-hit latency (its address stages and the reader's buffer, lookup, tag check and
    data read) is the texel pipeline's plus golden's ``FRONT_LATENCY``: one definition each side,
    tied here (21 today)."""
    from vqtex.golden.memory.timing import FRONT_LATENCY
    from vqtex.hw.memory.reader import CachedReader
    from vqtex.hw.memory.unit import ADDRESS_STAGES, CachedTexelFetch
    cfg = MemoryConfig()
    unit = CachedTexelFetch(texture_set("rgba_2x2_b7_mip_w16"), cfg)
    assert ADDRESS_STAGES + CachedReader.LATENCY == FRONT_LATENCY
    assert unit.latency == LATENCY + FRONT_LATENCY == 21
