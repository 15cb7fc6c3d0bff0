"""sim/bench/simulators/units.py: both units measured on the same requests, and their answers compared."""

import os

from tests.support import SPECIALISE_CASES as CASES
from tests.support import need, shared_cache_dir


def test_unit_speeds_shape(monkeypatch):
    need("g++")
    monkeypatch.setenv("VQTEX_CACHE", shared_cache_dir())
    from vqtex.sim.bench.simulators.units import unit_speeds
    rep = unit_speeds(CASES["three_widths"][0](), requests=3000, runs=1)
    assert set(rep) == {1, 2}
    for row in rep.values():
        assert row["specialised"] > 0 and row["full"] > 0
        assert abs(row["ratio"] - row["specialised"] / row["full"]) < 0.01
