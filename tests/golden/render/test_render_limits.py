"""The rasterizer at the limits of float64 (raster.py's Limits): magnitudes from 1e-30 to 1e30.

- Clipping is exact or refused: a quad that covers the frame, scaled up by any factor up to 1e30,
  covers every pixel exactly once, or (a clipped triangle beyond ``CLIP_RANGE`` times the near
  plane) is refused with ValueError; never half the frame. Below the bound it is never refused.
- Scaling a scene and its near plane by a power of two (2^-100 .. 2^100) gives the same fragments,
  bit for bit: clipping, the perspective divide and the interpolation do not depend on the magnitude.
- NaN or infinite positions and texture coordinates are refused with ValueError, never sampled.
"""

import warnings

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from vqtex.golden.render.raster import CLIP_RANGE, rasterize

NEAR = 0.1


def _quad_covering_the_frame(margins, angle):
    """The four NDC corners of a rectangle around the whole frame ([-1, 1]^2): half-sides of at least
    1.5 (beyond the frame's circumscribed circle, radius sqrt 2), rotated by ``angle``."""
    a, b, c, d = (1.5 + v for v in margins)
    corners = np.array([[-a, -b], [c, -b], [c, d], [-a, d]])
    rot = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    return corners @ rot.T


def _clip(ndc, w):
    v = np.concatenate([ndc * w, np.zeros((len(ndc), 1)), np.full((len(ndc), 1), w)], 1)
    return np.stack([v[[0, 1, 2]], v[[0, 2, 3]]])


@settings(max_examples=150)
@given(st.lists(st.floats(0, 3), min_size=4, max_size=4), st.floats(0, 2 * np.pi), st.floats(-0.9, 0.9),
       st.floats(-0.9, 0.9), st.floats(0, 30), st.floats(NEAR, 1e3), st.integers(1, 48), st.integers(1, 48))
def test_a_frame_covering_quad_covers_every_pixel_once_or_is_refused(margins, angle, cx, cy, exponent, w, width,
                                                                     height):
    scale = 10.0 ** exponent
    ndc = _quad_covering_the_frame(margins, angle)
    centre = np.array([cx, cy])
    ndc = centre + (ndc - centre) * scale              # still around the frame: it grows about a point inside
    clip = _clip(ndc, w)
    magnitude = np.abs(clip[..., [0, 1, 3]]).max()
    with warnings.catch_warnings():
        warnings.simplefilter("error")                # no divide-by-zero or overflow on the way
        try:
            f = rasterize(clip, np.zeros((2, 3, 2)), np.zeros(2, np.int64), width, height, near=NEAR)
        except ValueError as e:
            assert "needs clipping" in str(e) and magnitude > CLIP_RANGE * NEAR, (magnitude, e)
            return
    cover = np.bincount(f.pixel, minlength=width * height)
    assert (cover == 1).all(), (scale, cover.min(), cover.max(), width * height - (cover == 1).sum())


@settings(max_examples=150)
@given(st.lists(st.tuples(st.floats(-3, 3), st.floats(-3, 3), st.floats(-1, 3)), min_size=3, max_size=3),
       st.lists(st.floats(-4, 4), min_size=6, max_size=6), st.integers(-100, 100), st.integers(1, 40),
       st.integers(1, 40))
def test_scaling_by_a_power_of_two_changes_nothing(verts, st_values, k, width, height):
    clip = np.array([[[x, y, 0.0, w] for x, y, w in verts]])
    st_ = np.array(st_values).reshape(1, 3, 2)
    ref = rasterize(clip, st_, np.zeros(1, np.int64), width, height, near=NEAR)
    scaled = rasterize(clip * 2.0 ** k, st_, np.zeros(1, np.int64), width, height, near=NEAR * 2.0 ** k)
    assert np.array_equal(ref.pixel, scaled.pixel) and np.array_equal(ref.tri, scaled.tri)
    for name in ("s", "t", "dsdx", "dsdy", "dtdx", "dtdy"):
        assert np.array_equal(getattr(ref, name), getattr(scaled, name)), name


