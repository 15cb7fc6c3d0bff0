"""Bilinear sampling with both request streams: the sparse stream (zero-weight texels of the 2x2
footprint left out, repeats merged) resolves to the fixed stream's frame bit for bit, on both
built-in scenes and with mirror addressing; the fixed bilinear stream is the L0 half of trilinear's."""

import dataclasses

import numpy as np
import pytest

from vqtex.golden.render.frame import frame_requests
from vqtex.golden.render.raster import Fragments
from vqtex.golden.render.sampling import WEIGHT_BITS, Sampler
from vqtex.golden.render.scene import load_scene
from vqtex.golden.render.sparse import SkipCounts


@pytest.mark.parametrize("name", ["topspin", "town"])
def test_bilinear_sparse_frames_identical_to_fixed_on_both_scenes(name):
    sc = load_scene(name)
    sc = dataclasses.replace(sc, width=160, height=120)        # a small frame of the same camera
    src = sc.reference_source()
    for frame in (0, 23):
        fixed, fs = frame_requests(sc, frame, src, "bilinear", stream="fixed")
        sparse, ss = frame_requests(sc, frame, src, "bilinear")   # sparse is the default
        assert len(fs.counts) > 1000 and (fs.counts == 4).all()
        a = fs.resolve(src.fetch(*fixed.T))
        b = ss.resolve(src.fetch(*sparse.T))
        assert np.array_equal(a, b)
        k = ss.skipped
        assert k.fixed == len(fixed) and k.kept == len(sparse) < len(fixed)
        assert (ss.counts >= 1).all() and (ss.counts <= 4).all() and ss.counts.sum() == len(sparse)
        assert (ss.weights > 0).all()
        pix = np.repeat(np.arange(len(ss.counts)), ss.counts)
        assert (np.bincount(pix, ss.weights.astype(np.int64)) == 1 << WEIGHT_BITS).all()
        # fixed bilinear = the L0 footprint of fixed trilinear, request for request
        tri, _ = frame_requests(sc, frame, src, "trilinear", stream="fixed")
        assert np.array_equal(tri.reshape(-1, 8, 4)[:, :4], fixed.reshape(-1, 4, 4))


SQUARE = [(8 >> n, 8 >> n) for n in range(4)]          # 8x8 .. 1x1


def _frags(s, t, d):
    n = len(s)
    return Fragments(n, 1, np.arange(n), np.zeros(n, np.int64), np.zeros(n, np.int64), np.asarray(s, float),
                     np.asarray(t, float), *(np.full(n, v, float) for v in d))


def _texels(reqs):
    key = (reqs * [1 << 40, 1 << 32, 1 << 16, 1]).sum(1)
    return (np.stack([key, key >> 8, key >> 16, key >> 24], 1) * 2654435761 % 251).astype(np.uint8)


@pytest.mark.parametrize("mode", ["bilinear", "trilinear"])
def test_mirror_addressing_with_both_streams(mode):
    rng = np.random.default_rng(11)
    c = (np.arange(-16, 17) + 0.5) / 8                          # texel centres: fu = 0, repeats at the mirror
    s = np.concatenate([rng.uniform(-3, 3, 300), c, [0.0, 1.0, -1.0, 1e9, np.inf]])
    t = np.concatenate([rng.uniform(-3, 3, 300), c[::-1], [0.0, 1.0, 1.0, -1e9, -np.inf]])   # NaN is refused
    for d in ((0.01, 0, 0, 0.01), (1 / 8, 0, 0, 1 / 8), (0.3, 0.1, 0, 0.2)):
        f = _frags(s, t, d)
        out = {}
        for stream in ("fixed", "sparse"):
            sm = Sampler([SQUARE], ["mirror"], mode, stream=stream)
            r = sm.requests(f)
            out[stream] = (r, sm, sm.resolve(_texels(r)))
        assert np.array_equal(out["fixed"][2], out["sparse"][2])
        assert out["sparse"][1].skipped.kept == len(out["sparse"][0]) < len(out["fixed"][0])


def test_bilinear_at_the_mirror_edge_is_one_texel():
    """At s = 0 with mirror addressing, i0 = -1 mirrors to 0 = i1: a repeat, fetched once; at a texel
    centre the other half of the footprint has weight 0."""
    sm = Sampler([SQUARE], ["mirror"], "bilinear")
    r = sm.requests(_frags([0.0], [0.5 / 8], (1 / 8, 0, 0, 1 / 8)))
    assert r.tolist() == [[0, 0, 0, 0]] and sm.skipped == SkipCounts(4, 2, 1)
    assert sm.weights.tolist() == [1 << WEIGHT_BITS]


def test_fovea_biases_bilinear_and_the_filter_inputs():
    """The fovea's bias moves the bilinear footprint to a coarser level outside the fovea, in both
    streams alike, and filter_inputs (the RTL filter's inputs) carry the same biased LOD."""
    from vqtex.golden.render.fovea import Fovea
    n = 64
    f = Fragments(n, 1, np.arange(n), np.zeros(n, np.int64), np.zeros(n, np.int64), np.linspace(0, 1, n),
                  np.full(n, 0.3), *(np.full(n, v, float) for v in (1 / 8, 0, 0, 1 / 8)))
    fovea = Fovea(8.0, 0.5, 8.0, 1.0)
    lams = {}
    for stream in ("fixed", "sparse"):
        sm = Sampler([SQUARE], None, "bilinear", stream=stream, fovea=fovea)
        r = sm.requests(f)
        lams[stream] = (sm.lam, sm.resolve(_texels(r)))
        assert np.array_equal(sm.filter_inputs(f, sm.frac)["lod"], sm.lam)
    assert np.array_equal(lams["fixed"][0], lams["sparse"][0]) and np.array_equal(lams["fixed"][1], lams["sparse"][1])
    lam = lams["sparse"][0]
    assert (lam[:16] == 0).all() and lam[-1] > 256        # unbiased level 0 in the fovea, coarser far out
