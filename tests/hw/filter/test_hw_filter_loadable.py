"""The loadable texture filter (hw.filter.TextureFilter(geometry=..., loadable=True)) in pysim: one
Wishbone port loads every lane's copy of the memories and the footprint's level table; two sets
loaded in turn into one simulation filter bit for bit as golden, in the baked lane filter's cycles."""

from __future__ import annotations

import numpy as np
import pytest

from tests import support
from vqtex.golden import filter as spec
from vqtex.golden.geometry import Geometry
from vqtex.golden.register_map import load_writes
from vqtex.hw.address import COORD_BITS
from vqtex.hw.filter import TextureFilter
from vqtex.hw.filter.footprint import level_table
from vqtex.sim.backends.design import FIELDS
from vqtex.sim.backends.filter import golden_colors, simulate_filter
from vqtex.sim.backends.pysim import run_stream

from tests.support import edge_pixels, filter_set


def _pixels(ts, n, seed):
    table = level_table(ts)
    frac = spec.coordinate_frac_bits(table.max_log2)
    return frac, edge_pixels(table, frac, n, seed)


def test_two_sets_in_one_simulation():
    """Set A, then set B (another texture count, sizes and formats) loaded into one loadable filter:
    each filters as golden does; the level table follows the second load."""
    a, b = filter_set(), support.texture_set("yuv_4x4_b12_mip", images=2)
    g = Geometry.of(a).union(Geometry.of(b))
    unit_frac = spec.coordinate_frac_bits(COORD_BITS)
    dut = TextureFilter(geometry=g, loadable=True, lanes=2, tag_width=16, index_banks="lane")
    program, want = [], []
    for n, ts in enumerate((a, b)):
        frac, px = _pixels(ts, 30, n)
        rows = np.stack([np.asarray(px[f], np.int64) << (unit_frac - frac if f in ("s", "t") else 0)
                         for f in FIELDS], 1)
        program.append((load_writes(ts, g), rows))
        want.append(golden_colors(ts, px, frac))
    phases = run_stream(dut, program, columns=FIELDS, tag_width=16,
                        strobes=["stall_output", "busy", "bank_conflict"], valid=dut.o.valid, stall=0.2, seed=3,
                        name="filter")
    for ph, w in zip(phases, want):
        assert np.array_equal(ph["responses"], w)
        assert ph["load_cycles"] > 0


@pytest.mark.parametrize("lanes", [1, 4])
def test_loadable_filter_as_the_baked_one(lanes):
    """The same colours and cycles as the baked filter with a copy of the memories per lane."""
    ts = filter_set()
    frac, px = _pixels(ts, 40, lanes)
    g = Geometry.of(ts)
    loaded = simulate_filter(ts, px, backend="pysim", lanes=lanes, stall=0.3, seed=1, index_banks="lane", geometry=g)
    baked = simulate_filter(ts, px, backend="pysim", lanes=lanes, stall=0.3, seed=1, index_banks="lane")
    assert np.array_equal(loaded.colors, golden_colors(ts, px, frac))
    assert (loaded.cycles, loaded.stall_cycles) == (baked.cycles, baked.stall_cycles)


def test_loadable_filter_refusals():
    ts = filter_set()
    _, px = _pixels(ts, 4, 0)
    g = Geometry.of(ts)
    with pytest.raises(ValueError, match="index_banks"):
        simulate_filter(ts, px, backend="pysim", geometry=g)             # parity banks: not loadable
    with pytest.raises(ValueError, match="index_banks='lane'"):
        TextureFilter(geometry=g, loadable=True, lanes=2)
    small = Geometry(**{**g.to_dict(), "index_words": 2})
    from vqtex.golden.register_map import LoadError
    with pytest.raises(LoadError, match="index memory"):
        simulate_filter(ts, px, backend="pysim", index_banks="lane", geometry=small)