@pytest.mark.parametrize("exponent", range(-30, 31, 5))
def test_tiny_and_huge_triangles_that_need_no_clipping(exponent):
    """Inside the guard band and in front of the near plane: no bound. A triangle of 1e-30 of the
    frame covers at most one pixel; one at w = 1e30 (far away, the same shape on the screen) covers
    the same pixels as at w = 1."""
    s = 10.0 ** exponent
    tri = np.array([[[-0.5, -0.5, 0, 1], [0.5, -0.5, 0, 1], [0, 0.5, 0, 1]]], float)
    small = tri.copy()
    small[..., :2] *= min(s, 1.0)
    f = rasterize(small, np.zeros((1, 3, 2)), np.zeros(1, np.int64), 32, 32, near=NEAR)
    assert len(f) <= 1 if s < 1e-2 else len(f) > 0
    far = rasterize(tri * max(s, 1.0), np.zeros((1, 3, 2)), np.zeros(1, np.int64), 32, 32, near=NEAR)
    assert np.array_equal(far.pixel, rasterize(tri, np.zeros((1, 3, 2)), np.zeros(1, np.int64), 32, 32).pixel)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_positions_and_texture_coordinates_are_refused(bad):
    tri = np.array([[[-0.5, -0.5, 0, 1], [0.5, -0.5, 0, 1], [0, 0.5, 0, 1]]], float)
    st_ = np.zeros((1, 3, 2))
    for index in ((0, 0, 0), (0, 1, 1), (0, 2, 3)):
        c = tri.copy()
        c[index] = bad
        with pytest.raises(ValueError, match="clip-space coordinates of triangle 0 are not finite"):
            rasterize(c, st_, np.zeros(1, np.int64), 16, 16)
    s = st_.copy()
    s[0, 1, 0] = bad
    with pytest.raises(ValueError, match="texture coordinates of triangle 0 are not finite"):
        rasterize(tri, s, np.zeros(1, np.int64), 16, 16)


def test_texture_coordinates_that_overflow_are_refused():
    """Finite (s, t) of 1e308 whose interpolation overflows: refused, never NaN fragments."""
    tri = np.array([[[-1, -1, 0, 1], [1, -1, 0, 1], [0, 1, 0, 0.5]]], float)
    st_ = np.array([[[1.7e308, 0], [-1.7e308, 0], [0, 0]]])
    with pytest.raises(ValueError, match="overflow"):
        rasterize(tri, st_, np.zeros(1, np.int64), 16, 16)


def test_the_reported_triangles():
    """The triangles of the report: near 1e24 (refused with the bound, no w = 0 warnings), scaled by
    1e21 (refused, not half the frame), exact up to the bound."""
    quad = np.array([[[-1, -1, 0, 1], [1, -1, 0, 1], [1, 1, 0, 1]], [[-1, -1, 0, 1], [1, 1, 0, 1], [-1, 1, 0, 1]]],
                    float)
    for s in (1e21, 1e24):
        q = quad.copy()
        q[..., :2] *= s
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            with pytest.raises(ValueError, match="needs clipping"):
                rasterize(q, np.zeros((2, 3, 2)), np.zeros(2, np.int64), 64, 48)
    behind = np.array([[[1e24, 0, 0, -1e24], [-1e24, 1e24, 0, 1e24], [0, -1e24, 0, 1e24]]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match="needs clipping"):
            rasterize(behind, np.zeros((1, 3, 2)), np.zeros(1, np.int64), 64, 48)
    q = quad.copy()
    q[..., :2] *= CLIP_RANGE * 0.1 * 0.99
    f = rasterize(q, np.zeros((2, 3, 2)), np.zeros(2, np.int64), 64, 48, near=0.1)
    assert (np.bincount(f.pixel, minlength=64 * 48) == 1).all()
