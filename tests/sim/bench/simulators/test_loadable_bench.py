"""sim/bench/simulators/loadable.py: the loadable unit's speed on its own geometry, its answers checked."""

from tests.support import SPECIALISE_CASES as CASES
from tests.support import need, shared_cache_dir


def test_loadable_speed_shape(monkeypatch):
    need("g++")
    monkeypatch.setenv("VQTEX_CACHE", shared_cache_dir())
    from vqtex.sim.bench.simulators.loadable import loadable_speed
    rep = loadable_speed(CASES["three_widths"][0](), requests=2000, runs=1)
    assert rep["requests"] == 2000 and rep["cycles"] >= 2000 and rep["load_cycles"] > 0
    assert rep["cycles_per_cpu_second"] > 0 and rep["cycles_per_second"] > 0
