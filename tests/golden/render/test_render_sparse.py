"""The sparse request stream: only requests that can change a pixel, the same frames bit for bit.

The fixed stream stays exactly the stream the renderer issued before the sparse one existed (its
digest on two built-in frames, recorded from that code), the sparse stream is the fixed one with
requests removed (zero weight, repeats) and both resolve to identical frames on both scenes.
"""

import hashlib

import numpy as np
import pytest

from vqtex.golden.render.frame import frame_requests
from vqtex.golden.render.pyramid import ReferenceSource, VQSource
from vqtex.golden.render.raster import Fragments
from vqtex.golden.render.sampling import FRAC_BITS, WEIGHT_BITS, Sampler
from vqtex.golden.render.scene import build_texture_set, load_scene
from vqtex.golden.render.sparse import SkipCounts, request_keys, sparse_stream, stream_offsets

#: sha256 of the little-endian int64 (N, 4) fixed trilinear stream of frame 0, recorded from the
#: renderer before the sparse stream was added (main at f7e809f), reference-source level shapes.
FIXED_DIGESTS = {
    "topspin": (1_017_600, "9faa88e803853f6f202d184764a81399b8df2e9e289a8756b8405a04980d7e84"),
    "town": (769_840, "fbdaa24ca3523e979cd76362cce0818b0002e20f51b919cddaee2dc48988965d"),
}


@pytest.fixture(scope="module", params=["topspin", "town"])
def scene(request):
    sc = load_scene(request.param)
    return sc, sc.reference_source()


def _digest(reqs):
    return hashlib.sha256(np.ascontiguousarray(reqs, dtype="<i8").tobytes()).hexdigest()


def test_fixed_stream_is_todays_stream(scene):
    sc, src = scene
    reqs, sampler = frame_requests(sc, 0, src, stream="fixed")
    assert (len(reqs), _digest(reqs)) == FIXED_DIGESTS[sc.name]
    assert (sampler.counts == 8).all() and sampler.skipped == SkipCounts(len(reqs), 0, 0)


def _is_subsequence_per_pixel(fixed, fixed_counts, sparse, sparse_counts):
    """Every pixel's sparse requests are its fixed requests in the same order with some left out."""
    f = fixed.reshape(-1, 8, 4)
    off = stream_offsets(sparse_counts)
    # position of each sparse request inside its pixel's fixed footprint: the first equal one after
    # the previous sparse request's position (vectorised by matching against all eight)
    pix = np.repeat(np.arange(len(sparse_counts)), sparse_counts)
    eq = (f[pix] == sparse[:, None, :]).all(2)                 # (N, 8)
    assert eq.any(1).all()
    pos = eq.argmax(1)
    later = np.ones(len(sparse), bool)
    later[off] = False                                         # first of each pixel: anything goes
    assert (pos[1:][later[1:]] > pos[:-1][later[1:]]).all()


@pytest.mark.parametrize("frame", [0, 17, 33])
def test_sparse_frames_identical_to_fixed_on_both_scenes(scene, frame):
    sc, src = scene
    fixed, fs = frame_requests(sc, frame, src, stream="fixed")
    sparse, ss = frame_requests(sc, frame, src)                 # sparse is the default
    assert ss.stream == "sparse"
    a = fs.resolve(src.fetch(*fixed.T))
    b = ss.resolve(src.fetch(*sparse.T))
    assert np.array_equal(a, b)
    assert len(sparse) < len(fixed)
    k = ss.skipped
    assert k.fixed == len(fixed) and k.kept == len(sparse) and k.zero_weight > 0
    assert (ss.counts >= 1).all() and (ss.counts <= 8).all() and ss.counts.sum() == len(sparse)
    _is_subsequence_per_pixel(fixed, fs.counts, sparse, ss.counts)
    # every kept request carries weight, and each pixel's weights still sum to 2^24
    assert (ss.weights > 0).all()
    pix = np.repeat(np.arange(len(ss.counts)), ss.counts)
    assert (np.bincount(pix, ss.weights.astype(np.int64)) == 1 << WEIGHT_BITS).all()


