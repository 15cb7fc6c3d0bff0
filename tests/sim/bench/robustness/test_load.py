"""Long streams through ``vqtex sim`` on the compiled backend equal golden: responses and every count
(issue: stability under load). Each run is the command a user runs, in its own process."""

from tests.support import builtin_set, need
from vqtex.sim.bench.robustness.load import load_check


def test_ten_million_requests_with_30_percent_backpressure():
    need("g++")
    rep = load_check(10_000_000, stall=0.3, seed=5)
    assert rep["mismatches"] == 0
    assert rep["cycles"] > 10_000_000 and rep["stall_cycles"]["output_backpressure"] > 2_000_000


def test_a_million_one_port_requests():
    """12-bit indices (the four-texture set), so the one-port reader really stalls on straddles."""
    need("g++")
    rep = load_check(1_000_000, stall=0.2, one_port=True, seed=6, ts=builtin_set("four"))
    assert rep["straddling_index_reads"] > 10_000
    assert rep["stall_cycles"]["one_port_straddle"] == rep["straddling_index_reads"]
