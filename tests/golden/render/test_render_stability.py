"""Fixed-point sampling and geometry under stress (issue: numerical stability).

- The eight trilinear weights sum to exactly 2^24 for every fraction and level blend.
- The level of detail is defined and finite (within [-LOD_LIMIT, LOD_LIMIT]), and every request lands
  inside its level, for any fragment: magnification, the last level, zero or infinite derivatives,
  NaN, coordinates of 1e6.
- Degenerate triangles (zero area, edge-on, behind the camera, crossing the near plane, texture
  coordinates of 1e6) rasterize to finite fragments whose requests are all in range.
- A camera or rasterizer whose near plane is at 0 (w = 0 in the perspective divide) or whose field of
  view is 0 or 180 degrees is refused with ValueError.
"""

import warnings

import numpy as np
import pytest
from hypothesis import given, strategies as st

from vqtex.golden.render.camera import Camera
from vqtex.golden.render.raster import Fragments, rasterize
from vqtex.golden.render.sampling import FRAC_BITS, LOD_LIMIT, Sampler, level_of_detail, quantize_lod, trilinear_weights

ONE = 1 << FRAC_BITS
SHAPES = [[(256, 128), (128, 64), (64, 32), (32, 16), (16, 8), (8, 4), (4, 2), (2, 1), (1, 1)],
          [(1, 1)], [(4, 4), (2, 2), (1, 1)]]


def test_trilinear_weights_sum_to_2_24_for_every_fraction():
    """Exhaustive over (fu0, fv0) and the level blend f; fu1, fv1 swept beside them."""
    fu, fv = (a.ravel() for a in np.meshgrid(np.arange(ONE), np.arange(ONE), indexing="ij"))
    for f in range(ONE):
        w = trilinear_weights(fu, fv, fv, fu, np.full(len(fu), f))
        assert (w >= 0).all() and (w.sum(axis=1) == 1 << 24).all(), f"level blend {f}"


@given(st.lists(st.tuples(*[st.integers(0, ONE - 1)] * 5), min_size=1, max_size=64))
def test_trilinear_weights_sum_property(rows):
    a = np.array(rows)
    w = trilinear_weights(*a.T)
    assert (w.sum(axis=1) == 1 << 24).all() and (w >= 0).all()


_extreme = st.one_of(st.floats(allow_nan=True, allow_infinity=True, width=64),
                     st.sampled_from([0.0, -0.0, 1e-300, 1e6, -1e6, 1e300, float("inf"), float("nan")]))
_coord = st.one_of(st.floats(-1e6, 1e6, allow_nan=False), st.sampled_from([0.0, 0.5, 1.0, -1e6, 1e6]))


def _fragments(s, t, d):
    n = len(s)
    z = np.zeros(n, np.int64)
    return Fragments(8, (n + 7) // 8, np.arange(n, dtype=np.int64), z, z, np.array(s, np.float64),
                     np.array(t, np.float64), *(np.full(n, v, np.float64) for v in d))


@given(st.lists(st.tuples(_coord, _coord), min_size=1, max_size=16), st.tuples(*[_extreme] * 4),
       st.integers(0, len(SHAPES) - 1), st.sampled_from(["wrap", "clamp", ("wrap", "clamp")]))
def test_any_fragment_gives_requests_inside_their_level(coords, derivs, shape, addressing):
    shapes = SHAPES[shape]
    sampler = Sampler([shapes], address=[addressing], mode="trilinear")
    s, t = zip(*coords)
    frags = _fragments(s, t, derivs)
    raw = sampler.lod(frags)
    assert np.isfinite(raw).all() and (np.abs(raw) <= LOD_LIMIT).all()
    lam = quantize_lod(raw, np.full(len(s), len(shapes)))
    assert (lam >= 0).all() and (lam <= (len(shapes) - 1) * ONE).all()
    reqs = sampler.requests(frags)
    lv = reqs[:, 1]
    assert (lv >= 0).all() and (lv < len(shapes)).all()
    w = np.array([shapes[k][0] for k in lv])
    h = np.array([shapes[k][1] for k in lv])
    assert ((reqs[:, 2] >= 0) & (reqs[:, 2] < w) & (reqs[:, 3] >= 0) & (reqs[:, 3] < h)).all()
    pixel_of = np.repeat(np.arange(len(s)), sampler.counts)      # every pixel's weights still sum to 2^24
    assert (np.bincount(pixel_of, sampler.weights, len(s)) == 1 << 24).all()
    frame = sampler.resolve(np.full((len(reqs), 4), 200, np.uint8))
    assert (frame.reshape(-1, 4)[:len(s)] == 200).all()      # constant texels: exactly reproduced


