"""golden.color: the fixed-point matrix against its float64 reference, and the Dreamcast decode."""

import numpy as np
import pytest

from vqtex.golden.color import (DREAMCAST_YUV422, JFIF_BT601, ColorMatrix, rgb_to_yuv, yuv_to_rgb_float)


def _all_inputs(step=3):
    v = np.arange(0, 256, step)
    v = np.union1d(v, [0, 1, 127, 128, 129, 254, 255])
    return np.stack(np.meshgrid(v, v, v, indexing="ij"), -1).reshape(-1, 3).astype(np.uint8)


def test_jfif_within_stated_bound_of_float():
    x = _all_inputs()
    fixed = JFIF_BT601.apply(x).astype(np.float64)
    ref = np.clip(JFIF_BT601.apply_float(x), 0, 255)
    err = np.abs(fixed - ref).max()
    bound = JFIF_BT601.error_bound()
    assert err <= bound and bound < 0.6
    # and it is round-to-nearest almost everywhere
    assert (fixed == np.clip(np.floor(JFIF_BT601.apply_float(x) + 0.5), 0, 255)).mean() > 0.99


def test_forward_inverse_round_trip():
    rng = np.random.default_rng(0)
    rgb = rng.integers(0, 256, (10000, 3))
    assert np.allclose(yuv_to_rgb_float(rgb_to_yuv(rgb)), rgb, atol=1e-6)
    yuv = np.clip(np.rint(rgb_to_yuv(rgb)), 0, 255).astype(np.uint8)
    assert np.abs(JFIF_BT601.apply(yuv).astype(int) - rgb).max() <= 2


def test_dreamcast_is_the_same_unit():
    """R = Y + 11V/8, G = Y - (11U + 22V)/32, B = Y + 110U/64, floored, clamped."""
    x = _all_inputs(5).astype(np.int64)
    y, u, v = x[:, 0], x[:, 1] - 128, x[:, 2] - 128
    r = y + (11 * 8 * v) // 64
    g = y + (-22 * u - 44 * v) // 64
    b = y + (110 * u) // 64
    want = np.clip(np.stack([r, g, b], 1), 0, 255)
    assert (DREAMCAST_YUV422.apply(x.astype(np.uint8)) == want).all()
    # matches pvrtex's float formula truncated towards minus infinity
    fl = np.floor(DREAMCAST_YUV422.apply_float(x))
    assert (np.clip(fl, 0, 255) == want).all()
    assert DREAMCAST_YUV422.error_bound() == 1.0


def test_floor_is_arithmetic_shift():
    m = ColorMatrix(coeffs=((1, 0, 0), (0, 1, 0), (0, 0, 1)), offsets=(128, 128, 128), frac_bits=1, rounding=False)
    out = m.apply(np.array([[127, 129, 0]], np.uint8))
    # (127-128)>>1 = -1 -> 0 ; (129-128)>>1 = 0 ; (0-128)>>1 = -64 -> 0
    assert out.tolist() == [[0, 0, 0]]


def test_bad_parameters():
    with pytest.raises(ValueError):
        ColorMatrix(coeffs=((1 << 17, 0, 0), (0, 1, 0), (0, 0, 1)))
    with pytest.raises(ValueError):
        ColorMatrix(coeffs=((1, 0, 0), (0, -(1 << 17) - 1, 0), (0, 0, 1)))
    with pytest.raises(ValueError):
        ColorMatrix(coeffs=((1, 0), (0, 1)))
    with pytest.raises(ValueError):
        ColorMatrix(coeffs=((1, 0, 0), (0, 1, 0), (0, 0, 1)), frac_bits=20)


def test_coefficients_span_the_18_bit_signed_range():
    """-2^17 and 2^17 - 1 both fit one 18-bit multiplier operand; apply() equals Python's exact
    integers (floor shift) at both ends of the range."""
    lo, hi = -(1 << 17), (1 << 17) - 1
    m = ColorMatrix(coeffs=((lo, hi, 0), (hi, lo, lo), (lo, lo, hi)), offsets=(0, 255, 128), frac_bits=16)
    x = np.random.default_rng(3).integers(0, 256, (2000, 3))
    want = [[min(max((sum(c * (int(v) - o) for c, v, o in zip(row, px, m.offsets)) + m.bias) >> 16, 0), 255)
             for row in m.coeffs] for px in x]
    out = m.apply(x.astype(np.uint8))
    assert out.tolist() == want
    assert 0 < (out == 0).mean() < 1 and 0 < (out == 255).mean() < 1 and ((out > 0) & (out < 255)).any()
