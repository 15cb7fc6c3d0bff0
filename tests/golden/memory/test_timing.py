"""golden.memory.timing: the cycle model of the cached unit, by its rules on streams whose answer can
be worked out by hand, and by the properties any such unit has (never faster than a perfect cache,
more latency never helps, a line is read once while it stays)."""

import numpy as np
import pytest

from vqtex.golden.fetch import random_requests
from vqtex.golden.memory.cache import CacheShape
from vqtex.golden.memory.system import Layout, MemoryConfig, references
from vqtex.golden.memory.timing import FILL_READ, FRONT_LATENCY, LOOKUP_PLACES, LOOKUP_STAGES, REPLAY, attempt, fifo_slack, plan, run_requests
from vqtex.golden.encode import encode

from tests.support import image, texture_set

L = 14          # a pipeline latency (the texel pipeline's; the model takes it as a number)


def always(n):
    return np.ones(n, bool)


def pattern(seed, stall):
    return lambda n: np.random.default_rng(seed).random(n) >= stall


@pytest.fixture(scope="module")
def ts():
    return texture_set("yuv_4x4_b12_mip")


def test_references_follow_the_layout(ts):
    cfg = MemoryConfig(index_cache=CacheShape(1024, 16, 2), raw_cache=CacheShape(256, 16, 1))
    req = random_requests(ts, 500, seed=1)
    refs = references(ts, req, cfg)
    lay = Layout.of(ts)
    assert lay.raw_base % 4096 == 0 and lay.raw_base >= len(ts.index_words) * lay.word_bytes
    d = ts.descriptors[req[:, 0], req[:, 1]]
    comp = d["compressed"].astype(bool)
    # one reference per request, two when a straddling index spans two lines
    counts = np.bincount(refs.request, minlength=len(req))
    assert set(counts.tolist()) <= {1, 2} and (counts[~comp] == 1).all()
    assert (refs.cache[np.isin(refs.request, np.flatnonzero(~comp))] == 1).all()
    raw_lines = refs.line[refs.cache == 1]
    assert (raw_lines * 16 >= lay.raw_base).all() and (raw_lines * 16 < lay.end).all()


def test_perfect_cache_no_backpressure(ts):
    req = random_requests(ts, 300, seed=2)
    out = run_requests(ts, req, MemoryConfig(), L, always, ideal=True)
    assert out["cycles"] == len(req) + L + FRONT_LATENCY
    assert out["bursts"] == 0 and out["stall_cycles"]["miss"] == 0


@pytest.mark.parametrize("prefetch", [1, 4])
def test_lookup_buffer(ts, prefetch):
    """The cache block takes request n into the lookup's buffer when it holds fewer than three
    requests not yet taken by the check (``b[n] >= g[n-3] + 1``: its ready registered), and the
    check first tries it LOOKUP_STAGES = 2 cycles later (buffer, lookup); the address stages move
    against it (``a[n] >= b[n-2]``). On a stream that stalls (small caches, 60 cycles of memory),
    each rule binds somewhere."""
    req = random_requests(ts, 400, seed=5)
    cfg = MemoryConfig(index_cache=CacheShape(128, 16, 2), raw_cache=CacheShape(64, 16, 2), prefetch=prefetch,
                       latency=60, bandwidth=16, bus_bytes=16)
    out = run_requests(ts, req, cfg, L, always)
    a, b, g = out["accept"], out["lookup"], out["tag"]
    assert LOOKUP_STAGES == 2 and LOOKUP_PLACES == 3
    assert (g >= b + 2).all() and (g == b + 2).any() and (b >= a + 2).all()
    assert (b[3:] >= g[:-3] + 1).all() and (b[3:] == g[:-3] + 1).any()
    assert (a[2:] >= b[:-2]).all() and (a[2:] == b[:-2]).any() and (a[2:] > a[:-2] + 2).any()