def test_sparse_frames_identical_on_the_compressed_textures():
    """Through golden.fetch on the encoded topspin set (what the RTL answers)."""
    sc = load_scene("topspin")
    src = VQSource(build_texture_set(sc))
    for frame in (5, 40):
        fixed, fs = frame_requests(sc, frame, src, stream="fixed")
        sparse, ss = frame_requests(sc, frame, src, stream="sparse")
        assert np.array_equal(fs.resolve(src.fetch(*fixed.T)), ss.resolve(src.fetch(*sparse.T)))


def _brute(reqs, weights):
    """The sparse rule, one pixel at a time (a reference for small cases)."""
    out, ws, counts = [], [], []
    for r, w in zip(reqs, weights):
        kept = {}
        for req, wk in zip(map(tuple, r), w):
            kept[req] = kept.get(req, 0) + int(wk)             # dicts keep first-insertion order
        rows = [(q, v) for q, v in kept.items() if v > 0]
        out += [q for q, _ in rows]
        ws += [v for _, v in rows]
        counts.append(len(rows))
    return np.array(out, np.int64).reshape(-1, 4), np.array(ws, np.int64), np.array(counts)


def test_sparse_stream_against_a_brute_force_rule():
    rng = np.random.default_rng(7)
    m, k = 400, 8
    reqs = np.zeros((m, k, 4), np.int64)
    reqs[:, :, 1:] = rng.integers(0, 2, (m, k, 3))             # few distinct values: many repeats
    reqs[:, :, 0] = rng.integers(0, 3, (m, 1))
    weights = rng.integers(0, 4, (m, k)) * rng.integers(0, 2, (m, k))
    weights[0] = 0                                             # a pixel with no weight at all
    r, w, c, skip = sparse_stream(reqs, weights)
    br, bw, bc = _brute(reqs, weights)
    assert np.array_equal(r, br) and np.array_equal(w, bw) and np.array_equal(c, bc)
    assert c[0] == 0 and skip.kept == len(r) == c.sum()
    # left out: every request but the first naming its texel, and that one too if the texel's weights
    # add up to 0; counted as zero weight when its own weight is 0, else as a repeat
    left_out = [(p, a) for p in range(m) for a in range(k)
                if (reqs[p, :a] == reqs[p, a]).all(1).any() or weights[p][(reqs[p] == reqs[p, a]).all(1)].sum() == 0]
    zero = sum(1 for p, a in left_out if weights[p, a] == 0)
    assert len(left_out) == m * k - len(r)
    assert skip.zero_weight == zero and skip.repeats == len(left_out) - zero
    with pytest.raises(ValueError):
        sparse_stream(reqs, -weights - 1)
    with pytest.raises(ValueError):
        sparse_stream(reqs[:, :4], weights)


def test_request_keys_are_equal_exactly_for_equal_rows():
    rng = np.random.default_rng(5)
    small = rng.integers(-3, 3, (500, 4))
    huge = small * (1 << 60)                              # spans beyond 2^62: the distinct-row fallback
    for rows in (small, huge):
        key = request_keys(rows)
        same_key = key[:, None] == key[None, :]
        same_row = (rows[:, None, :] == rows[None, :, :]).all(2)
        assert np.array_equal(same_key, same_row)
    assert len(request_keys(np.zeros((0, 4), np.int64))) == 0


def _one(s, t, d, shapes, address="wrap"):
    n = len(s)
    f = Fragments(n, 1, np.arange(n), np.zeros(n, np.int64), np.zeros(n, np.int64), np.array(s, float),
                  np.array(t, float), *(np.full(n, v, float) for v in d))
    out = {}
    for stream in ("fixed", "sparse"):
        sm = Sampler([shapes], address=[address], stream=stream)
        reqs = sm.requests(f)
        # the same texel for the same request, in both streams
        key = (reqs * [1 << 40, 1 << 32, 1 << 16, 1]).sum(1)
        texels = (np.stack([key, key >> 8, key >> 16, key >> 24], 1) * 2654435761 % 251).astype(np.uint8)
        out[stream] = (reqs, sm, sm.resolve(texels))
    assert np.array_equal(out["fixed"][2], out["sparse"][2])
    return out["sparse"][0], out["sparse"][1]


