"""Sampler: level of detail, fixed-point trilinear weights, wrap/clamp, point sampling, request order."""

import numpy as np
import pytest

from tests.support import fragments
from vqtex.golden.render.camera import Camera
from vqtex.golden.render.pyramid import ReferenceSource, build_pyramid
from vqtex.golden.render.raster import Fragments, rasterize
from vqtex.golden.render.sampling import (
    FRAC_BITS, WEIGHT_BITS, Sampler, address, level_of_detail, quantize_lod, trilinear_weights,
)


def _facing_quad_lod(texels_per_pixel, tex_size=256, frame=64):
    """A textured quad facing the camera at a distance where a pixel covers k x k texels."""
    cam = Camera((0, 0, 0), (0, 0, -1), fov=90)  # at distance z the view is 2z wide
    z = 3.0
    # the quad spans 2z (the whole frame of `frame` pixels) per `frame * k / tex_size` repeats
    reps = frame * texels_per_pixel / tex_size
    half = 2 * z  # twice the view, so no edge is visible
    v = np.array([[-half, -half, -z], [half, -half, -z], [half, half, -z], [-half, half, -z]])
    st = np.array([[0, 0], [2 * reps, 0], [2 * reps, 2 * reps], [0, 2 * reps]], float)
    vp = cam.view_projection(frame, frame)
    clip = np.concatenate([v, np.ones((4, 1))], 1) @ vp.T
    f = rasterize(np.stack([clip[[0, 1, 2]], clip[[0, 2, 3]]]), np.stack([st[[0, 1, 2]], st[[0, 2, 3]]]),
                  np.zeros(2, int), frame, frame, cam.near)
    return f


@pytest.mark.parametrize("k,lod", [(4, 2.0), (1, 0.0), (8, 3.0), (2, 1.0)])
def test_lod_of_known_minification(k, lod):
    f = _facing_quad_lod(k)
    assert len(f) == 64 * 64
    lam = level_of_detail(f, np.full(len(f), 256), np.full(len(f), 256))
    assert np.allclose(lam, lod, atol=1e-9)
    q = quantize_lod(lam, np.full(len(f), 9))
    assert (q == int(lod) << FRAC_BITS).all()
    sampler = Sampler([[(256 >> n, 256 >> n) for n in range(9)]], mode="trilinear", stream="fixed")
    reqs = sampler.requests(f).reshape(-1, 8, 4)
    assert (reqs[:, :4, 1] == int(lod)).all() and (reqs[:, 4:, 1] == int(lod) + 1).all()


def test_lod_clamps_to_the_pyramid():
    shapes = [[(8, 8), (4, 4), (2, 2), (1, 1)]]
    sm = Sampler(shapes, stream="fixed")
    mag = fragments([0.3], [0.3], d=(0.01, 0, 0, 0.01))  # 0.08 texels per pixel: magnification
    r = sm.requests(mag)
    assert (r[:, 1] == [0, 0, 0, 0, 1, 1, 1, 1]).all()
    big = fragments([0.3], [0.3], d=(100.0, 0, 0, 100.0))
    r = sm.requests(big)
    assert (r[:, 1] == 3).all()  # the 1x1 level, twice
    flat = fragments([0.3], [0.3])  # zero derivatives: lambda = -LOD_LIMIT -> level 0
    assert (sm.requests(flat)[:4, 1] == 0).all()


def test_trilinear_weights_sum_exactly_for_random_fractions():
    rng = np.random.default_rng(0)
    fr = rng.integers(0, 1 << FRAC_BITS, size=(5, 100_000))
    w = trilinear_weights(*fr)
    assert w.shape == (100_000, 8)
    assert (w >= 0).all()
    assert (w.sum(1) == 1 << WEIGHT_BITS).all()
    edge = trilinear_weights([0, 255], [0, 255], [255, 0], [255, 0], [0, 255])
    assert (edge.sum(1) == 1 << WEIGHT_BITS).all()


