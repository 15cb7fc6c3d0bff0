"""Need analysis (golden.need.analysis) against a brute-force count in plain Python over a small scene."""

from collections import OrderedDict

import numpy as np
import pytest

from tests.support import NEED_SCENE
from vqtex.golden.format import MAX_LEVELS, unpack_indices
from vqtex.golden.need.analysis import CacheSpec, analyse, cache_hits, distinct_requests, scene_level_shapes, scene_streams
from vqtex.golden.render.scene import build_texture_set, parse_scene


FRAMES = [0, 2, 3]


@pytest.fixture(scope="module")
def small():
    scene = parse_scene(NEED_SCENE, "small.toml")
    ts = build_texture_set(scene)
    streams = list(scene_streams(scene, ts, FRAMES))
    return scene, ts, streams


def brute_force(ts, streams, tile=(8, 8)):
    """Everything the need report counts, one request at a time with Python sets and an explicit LRU."""
    wb = ts.word_bits
    maps = {}
    levels, groups, blocks, codewords = set(), set(), {}, {}
    idx_words, entries, raw_words = set(), set(), set()
    frames = []
    for f, reqs in streams:
        fw, fe, fr, fb = set(), set(), set(), set()
        prev, buf, hits, strad = None, 0, 0, 0
        lru = {}                                            # set -> OrderedDict of blocks, LRU first
        for t, L, i, j in reqs.tolist():
            d = ts.descriptor(t, L)
            levels.add((t, L))
            if d["compressed"]:
                s, b = d["sublevel"], d["index_bits"]
                bx, by = i >> d["log2bw"], j >> d["log2bh"]
                nbx = (1 << d["log2w"]) >> d["log2bw"]
                k = by * nbx + bx
                key = ("group", t, L - s, k)
                if d["base"] not in maps:
                    n = nbx * ((1 << d["log2h"]) >> d["log2bh"])
                    maps[d["base"]] = unpack_indices(ts.index_words, b, n, d["base"], wb)
                index = int(maps[d["base"]][k])
                w = d["base"] + k * b // wb
                fw.add(w)
                if (k * b) % wb + b > wb:
                    fw.add(w + 1)
                    strad += 1
                fe.add(d["cb_base"] + index)
                codewords.setdefault(ts.textures[t].codebook, set()).add(index)
                groups.add((t, L - s))
            else:
                bx, by = i, j
                key = ("raw", t, L, i, j)
                fr.add(d["base"] + (j << d["log2w"]) + i)
                groups.add((t, L))
            blocks[(t, L, bx, by)] = blocks.get((t, L, bx, by), 0) + 1
            fb.add(key)
            buf += key == prev
            prev = key
            ways = lru.setdefault((by % tile[1]) * tile[0] + bx % tile[0], OrderedDict())
            if key in ways:
                hits += 1
                ways.move_to_end(key)
            else:
                ways[key] = True
                if len(ways) > 2:
                    ways.popitem(last=False)
        idx_words |= fw
        entries |= fe
        raw_words |= fr
        frames.append(dict(frame=f, requests=len(reqs), index_words=len(fw), codebook_entries=len(fe),
                           raw_words=len(fr), blocks=len(fb), straddling_reads=strad, buffer_hits=buf,
                           cache_hits=hits))
    return dict(levels=levels, groups=groups, blocks=blocks, codewords=codewords, idx_words=idx_words,
                entries=entries, raw_words=raw_words, frames=frames)


def test_counts_match_a_brute_force_count(small):
    _, ts, streams = small
    need = analyse(ts, streams)
    bf = brute_force(ts, streams)
    assert {(int(t), int(L)) for t, L in zip(*np.nonzero(need.levels))} == bf["levels"]
    assert {(t, top) for t, top, _ in need.groups} == bf["groups"]
    assert list(need.textures) == [True, False, True]
    for t, info in enumerate(ts.textures):
        for L in range(info.levels):
            counts = need.blocks(t, L)
            got = {(t, L, int(x), int(y)): int(counts[y, x]) for y, x in zip(*np.nonzero(counts))}
            assert got == {k: v for k, v in bf["blocks"].items() if k[:2] == (t, L)}
    for c, used in enumerate(need.codewords):
        assert set(np.flatnonzero(used).tolist()) == bf["codewords"].get(c, set())
    assert set(np.flatnonzero(need.index_words).tolist()) == bf["idx_words"]
    assert set(np.flatnonzero(need.codebook_entries).tolist()) == bf["entries"]
    assert set(np.flatnonzero(need.raw_words).tolist()) == bf["raw_words"]
    assert [f.to_dict() for f in need.frames] == bf["frames"]
    # The scene exercises what the counts are about: straddles, hits of both kinds, raw levels.
    tot = need.summary()["totals"]
    assert tot["straddling_reads"] > 0 and 0 < tot["buffer_hits"] < tot["cache_hits"] < tot["requests"]
    assert need.summary()["formats"] == {"colors": ["rgb", "yuv411", "raw"], "index_bits": [3, 12],
                                         "sublevels": [0, 1]}


def test_summary_totals_agree_with_frames(small):
    _, ts, streams = small
    s = analyse(ts, streams).summary()
    assert s["totals"]["requests"] == sum(len(r) for _, r in streams)
    assert s["textures"] == {"stored": 3, "touched": 2}
    assert s["memory_stored"]["index_words"] == len(ts.index_words)
    assert s["levels"]["touched"] == sum(len(levels) for levels in
                                         [r["levels_touched"] for r in s["texture_detail"]])


def test_lru_caches_against_explicit_lru():
    rng = np.random.default_rng(3)
    keys = rng.integers(0, 12, 4000)
    sets = keys % 3
    for ways in (1, 2, 4):
        expect, state = [], {}
        for k, s in zip(keys.tolist(), sets.tolist()):
            od = state.setdefault(s, OrderedDict())
            expect.append(k in od)
            od[k] = True
            od.move_to_end(k)
            if len(od) > ways:
                od.popitem(last=False)
        assert cache_hits(keys, sets, ways).tolist() == expect
    with pytest.raises(ValueError):
        CacheSpec(ways=3)


def test_scene_level_shapes_are_the_encoded_ones(small):
    scene, ts, _ = small
    assert scene_level_shapes(scene) == [ts.level_shapes(t) for t in range(ts.n_textures)]
    assert ts.descriptors.shape[1] == MAX_LEVELS


def test_a_frame_without_requests_touches_nothing(small):
    _, ts, _ = small
    s = analyse(ts, [np.zeros((0, 4), np.int64)], frames=[7]).summary()
    assert s["levels"]["touched"] == 0 and s["codewords"]["used"] == 0 and s["memory_touched"]["index_words"] == 0
    assert s["per_frame"] == [dict(frame=7, requests=0, index_words=0, codebook_entries=0, raw_words=0, blocks=0,
                                   straddling_reads=0, buffer_hits=0, cache_hits=0)]


def test_distinct_requests_is_the_union(small):
    _, ts, streams = small
    got = distinct_requests(r for _, r in streams)
    assert [tuple(r) for r in got.tolist()] == sorted({tuple(r) for _, s in streams for r in s.tolist()},
                                                      key=lambda r: (r[0], r[1], r[3], r[2]))
    assert distinct_requests([]).shape == (0, 4)