@pytest.mark.parametrize("latency", [20, 21, 22])
def test_every_request_a_new_line_blocking(latency):
    """A blocking cache (prefetch 1) and a stream whose every request misses: each request waits for
    its line, issued the cycle after its tag check; worked out from the rules: the data read of n-1
    is ``1 + latency + FILL_READ`` cycles after its check (one beat), and the check of n, first tried the cycle
    after n-1's and then every ``REPLAY`` cycles, is taken at the first try at or after that read
    (the blocking cache sees the read's room in the read's cycle)."""
    ts = encode([image((64, 64), 0)], block=(4, 4), codebook_size=8, color="rgb", index_bits=8)  # no mipmaps: all compressed
    line = 16                                       # 4 words of 8-bit indices = 16 blocks per line
    cfg = MemoryConfig(index_cache=CacheShape(4096, line, 4), prefetch=1, latency=latency, bandwidth=16, bus_bytes=16)
    req = np.array([(0, 0, 0, 4 * r) for r in range(16)], np.int64)   # block k = 16 r: line r
    p = plan(ts, req, cfg)
    assert p.misses.tolist() == [1] * 16
    out = run_requests(ts, req, cfg, L, always)
    wait = 1 + cfg.latency + FILL_READ              # AR after the tag check, the latency, 1 beat, readable
    per = 1 + -(-(wait - 1) // REPLAY) * REPLAY     # tries at g + 1, g + 1 + REPLAY, ...: the first >= g + wait
    assert 0 <= per - wait < REPLAY and (per - 1) % REPLAY == 0
    assert np.diff(out["tag"]).tolist() == [per] * 15
    assert np.diff(out["read"]).tolist() == [per] * 15
    # first: accepted 0, into the cache block 2, looked up 3, tag 4, AR 5, beat 5 + latency, read
    # FILL_READ = 2 later
    assert FILL_READ == 2 and out["read"][0] == 4 + 1 + cfg.latency + 2
    assert out["cycles"] == out["read"][-1] + 1 + L + 1
    assert out["stall_cycles"]["miss"] + out["stall_cycles"]["bandwidth"] == 16 * (cfg.latency + FILL_READ)
    # prefetching overlaps them: the bursts go out back to back, limited by nothing but the memory
    pre = run_requests(ts, req, MemoryConfig(index_cache=cfg.index_cache, prefetch=16, latency=20), L, always)
    # tag n at n + 4, AR at n + 5, its beat at n + 25, readable at n + 27
    assert np.diff(pre["tag"]).tolist() == [1] * 15
    assert pre["tag"][0] == 4
    assert pre["read"].tolist() == (27 + np.arange(16)).tolist()
    assert pre["cycles"] == 27 + 15 + 1 + L + 1


def test_fifo_room_from_the_registered_level():
    """A prefetching FIFO of Q entries frees an entry for the check the cycle after its reference is
    read (``g[n] >= p[n-Q] + 1``: the check sees the registered level, not the read's ``pop``); the
    blocking cache (Q = 1) in the read's own cycle (``g[n] >= p[n-1]``). Every request misses on a
    new line, so the FIFO is full and the rule binds for every n >= Q."""
    ts = encode([image((64, 64), 0)], block=(4, 4), codebook_size=8, color="rgb", index_bits=8)
    line = 16
    req = np.array([(0, 0, 0, 4 * r) for r in range(16)], np.int64)   # request r: line r, a miss
    assert (fifo_slack(1), fifo_slack(2), fifo_slack(128)) == (0, 1, 1)
    for q in (1, 2, 4):
        cfg = MemoryConfig(index_cache=CacheShape(4096, line, 4), prefetch=q, latency=20, bandwidth=16,
                           bus_bytes=16)
        out = run_requests(ts, req, cfg, L, always)
        g, p = out["tag"], out["read"]
        # the check of n is first tried the cycle after n-1's, again every REPLAY cycles until the
        # FIFO has room (no other rule binds here: one miss each, no victim waits)
        room = p[:-q] + fifo_slack(q)
        first = g[q - 1:-1] + 1
        assert g[q:].tolist() == [attempt(int(c), int(r)) for c, r in zip(first, room)], q
        late = room > first                         # the FIFO's room binds: at most REPLAY - 1 beyond it
        assert late.any() and (g[q:][late] - room[late] < REPLAY).all(), q
        assert ((g[q:] - first) % REPLAY == 0).all() and (g[q:][~late] == first[~late]).all(), q
        assert out["stall_cycles"]["fifo_full"] > 0


def test_attempt_tries_every_replay_cycles():
    """A check not taken is tried again REPLAY cycles later: the first try at or after the rule's
    cycle, in the first try's class mod REPLAY; two rules in turn are their maximum."""
    assert REPLAY == 3      # the kill acts from a register, the cycle after the try
    assert [attempt(10, r) for r in (5, 10, 11, 12, 13, 14)] == [10, 10, 13, 13, 13, 16]
    rng = np.random.default_rng(3)
    for c, r1, r2 in rng.integers(0, 50, (200, 3)).tolist():
        assert attempt(attempt(c, r1), r2) == attempt(c, max(r1, r2))


@pytest.mark.parametrize("name", ["yuv_4x4_b12_mip", "rgba_2x2_b7_mip_w16", "i8_4x2_b5_w64"])
def test_properties_on_random_streams(name):
    ts = texture_set(name)
    rng = np.random.default_rng(7)
    for trial in range(6):
        req = random_requests(ts, int(rng.integers(1, 400)), seed=trial)
        # some locality: repeat neighbours
        req = np.repeat(req, rng.integers(1, 5, len(req)), axis=0)
        stall = float(rng.choice([0.0, 0.3]))
        kw = dict(index_cache=CacheShape(int(rng.choice([256, 1024])), int(rng.choice([16, 32])), int(rng.choice([1, 2, 4]))),
                  raw_cache=CacheShape(256, 16, 2), bus_bytes=16, bandwidth=int(rng.choice([4, 16])))
        ready = pattern(trial, stall)
        ideal = run_requests(ts, req, MemoryConfig(**kw), L, ready, ideal=True)
        prev = None
        for latency in (1, 30, 300):
            outs = {q: run_requests(ts, req, MemoryConfig(prefetch=q, latency=latency, **kw), L, ready) for q in (1, 4, 16)}
            for q, o in outs.items():
                assert o["cycles"] >= ideal["cycles"]
                assert (np.diff(o["transfer"]) >= 1).all()
                # responses leave in order, each after its data read and the pipeline
                assert (o["transfer"] >= o["read"] + 1 + L).all()
                assert o["stall_cycles"]["output_backpressure"] >= 0
            # a deeper FIFO never hurts; nor does less latency
            assert outs[1]["cycles"] >= outs[4]["cycles"] >= outs[16]["cycles"]
            if prev is not None:
                assert outs[16]["cycles"] >= prev
            prev = outs[16]["cycles"]


def test_a_line_is_read_once_while_it_stays(ts):
    """A cache large enough for the whole set: one burst per distinct line, whatever the order and
    however many references wait on a line in flight."""
    req = random_requests(ts, 2000, seed=5)
    cfg = MemoryConfig(index_cache=CacheShape(1 << 16, 32, 4), raw_cache=CacheShape(1 << 14, 32, 4), latency=200)
    out = run_requests(ts, req, cfg, L, always)
    refs = references(ts, req, cfg)
    distinct = len(np.unique(refs.line[refs.cache == 0])) + len(np.unique(refs.line[refs.cache == 1]))
    assert out["bursts"] == distinct
    assert out["memory_bytes"]["index"] + out["memory_bytes"]["raw"] == 32 * distinct
    assert out["bytes_per_texel"] == 32 * distinct / len(req)


def test_dram_memory_runs(ts):
    req = random_requests(ts, 500, seed=9)
    cfg = MemoryConfig(kind="dram", index_cache=CacheShape(512, 32, 2), raw_cache=CacheShape(256, 32, 2))
    out = run_requests(ts, req, cfg, L, always)
    mem = out["memory"]
    assert mem.row_hits + mem.row_misses + mem.row_conflicts == out["bursts"] > 0
    assert out["cycles"] > run_requests(ts, req, cfg, L, always, ideal=True)["cycles"]