def test_trilinear_weights_sum_in_the_sampler_and_constant_texture_is_exact():
    rng = np.random.default_rng(1)
    n = 5000
    img = np.full((32, 16, 3), (17, 200, 99), np.uint8)
    src = ReferenceSource([img])
    sm = Sampler([src.level_shapes(0)], mode="trilinear", stream="fixed")
    f = fragments(rng.uniform(-3, 3, n), rng.uniform(-3, 3, n), w=100,
               d=tuple(rng.uniform(-0.2, 0.2, 4)))
    f.dsdx = rng.uniform(-0.3, 0.3, n)
    f.dtdy = rng.uniform(-0.3, 0.3, n)
    reqs = sm.requests(f)
    w = sm.weights.astype(np.int64).reshape(n, 8)
    assert (w.sum(1) == 1 << WEIGHT_BITS).all()
    frame = sm.resolve(src.fetch(*reqs.T))
    assert (frame.reshape(-1, 4)[:n] == (17, 200, 99, 255)).all()


def test_trilinear_matches_float_reference_up_to_rounding():
    rng = np.random.default_rng(2)
    img = rng.integers(0, 256, (16, 16, 4), dtype=np.uint8)
    src = ReferenceSource([img])
    pyr = build_pyramid(img)
    n = 3000
    s, t = rng.uniform(0, 1, n), rng.uniform(0, 1, n)
    f = fragments(s, t, w=100)
    f.dsdx = rng.uniform(0.001, 0.2, n)
    f.dtdy = f.dsdx.copy()
    sm = Sampler([src.level_shapes(0)])
    frame = sm.resolve(src.fetch(*sm.requests(f).T)).reshape(-1, 4)[:n].astype(float)
    lam = np.clip(np.floor(np.log2(f.dsdx * 16) * 256 + 0.5) / 256, 0, 4)

    def bilinear(level, s, t):
        a = pyr[level].astype(float)
        hh, ww = a.shape[:2]
        # positions quantised like the sampler (8-bit fractions): the filter is then exact
        u = (np.floor(s * ww * 256) - 128) / 256
        v = (np.floor(t * hh * 256) - 128) / 256
        i0, j0 = np.floor(u).astype(int), np.floor(v).astype(int)
        fu, fv = (u - i0)[:, None], (v - j0)[:, None]
        g = lambda i, j: a[j % hh, i % ww]  # noqa: E731
        return (g(i0, j0) * (1 - fu) * (1 - fv) + g(i0 + 1, j0) * fu * (1 - fv)
                + g(i0, j0 + 1) * (1 - fu) * fv + g(i0 + 1, j0 + 1) * fu * fv)

    l0 = np.floor(lam).astype(int)
    fl = (lam - l0)[:, None]
    ref = np.zeros((n, 4))
    for lv in range(5):
        sel = l0 == lv
        if sel.any():
            ref[sel] = bilinear(lv, s[sel], t[sel]) * (1 - fl[sel]) + bilinear(min(lv + 1, 4), s[sel], t[sel]) * fl[sel]
    # the only error left is the final round to nearest
    assert np.abs(frame - ref).max() <= 0.5 + 1e-6