SQUARE = [(8 >> n, 8 >> n) for n in range(4)]          # 8x8 .. 1x1


def test_edge_cases_of_the_footprint():
    # magnification: level 0 only (L1's weight f = 0): at most 4 requests, all level 0
    reqs, sm = _one([0.3], [0.3], (0.01, 0, 0, 0.01), SQUARE)
    assert len(reqs) == 4 and (reqs[:, 1] == 0).all()
    # texel centres exactly (fu = fv = 0) at an exact level: one request
    c = (2 + 0.5) / 8
    reqs, sm = _one([c], [c], (1 / 8, 0, 0, 1 / 8), SQUARE)       # lambda = 0 exactly
    assert sm.lam.tolist() == [0] and reqs.tolist() == [[0, 0, 2, 2]]
    # fu = 0 only: half of the footprint
    reqs, _ = _one([c], [0.3], (1 / 8, 0, 0, 1 / 8), SQUARE)
    assert len(reqs) == 2 and (reqs[:, 2] == 2).all()
    # the last level, 1x1: every request is texel (0, 0) of it -> exactly one
    reqs, sm = _one([0.3], [0.7], (100.0, 0, 0, 100.0), SQUARE)
    assert sm.lam.tolist() == [3 << FRAC_BITS] and reqs.tolist() == [[0, 3, 0, 0]]
    assert sm.skipped == SkipCounts(8, 4, 3)          # L1's four of weight 0, three repeats in L0
    # an exact level with a blend of 0 between two levels: only L0
    reqs, sm = _one([0.37], [0.61], (2 / 8, 0, 0, 2 / 8), SQUARE)
    assert sm.lam.tolist() == [1 << FRAC_BITS] and (reqs[:, 1] == 1).all() and len(reqs) == 4


def test_one_texel_wide_levels_merge_repeats():
    tall = [(4, 16), (2, 8), (1, 4), (1, 2), (1, 1)]     # levels 2.. are 1 x N
    for address in ("wrap", "clamp"):
        # between level 2 (1x4) and level 3 (1x2): i0 and i1 are the one column, so 2 + 2 requests
        reqs, sm = _one([0.3], [0.3], (0, 0, 0, 5 / 16), tall, address)   # lambda = log2(5) = 2.32
        assert sm.lam[0] >> FRAC_BITS == 2 and sm.lam[0] & 255 and sm.skipped == SkipCounts(8, 0, 4)
        assert reqs[:, 1:].tolist() == [[2, 0, 0], [2, 0, 1], [3, 0, 0], [3, 0, 1]]
    # clamp at a corner: the whole footprint is the corner texel
    reqs, sm = _one([0.0], [0.0], (1 / 8, 0, 0, 1 / 8), SQUARE, "clamp")
    assert reqs.tolist() == [[0, 0, 0, 0]] and sm.skipped.repeats == 3 and sm.skipped.zero_weight == 4


def test_point_mode_and_bad_stream():
    sm = Sampler([SQUARE], mode="point")
    f = Fragments(2, 1, np.arange(2), np.zeros(2, np.int64), np.zeros(2, np.int64), np.array([0.1, 0.9]),
                  np.array([0.1, 0.9]), *(np.zeros(2),) * 4)
    assert len(sm.requests(f)) == 2 and (sm.counts == 1).all()
    with pytest.raises(ValueError, match="stream"):
        Sampler([SQUARE], stream="dense")


def test_a_frame_without_fragments():
    e = np.zeros(0)
    f = Fragments(4, 3, np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0, np.int64), *(e,) * 6)
    for stream in ("sparse", "fixed"):
        for mode in ("point", "trilinear"):
            sm = Sampler([SQUARE], mode=mode, stream=stream)
            assert sm.requests(f).shape == (0, 4) and sm.skipped == SkipCounts(0, 0, 0)
            assert (sm.resolve(np.zeros((0, 4), np.uint8)) == (0, 0, 0, 255)).all()
