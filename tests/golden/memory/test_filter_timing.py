"""golden.memory.filter: the texture filter's cycle model through the memory system (numpy lane
streams, the per-group loop): its lane streams are the footprints' slots; a perfect cache gives
``groups + 29`` (with the texel pipeline's LATENCY, 15); one lane is golden.memory.timing.run's model exactly (shifted by the footprint);
the arbiter's order; never faster than a perfect cache, never faster with a longer latency."""

import numpy as np
import pytest

from tests.support import edge_pixels, filter_set
from vqtex.golden import filter as spec
from vqtex.golden.memory import filter as gf
from vqtex.golden.memory import timing
from vqtex.golden.memory.cache import CacheShape
from vqtex.golden.memory.system import MemoryConfig
from vqtex.hw.filter.footprint import level_table
from vqtex.hw.texel_fetch import LATENCY


def setup(n=150, seed=1):
    ts = filter_set()
    frac = spec.coordinate_frac_bits(level_table(ts).max_log2)
    return ts, edge_pixels(level_table(ts), frac, n, seed), frac


def config(latency=20, prefetch=4, **kw):
    return MemoryConfig(index_cache=CacheShape(128, 16, 2), raw_cache=CacheShape(64, 16, 2), prefetch=prefetch,
                        latency=latency, bus_bytes=16, **kw)


@pytest.mark.parametrize("lanes", [1, 2, 4, 8])
def test_lane_streams_are_the_footprint_slots(lanes):
    ts, px, frac = setup()
    req, last = gf.lane_requests(ts, px, lanes, frac)
    lv, i, j, _ = spec.footprint(level_table(ts), px["texture"], px["s"], px["t"], px["lod"], px["mode"],
                                 px["address_s"], px["address_t"], frac)
    used = np.array([1, 4, 8])[px["mode"]]
    groups = -(-used // lanes)
    assert req.shape == (lanes, groups.sum(), 4) and last.sum() == len(used)
    # per pixel, the lanes' slots group by group: slot k + lanes g, in order (a loop as the reference)
    n = 0
    for m in range(len(used)):
        for g in range(groups[m]):
            for k in range(lanes):
                s = k + lanes * g
                assert req[k, n].tolist() == [px["texture"][m], lv[m, s], i[m, s], j[m, s]]
            assert last[n] == (g == groups[m] - 1)
            n += 1


@pytest.mark.parametrize("lanes", [1, 2, 4, 8])
def test_perfect_cache_is_groups_plus_30(lanes):
    ts, px, frac = setup()
    r = gf.run_pixels(ts, px, config(), lanes, frac, ideal=True, latency=LATENCY)
    assert r["cycles"] == r["groups"] + 30 == r["on_chip_cycles"] + 6
    assert r["bursts"] == 0 and r["stall_cycles"]["miss"] == 0
    # the colours leave one group apart, in order
    assert (np.diff(r["transfer"]) >= 1).all()


@pytest.mark.parametrize("prefetch,latency,kind", [(1, 9, "fixed"), (4, 40, "fixed"), (8, 300, "fixed"),
                                                   (4, 0, "dram")])
def test_one_lane_is_the_texel_fetch_units_model(prefetch, latency, kind):
    ts, px, frac = setup(120, prefetch)
    cfg = config(latency or 1, prefetch, kind=kind)
    req, last = gf.lane_requests(ts, px, 1, frac)
    p = timing.plan(ts, req[0], cfg)
    single = timing.run(p, cfg, LATENCY, lambda m: np.ones(m, bool))
    r = gf.run([p], cfg, last, latency=LATENCY)
    assert (r["group_transfer"] == single["transfer"] + gf.FOOTPRINT_LATENCY).all()
    assert (r["tag"] == single["tag"] + gf.FOOTPRINT_LATENCY).all()
    assert r["stall_cycles"]["miss"] == single["stall_cycles"]["miss"] > 0
    assert r["stall_cycles"]["arbiter"] == 0 and r["bursts"] == single["bursts"]


@pytest.mark.parametrize("lanes", [2, 4])
def test_arbiter_order_and_bounds(lanes):
    ts, px, frac = setup(120, 3)
    cfg = config(30, 4)
    req, last = gf.lane_requests(ts, px, lanes, frac)
    plans = [timing.plan(ts, req[k], cfg) for k in range(lanes)]
    r = gf.run(plans, cfg, last, latency=LATENCY)
    assert (np.diff(r["ar"]) >= 1).all()                       # one AR per cycle, in order
    # every lane's bursts in its own order, as many as its misses
    assert np.bincount(r["ar_lane"], minlength=lanes).tolist() == [int(p.misses.sum()) for p in plans]
    # the offers: g + 1 + j per lane; an AR never before its offer
    offers = sorted((g + 1 + j, k) for k, p in enumerate(plans)
                    for g, m in zip(r["tag"].tolist(), p.misses.tolist()) for j in range(m))
    assert [k for _, k in offers] == r["ar_lane"].tolist()
    assert (r["ar"] >= np.array([t for t, _ in offers])).all()
    assert r["stall_cycles"]["arbiter"] == int((r["ar"] - np.array([t for t, _ in offers])).sum()) > 0


@pytest.mark.parametrize("lanes", [2, 4])
def test_slower_memory_never_faster(lanes):
    ts, px, frac = setup(150, 5)
    ideal = gf.run_pixels(ts, px, config(), lanes, frac, ideal=True, latency=LATENCY)["cycles"]
    prev = 0
    for latency in (1, 10, 50, 200):
        c = gf.run_pixels(ts, px, config(latency), lanes, frac, latency=LATENCY)["cycles"]
        assert c >= max(prev, ideal)
        prev = c


@pytest.mark.parametrize("lanes", [1, 4])
def test_backpressure_model(lanes):
    """With output backpressure (``ready_pattern``): o.ready high always gives the closed form's
    every cycle; backpressure never makes a frame faster (heavy backpressure slower), and the
    colours leave in order, one per cycle at most, only in cycles with o.ready high."""
    from vqtex.sim.streams import ready_pattern
    ts, px, frac = setup(80, lanes)
    req, last = gf.lane_requests(ts, px, lanes, frac)
    plans = [timing.plan(ts, req[k], config()) for k in range(lanes)]
    free = gf.run(plans, config(), last, latency=LATENCY)
    high = gf.run(plans, config(), last, latency=LATENCY, ready_pattern=lambda m: np.ones(m, bool))
    for key in ("transfer", "group_transfer", "tag", "enter", "ar"):
        assert high[key].tolist() == free[key].tolist()
    assert high["cycles"] == free["cycles"] and high["stall_cycles"]["output_backpressure"] == 0
    for stall in (0.3, 0.8):
        r = gf.run(plans, config(), last, latency=LATENCY, ready_pattern=lambda m: ready_pattern(2, stall, m))
        bp = r["stall_cycles"]["output_backpressure"]
        assert bp > 0 and r["cycles"] >= free["cycles"] + (stall > 0.5)
        assert len(r["transfer"]) == last.sum() and (np.diff(r["transfer"]) >= 1).all()
        ready = ready_pattern(2, stall, r["cycles"])
        assert ready[r["transfer"]].all()                      # a colour leaves only when o.ready is high
    with pytest.raises(ValueError, match="4 stages"):
        gf.run(plans, config(), last, latency=LATENCY, blend=3, ready_pattern=lambda m: np.ones(m, bool))