def test_wrap_and_clamp_addressing():
    i = np.array([-17, -1, 0, 5, 7, 8, 9, 100])
    assert address(i, 8, np.ones(len(i), bool)).tolist() == [7, 7, 0, 5, 7, 0, 1, 4]
    assert address(i, 8, np.zeros(len(i), bool)).tolist() == [0, 0, 0, 5, 7, 7, 7, 7]
    img = np.arange(8 * 4 * 3, dtype=np.uint8).reshape(4, 8, 3)
    shapes = [ReferenceSource([img]).level_shapes(0)] * 3
    sm = Sampler(shapes, address=["wrap", "clamp", ("wrap", "clamp")], mode="point")
    s = np.array([-0.01, 1.01, -0.01, 1.01, -0.01, 1.5])
    t = np.array([-0.01, 1.01, -0.01, 1.01, 1.3, 1.3])
    r = sm.requests(fragments(s, t, tex=[0, 0, 1, 1, 2, 2]))
    assert r[:, 2].tolist() == [7, 0, 0, 7, 7, 4]
    assert r[:, 3].tolist() == [3, 0, 0, 3, 3, 3]
    # trilinear footprint at a clamped border repeats the edge texel
    sm = Sampler(shapes[:1], address=["clamp"], stream="fixed")
    r = sm.requests(fragments([0.0], [0.0])).reshape(8, 4)
    assert r[:4, 2].tolist() == [0, 0, 0, 0] and r[:4, 3].tolist() == [0, 0, 0, 0]
    sm = Sampler(shapes[:1], address=["wrap"], stream="fixed")
    r = sm.requests(fragments([0.0], [0.0])).reshape(8, 4)
    assert r[:4, 2].tolist() == [7, 0, 7, 0] and r[:4, 3].tolist() == [3, 3, 0, 0]


def test_point_sampling_equals_direct_lookup():
    rng = np.random.default_rng(4)
    imgs = [rng.integers(0, 256, (32, 64, 3), dtype=np.uint8), rng.integers(0, 256, (16, 16), dtype=np.uint8)]
    src = ReferenceSource(imgs)
    n = 4000
    tex = rng.integers(0, 2, n)
    s, t = rng.uniform(-2, 3, n), rng.uniform(-2, 3, n)
    sm = Sampler([src.level_shapes(k) for k in range(2)], mode="point")
    reqs = sm.requests(fragments(s, t, w=50, tex=tex))
    assert (reqs[:, 1] == 0).all() and (reqs[:, 0] == tex).all()
    frame = sm.resolve(src.fetch(*reqs.T)).reshape(-1, 4)[:n]
    for k in range(2):
        sel = tex == k
        lv = build_pyramid(imgs[k])[0]
        h, w = lv.shape[:2]
        i = np.floor(s[sel] * w).astype(int) % w
        j = np.floor(t[sel] * h).astype(int) % h
        assert (frame[sel] == lv[j, i]).all()


def test_request_order_and_background():
    src = ReferenceSource([np.zeros((8, 8, 3), np.uint8)])
    sm = Sampler([src.level_shapes(0)], background=(1, 2, 3), stream="fixed")
    f = Fragments(4, 2, np.array([1, 6]), np.zeros(2, np.int64), np.zeros(2, np.int64),
                  np.array([0.3, 0.5]), np.array([0.3, 0.5]), *(np.full(2, 0.1),) * 4)
    r = sm.requests(f).reshape(2, 8, 4)
    # per pixel: level L0 then L1; inside a level (i0,j0), (i1,j0), (i0,j1), (i1,j1)
    for p in r:
        for lv in (p[:4], p[4:]):
            assert lv[1, 2] == (lv[0, 2] + 1) % 8 or lv[1, 2] == lv[0, 2]
            assert lv[0, 3] == lv[1, 3] and lv[2, 3] == lv[3, 3]
            assert lv[0, 2] == lv[2, 2] and lv[1, 2] == lv[3, 2]
        assert p[0, 1] <= p[4, 1]
    out = sm.resolve(np.full((16, 4), 9, np.uint8))
    assert out.shape == (2, 4, 4)
    flat = out.reshape(-1, 4)
    assert (flat[[1, 6]] == 9).all()
    assert (np.delete(flat, [1, 6], 0) == (1, 2, 3, 255)).all()
    with pytest.raises(ValueError):
        sm.resolve(np.zeros((15, 4), np.uint8))
    with pytest.raises(ValueError):
        sm.resolve(np.zeros((16, 4), np.int64))


def test_sampler_rejects_bad_configuration():
    with pytest.raises(ValueError):
        Sampler([[(8, 8)]], mode="bilinear-ish")
    with pytest.raises(ValueError):
        Sampler([[(6, 8)]])
    with pytest.raises(ValueError):
        Sampler([[(8, 8)]], address=["border"])