def _clip(cam, verts, w=32, h=32):
    v = np.concatenate([np.asarray(verts, np.float64), np.ones((len(verts), 1))], 1)
    return (cam.view_projection(w, h) @ v.T).T


CAM = Camera(position=(0.0, 0.0, 3.0), target=(0.0, 0.0, 0.0), near=0.1)

_vertex = st.tuples(*[st.one_of(st.floats(-5, 5, allow_nan=False), st.sampled_from([0.0, 1.0, -1.0, 2.9, 3.0, 3.1]))] * 3)


@given(st.lists(st.tuples(_vertex, _vertex, _vertex), min_size=1, max_size=4),
       st.sampled_from([1.0, 1e6]), st.booleans())
def test_degenerate_triangles_give_finite_fragments_and_valid_requests(tris, st_scale, collapse):
    """Zero area (collapse: a repeated vertex), edge-on, behind the camera (z > 3), crossing the near
    plane (z near 2.9..3.1), texture coordinates up to 1e6."""
    tris = np.array(tris, np.float64)
    if collapse:
        tris[:, 2] = tris[:, 1]
    clip = np.stack([_clip(CAM, t) for t in tris])
    st_ = np.tile(np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]) * st_scale, (len(tris), 1, 1))
    frags = rasterize(clip, st_, np.zeros(len(tris), np.int64), 32, 32, near=CAM.near)
    for name in ("s", "t", "dsdx", "dsdy", "dtdx", "dtdy"):
        assert np.isfinite(getattr(frags, name)).all(), name
    sampler = Sampler([SHAPES[0]], mode="trilinear")
    lam = sampler.lod(frags)
    assert np.isfinite(lam).all() and (np.abs(lam) <= LOD_LIMIT).all()
    reqs = sampler.requests(frags)
    if len(reqs):
        lv = reqs[:, 1]
        w = np.array([SHAPES[0][k][0] for k in lv])
        h = np.array([SHAPES[0][k][1] for k in lv])
        assert ((reqs[:, 2] >= 0) & (reqs[:, 2] < w) & (reqs[:, 3] >= 0) & (reqs[:, 3] < h)).all()


def test_edge_on_and_behind_the_camera_cover_nothing():
    edge_on = [(0.0, -1.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, -2.0)]      # in the plane x = 0 through the eye
    behind = [(-1.0, -1.0, 4.0), (1.0, -1.0, 4.0), (0.0, 1.0, 4.0)]
    for tri in (edge_on, behind):
        frags = rasterize(_clip(CAM, tri)[None], np.zeros((1, 3, 2)), np.zeros(1, np.int64), 32, 32, near=CAM.near)
        assert len(frags) == 0


def test_lod_rule_at_the_limits():
    """Zero and underflowing derivatives -> -LOD_LIMIT, overflowing -> +LOD_LIMIT, NaN -> -LOD_LIMIT;
    ordinary ones unchanged (a pixel covering 4 x 4 texels of a 256-texel level 0 is lambda = 2)."""
    d = np.array([[0.0, 0, 0, 0], [1e-200, 0, 0, 1e-200], [1e200, 0, 0, 0], [np.inf, 0, 0, 0],
                  [np.nan, 1.0, 0, 0], [4 / 256, 0, 0, 4 / 256], [0, -1e6, 3e6, 0]])
    frags = _fragments(np.zeros(len(d)), np.zeros(len(d)), d.T)
    lam = level_of_detail(frags, np.full(len(d), 256), np.full(len(d), 256))
    want = [-LOD_LIMIT, -LOD_LIMIT, LOD_LIMIT, LOD_LIMIT, -LOD_LIMIT, 2.0, np.log2(3e6 * 256)]
    assert lam.tolist() == pytest.approx(want, rel=0, abs=1e-12)


def test_flat_texture_coordinates_give_level_0_and_a_finite_lod():
    """A triangle whose (s, t) is the same at every vertex: zero derivatives, the finest level."""
    clip = _clip(CAM, [(-1.0, -1.0, 0.0), (1.0, -1.0, 0.0), (0.0, 1.0, 0.0)])[None]
    frags = rasterize(clip, np.full((1, 3, 2), 0.25), np.zeros(1, np.int64), 32, 32, near=CAM.near)
    assert len(frags) > 0
    sampler = Sampler([SHAPES[0]], mode="trilinear", stream="fixed")
    lam = sampler.lod(frags)
    assert (lam == -LOD_LIMIT).all() and (quantize_lod(lam, np.full(len(lam), len(SHAPES[0]))) == 0).all()
    assert (sampler.requests(frags).reshape(-1, 8, 4)[:, :4, 1] == 0).all()     # L0 = 0, blend 0


