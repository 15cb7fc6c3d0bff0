"""The C++ twin of the memory models (sim/backends/drivers/memory_model.h) equals the golden models
burst for burst: first beats and queued cycles, fixed latency and bandwidth, and the DDR3 part with
row hits, conflicts, bank parallelism and refresh."""

import numpy as np
import pytest

from vqtex.golden.memory.dram import DramMemory
from vqtex.golden.memory.external import FixedMemory

from tests.support import need, shared_cache


@pytest.fixture(autouse=True)
def _cache():
    with shared_cache():
        yield


def bursts(seed, n, spread, span):
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.integers(0, spread, n))
    beats = rng.choice([1, 2, 4, 8], n)
    address = rng.integers(0, span // 64, n) * 64
    return t, address, beats


@pytest.mark.parametrize("model", [FixedMemory(1, 16, 16), FixedMemory(100, 4, 16), FixedMemory(300, 1, 8),
                                   DramMemory(), DramMemory(bus_bytes=64, clock_mhz=150.0, controller_cycles=7)])
def test_cxx_model_equals_golden(model):
    need("g++")
    from vqtex.sim.backends.memory_model_cxx import reads
    seen = {"refreshes": 0, "row_conflicts": 0, "row_hits": 0}
    for seed, spread, span in ((1, 3, 1 << 16), (2, 40, 1 << 26), (3, 400, 1 << 29)):
        t, address, beats = bursts(seed, 3000, spread, span)
        model.reset()
        first, queued = [], []
        for a, b, c in zip(t.tolist(), address.tolist(), beats.tolist()):
            first.append(model.read(a, b, c))
            queued.append(model.queued)
        cf, cq = reads(model, t, address, beats)
        assert cf.tolist() == first
        assert cq.tolist() == queued
        if isinstance(model, DramMemory):
            seen = {k: v + getattr(model, k) for k, v in seen.items()}
    if isinstance(model, DramMemory):                   # the streams exercised what the DRAM model does
        assert all(seen.values()), seen
