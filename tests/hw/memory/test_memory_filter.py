"""hw.memory.filter.CachedTextureFilter on pysim (sim.backends.filter_memory), its AXI master
answered by the golden memory models: colours equal golden's bit for bit, in order; the cycles,
every AR's cycle (the arbiter's order), the bursts and the lanes' fill waits equal the cycle model
golden.memory.filter exactly; 1, 2, 4 and 8 lanes, blocking and prefetching caches
smaller than the set, memory latencies 1 to 300, DDR3; with random output backpressure (0.4 to 0.9)
too."""

import numpy as np
import pytest

from tests.support import edge_pixels, filter_set
from vqtex.golden import filter as spec
from vqtex.golden.memory.cache import CacheShape
from vqtex.golden.memory.system import MemoryConfig
from vqtex.hw.filter.footprint import level_table
from vqtex.hw.memory.filter import LATENCY, CachedTextureFilter
from vqtex.sim.backends.filter import golden_colors
from vqtex.sim.backends.filter_memory import simulate_cached_filter


def pixels(n, seed):
    ts = filter_set()
    frac = spec.coordinate_frac_bits(level_table(ts).max_log2)
    return ts, edge_pixels(level_table(ts), frac, n, seed), frac


def config(latency, prefetch, kind="fixed"):
    return MemoryConfig(index_cache=CacheShape(128, 16, 2), raw_cache=CacheShape(64, 16, 2), prefetch=prefetch,
                        latency=latency, bus_bytes=16, bandwidth=8 if latency == 20 else 16, kind=kind)


@pytest.mark.parametrize("lanes,n,latency,prefetch,kind", [
    (1, 16, 300, 4, "fixed"),
    (2, 24, 7, 1, "fixed"),
    (4, 36, 20, 4, "fixed"),
    (4, 24, 1, 1, "dram"),
    (8, 24, 60, 8, "fixed"),
])
def test_cached_filter_equals_the_cycle_model(lanes, n, latency, prefetch, kind):
    ts, px, frac = pixels(n, lanes * 7 + prefetch)
    cfg = config(latency, prefetch, kind)
    rtl = simulate_cached_filter(ts, px, cfg, backend="pysim", lanes=lanes)
    model = simulate_cached_filter(ts, px, cfg, backend="golden", lanes=lanes)
    assert (rtl.colors == golden_colors(ts, px, frac)).all()
    assert (model.colors == rtl.colors).all()
    assert rtl.cycles == model.cycles
    assert rtl.memory["ar"].tolist() == model.memory["ar"].tolist()
    assert rtl.memory["memory_bytes"] == model.memory["memory_bytes"]
    assert rtl.memory["fill_waits"] == model.memory["fill_waits"] > 0
    assert rtl.stall_cycles["output_backpressure"] == 0
    # the memory cost something: slower than the on-chip filter's groups + 23
    assert rtl.cycles > model.memory["on_chip_cycles"] + 4
    if lanes > 1:
        assert model.memory["stall_detail"]["join"] > 0


@pytest.mark.parametrize("lanes,n,latency,prefetch,stall,kind", [
    (4, 30, 9, 4, 0.4, "fixed"),
    (4, 24, 1, 4, 0.8, "dram"),
    (1, 16, 7, 1, 0.9, "fixed"),
    (8, 8, 60, 8, 0.5, "fixed"),
])
def test_cached_filter_with_backpressure_equals_the_cycle_model(lanes, n, latency, prefetch, stall, kind):
    """Random output backpressure: colours and order, and the cycles, every AR, the fill waits and
    the output backpressure cycles equal the model's (golden.memory.filter with ``ready_pattern``)."""
    ts, px, frac = pixels(n, 11 + lanes)
    cfg = config(latency, prefetch, kind)
    rtl = simulate_cached_filter(ts, px, cfg, backend="pysim", lanes=lanes, stall=stall, seed=3)
    model = simulate_cached_filter(ts, px, cfg, backend="golden", lanes=lanes, stall=stall, seed=3)
    assert (rtl.colors == golden_colors(ts, px, frac)).all()          # (run_stream checks every tag's order)
    assert rtl.stall_cycles["output_backpressure"] > 0
    assert rtl.cycles == model.cycles
    assert rtl.stall_cycles == model.stall_cycles
    assert rtl.memory["ar"].tolist() == model.memory["ar"].tolist()


def test_cached_filter_refuses_bad_configuration():
    ts, px, frac = pixels(4, 1)
    with pytest.raises(ValueError, match="lanes"):
        CachedTextureFilter(ts, config(5, 4), lanes=3)
    with pytest.raises(ValueError, match="stall probability"):
        simulate_cached_filter(ts, px, config(5, 4), backend="golden", stall=1.2)
    with pytest.raises(ValueError, match="runs on"):
        simulate_cached_filter(ts, px, config(5, 4), backend="icarus")
    assert LATENCY == 29
