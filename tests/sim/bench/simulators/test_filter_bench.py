"""``vqtex bench sim``'s filter table on a few pixels: rates reported, colours and cycles agree."""

from tests.support import edge_pixels, filter_set
from tests.support import need, shared_cache
from vqtex.golden import filter as spec
from vqtex.hw.filter import LATENCY
from vqtex.hw.filter.footprint import level_table


def test_filter_speeds_shape(capsys):
    need("g++")
    from vqtex.sim.bench.simulators.filter import filter_speeds, print_table
    ts = filter_set()
    frac = spec.coordinate_frac_bits(level_table(ts).max_log2)
    frames = [(0, edge_pixels(level_table(ts), frac, 300, 1), frac), (1, edge_pixels(level_table(ts), frac, 200, 2), frac)]
    with shared_cache():
        rep = filter_speeds(ts, frames, lanes=2, repeats=1)
    assert rep["setup_s"] > 0 and len(rep["frames"]) == 2
    for row, (_, px, _) in zip(rep["frames"], frames):
        assert row["agrees_with_golden"] and row["pixels"] == len(px["mode"])
        assert row["cycles"] > LATENCY
        assert row["cycles_per_s"] > 0 and row["cycles_per_s_in_library_cpu"] > 0
    assert rep["total"]["cycles"] == sum(r["cycles"] for r in rep["frames"]) and rep["total"]["agrees_with_golden"]
    print_table(rep, "two streams")
    assert "in library" in capsys.readouterr().out
