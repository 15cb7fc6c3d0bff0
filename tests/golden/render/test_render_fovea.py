"""Foveation: the LOD bias formula, the fovea identical to the unbiased frame, the periphery coarser."""

import math

import numpy as np
import pytest

from vqtex.golden.render.fovea import BIAS_LIMIT, Fovea, parse_gaze
from vqtex.golden.render.frame import frame_requests
from vqtex.golden.render.sampling import FRAC_BITS, quantize_lod
from vqtex.golden.render.scene import load_scene


def test_bias_formula():
    fv = Fovea(10.5, 20.5, radius=4.0, falloff=1.5)
    width = 100
    # pixel centres at distance 0, 4 (the edge), 8 (one radius beyond) and 10 along x
    xs = np.array([10, 14, 18, 20])
    pixel = 20 * width + xs
    assert fv.distance(pixel, width).tolist() == [0.0, 4.0, 8.0, 10.0]
    assert fv.inside(pixel, width).tolist() == [True, True, False, False]
    assert fv.bias(pixel, width).tolist() == [0, 0, 384, math.floor(256 * 1.5 * 6 / 4)]
    # never negative, non-decreasing with distance, capped
    pix = np.arange(width * 60)
    d, b = fv.distance(pix, width), fv.bias(pix, width)
    order = np.argsort(d, kind="stable")
    assert (b >= 0).all() and (np.diff(b[order]) >= 0).all() and (b[d <= 4.0] == 0).all()
    assert Fovea(0, 0, 1e-300, 1.0).bias(np.array([5]), 10).tolist() == [BIAS_LIMIT]
    assert Fovea(0, 0, 1.0, 0.0).bias(pix, width).max() == 0


def test_quantize_lod_adds_the_bias_before_the_clamp():
    rng = np.random.default_rng(0)
    lam = rng.uniform(-3, 12, 10_000)
    levels = np.full(len(lam), 9)
    bias = rng.integers(0, 3 * 256, len(lam))
    plain = np.floor(lam * 256 + 0.5).astype(np.int64)
    assert np.array_equal(quantize_lod(lam, levels, bias), np.clip(plain + bias, 0, 8 * 256))
    assert np.array_equal(quantize_lod(lam, levels, np.zeros(len(lam), np.int64)), quantize_lod(lam, levels))


@pytest.mark.parametrize("bad", [dict(radius=0.0), dict(radius=-1.0), dict(falloff=-0.5), dict(x=float("nan")),
                                 dict(radius=float("inf")), dict(y="3")])
def test_bad_fovea_is_refused(bad):
    args = dict(x=1.0, y=2.0, radius=3.0, falloff=1.0)
    args.update(bad)
    with pytest.raises(ValueError, match="fovea"):
        Fovea(**args)


def test_parse_gaze():
    assert parse_gaze("200,150.5") == (200.0, 150.5)
    for bad in ("200", "1,2,3", "a,b", "nan,1", "inf,2", ""):
        with pytest.raises(ValueError, match="gaze"):
            parse_gaze(bad)


@pytest.mark.parametrize("name,gaze", [("topspin", (200, 230)), ("town", (120, 160))])
def test_fovea_identical_and_periphery_coarser(name, gaze):
    scene = load_scene(name)
    src = scene.reference_source()
    fv = Fovea(*gaze, radius=60.0, falloff=1.0)
    for stream in ("sparse", "fixed"):
        ur, us = frame_requests(scene, 3, src, stream=stream)
        fr, fs = frame_requests(scene, 3, src, stream=stream, fovea=fv)
        uimg, fimg = us.resolve(src.fetch(*ur.T)), fs.resolve(src.fetch(*fr.T))
        pixel = fs.fragments.pixel
        inside = fv.inside(pixel, scene.width)
        assert inside.any() and (~inside).any()
        # the fovea: the same LOD, the same requests, the same pixels
        assert np.array_equal(fs.lam[inside], us.lam[inside])
        assert np.array_equal(fr[np.repeat(inside, fs.counts)], ur[np.repeat(inside, us.counts)])
        flat_u, flat_f = uimg.reshape(-1, 4), fimg.reshape(-1, 4)
        assert np.array_equal(flat_f[pixel[inside]], flat_u[pixel[inside]])
        # uncovered pixels: background in both
        assert np.array_equal(np.delete(flat_f, pixel, 0), np.delete(flat_u, pixel, 0))
        # the periphery: levels at least the unbiased ones, strictly coarser somewhere, different pixels
        assert (fs.lam >= us.lam).all() and (fs.lam[~inside] > us.lam[~inside]).any()
        assert ((fs.lam >> FRAC_BITS) >= (us.lam >> FRAC_BITS)).all()
        assert not np.array_equal(flat_f[pixel[~inside]], flat_u[pixel[~inside]])
        if stream == "fixed":                                # per request: L0 and L1 never finer
            assert (fr.reshape(-1, 8, 4)[:, :, 1] >= ur.reshape(-1, 8, 4)[:, :, 1]).all()