@pytest.mark.parametrize("near", [0.0, -0.1, float("inf"), float("nan")])
def test_a_near_plane_at_or_behind_the_eye_is_refused(near):
    tri = _clip(CAM, [(-1.0, -1.0, 0.0), (1.0, -1.0, 0.0), (0.0, 1.0, 0.0)])[None]
    with pytest.raises(ValueError, match="near"):
        rasterize(tri, np.zeros((1, 3, 2)), np.zeros(1, np.int64), 32, 32, near=near)
    with pytest.raises(ValueError, match="near"):
        Camera(position=(0.0, 0.0, 3.0), target=(0.0, 0.0, 0.0), near=near)


@pytest.mark.parametrize("fov", [0.0, -10.0, 180.0, 270.0, float("nan")])
def test_a_field_of_view_without_a_projection_is_refused(fov):
    with pytest.raises(ValueError, match="field of view"):
        Camera(position=(0.0, 0.0, 3.0), target=(0.0, 0.0, 0.0), fov=fov)


_level_shapes = st.sampled_from(SHAPES)
_fine = st.integers(-(1 << 21), 1 << 21).map(lambda k: k / (1 << 20))     # multiples of 2^-20 in [-2, 2]


@given(st.lists(st.tuples(_fine, _fine, st.integers(-(1 << 30), 1 << 30), st.integers(-(1 << 30), 1 << 30)),
                min_size=1, max_size=16), _level_shapes, st.sampled_from(["point", "trilinear"]), _extreme)
def test_wrapped_coordinates_shifted_by_whole_repeats_fetch_the_same(rows, shapes, mode, deriv):
    """Wrap: s and s + k (k an integer, exact in float64) give the same requests and frame."""
    s, t, ks, kt = (np.array(c, np.float64) for c in zip(*rows))
    d = (deriv, 0.0, 0.0, deriv)
    a, b = Sampler([shapes], mode=mode), Sampler([shapes], mode=mode)
    ra, rb = a.requests(_fragments(s, t, d)), b.requests(_fragments(s + ks, t + kt, d))
    assert (ra == rb).all()
    texels = np.random.default_rng(len(rows)).integers(0, 256, (len(ra), 4)).astype(np.uint8)
    assert (a.resolve(texels) == b.resolve(texels)).all()


@given(st.lists(st.tuples(st.floats(2, 1e300), st.floats(2, 1e300)), min_size=1, max_size=16), _level_shapes,
       st.sampled_from(["point", "trilinear"]), _extreme)
def test_clamped_coordinates_beyond_the_edge_fetch_the_edge(far, shapes, mode, deriv):
    """Clamp: any coordinate beyond [-1, 2] fetches exactly what -1 or 2 fetches, same frame."""
    s, t = (np.array(c, np.float64) for c in zip(*far))
    sign = np.where(np.arange(len(s)) % 2, -1.0, 1.0)
    d = (deriv, 0.0, 0.0, deriv)
    a, b = Sampler([shapes], "clamp", mode), Sampler([shapes], "clamp", mode)
    ra = a.requests(_fragments(sign * s, -sign * t, d))
    rb = b.requests(_fragments(np.where(sign > 0, 2.0, -1.0), np.where(sign > 0, -1.0, 2.0), d))
    assert (ra == rb).all()
    texels = np.random.default_rng(len(far)).integers(0, 256, (len(ra), 4)).astype(np.uint8)
    assert (a.resolve(texels) == b.resolve(texels)).all()


@pytest.mark.parametrize("addressing", ["wrap", "clamp"])
def test_coordinates_of_any_size_are_defined(addressing):
    """1e15 (beyond int64 once scaled), 1e300 and infinities: requests in range, no warning; NaN
    names no texel and is refused."""
    far = [1e6, -1e6, 1e12, 1e15, -1e15, 1e300, -1e300, np.inf, -np.inf, 2.0 ** 60 + 0.5]
    n = len(far)
    shapes = SHAPES[0]
    for mode in ("point", "trilinear"):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            reqs = Sampler([shapes], addressing, mode, stream="fixed").requests(
                _fragments(far, far[::-1], (1e-3, 0, 0, 1e-3)))
        assert len(reqs) == n * (1 if mode == "point" else 8)
        w = np.array([shapes[k][0] for k in reqs[:, 1]])
        h = np.array([shapes[k][1] for k in reqs[:, 1]])
        assert ((reqs[:, 2] >= 0) & (reqs[:, 2] < w) & (reqs[:, 3] >= 0) & (reqs[:, 3] < h)).all()
        for s, t in (([0.5, np.nan], [0.5, 0.5]), ([0.5, 0.5], [np.nan, 0.5])):
            with pytest.raises(ValueError, match="NaN"):
                Sampler([shapes], addressing, mode).requests(_fragments(s, t, (1e-3, 0, 0, 1e-3)))
