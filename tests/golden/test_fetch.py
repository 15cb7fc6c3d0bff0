"""golden.fetch: per-texel fetch from the memory images against independent decodes and by hand."""

import numpy as np
import pytest

from vqtex.golden.encode import encode, reference_pyramid
from vqtex.golden.mipmap import box_down as _box_down
from vqtex.golden.fetch import RequestError, check_requests, decode, fetch, straddles, lookup_descriptor, block_address
from vqtex.golden.format import TextureSet

COLORS = ["rgb", "rgba", "intensity", "yuv411"]
BLOCKS = [(2, 2), (4, 4), (4, 2), (2, 4), (4, 1), (1, 4), (8, 8), (1, 1)]


def _img(h, w, c=4, seed=0):
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:h, 0:w]
    base = np.stack([xx * 255 // max(w - 1, 1), yy * 255 // max(h - 1, 1), (xx ^ yy) & 255, (xx + yy) * 3 & 255], -1)
    return np.clip(base + rng.integers(-20, 21, (h, w, 4)), 0, 255).astype(np.uint8)[..., :c]


def _fetch_level(ts, t, L):
    w, h = ts.level_shapes(t)[L]
    jj, ii = np.mgrid[0:h, 0:w]
    n = w * h
    return fetch(ts, np.full(n, t), np.full(n, L), ii.ravel(), jj.ravel()).reshape(h, w, 4)


@pytest.mark.parametrize("color", COLORS)
@pytest.mark.parametrize("block", BLOCKS)
def test_fetch_equals_decode_every_level(color, block):
    """Every format, block shape and sub-level (mipmapped, several groups, raw levels)."""
    imgs = [_img(64, 64, seed=1), _img(32, 128, seed=2)]
    ts = encode(imgs, block=block, codebook_size=16, color=color, mipmaps=True, raw_below=4,
                index_bits=7, encoder="tsvq")
    subs = set()
    for t in range(2):
        for L in range(ts.textures[t].levels):
            d = ts.descriptor(t, L)
            subs.add((d["compressed"], d["sublevel"]))
            assert np.array_equal(_fetch_level(ts, t, L), decode(ts, t, L)), (t, L)
    expect_subs = {(1, s) for s in range(min(3, 1 + min(block).bit_length() - 1))} | {(0, 0)}
    assert subs == expect_subs


def test_average_extended_codewords_are_box_filters():
    """The paper's extended codewords: sub-level s+1 of every decoded level group equals the
    rounded 2x2 mean of sub-level s (exact for formats without a colour matrix)."""
    for color in ("rgb", "rgba", "intensity"):
        ts = encode([_img(64, 64, seed=5)], codebook_size=16, color=color, mipmaps=True, raw_below=4,
                    encoder="tsvq")
        for L in (0, 1, 3):          # level 5 (2x2) is below raw_below=4: raw
            assert np.array_equal(_box_down(decode(ts, 0, L)), decode(ts, 0, L + 1)), (color, L)


def test_hand_built_set():
    """A set whose every texel is known by construction: one 4x4 codeword per block, codeword n
    holding texels (n, x, y). 12-bit indices so that indices straddle words."""
    w = h = 32
    nb = (w // 4) * (h // 4)                       # 64 blocks, codebook of 64 codewords
    imgs = np.zeros((h, w, 3), np.uint8)
    for by in range(h // 4):
        for bx in range(w // 4):
            n = by * (w // 4) + bx
            for y in range(4):
                for x in range(4):
                    imgs[by * 4 + y, bx * 4 + x] = (n * 3, x * 16 + y, 200 - n)
    ts = encode([imgs], codebook_size=64, index_bits=12, encoder="gla")
    got = _fetch_level(ts, 0, 0)
    assert np.array_equal(got[..., :3], imgs) and (got[..., 3] == 255).all()
    d = lookup_descriptor(ts, np.zeros(nb, int), np.zeros(nb, int))
    k, _, _ = block_address(d, (np.arange(nb) % 8) * 4, (np.arange(nb) // 8) * 4)
    assert np.array_equal(k, np.arange(nb))
    assert straddles(d, k, 32).sum() == nb // 8 * 2      # 12-bit indices straddle at k*12 mod 32 in {24, 28}


def test_constant_image_exact_every_format():
    for color in COLORS:
        img = np.full((64, 64, 4), (200, 100, 50, 128), np.uint8)
        ts = encode([img], codebook_size=4, color=color, mipmaps=True, raw_below=8)
        ref = reference_pyramid(img, color, True)
        for L in range(ts.textures[0].levels):
            got = decode(ts, 0, L)
            tol = 1 if color == "yuv411" else 0          # one rounding through YUV
            assert np.abs(got.astype(int) - ref[L]).max() <= tol, (color, L)


def test_values_at_0_and_255_and_two_colours():
    img = np.zeros((32, 32, 3), np.uint8)
    img[::2, :, :] = 255
    img[:, ::3, 1] = 0
    ts = encode([img], block=(2, 2), codebook_size=64)
    assert np.array_equal(decode(ts, 0, 0)[..., :3], img)        # few distinct blocks: exact
    two = np.zeros((64, 64, 3), np.uint8)
    two[:32] = (255, 0, 0)
    two[32:] = (0, 255, 255)
    ts = encode([two], codebook_size=2)
    assert np.array_equal(decode(ts, 0, 0)[..., :3], two)


def test_check_requests():
    ts = encode([_img(32, 64, 3)], codebook_size=4, mipmaps=True)
    check_requests(ts, [0, 0], [0, 6], [63, 0], [31, 0])
    for bad in ([1], [0], [0], [0]), ([0], [7], [0], [0]), ([0], [0], [64], [0]), ([0], [1], [0], [16]), ([0], [0], [-1], [0]):
        with pytest.raises(RequestError):
            check_requests(ts, *bad)


def test_fetch_is_vectorised_over_mixed_requests():
    """One call over requests from several textures, codebooks, formats and raw levels equals
    per-level decodes."""
    sets = [encode([_img(64, 64, 3, seed=s)], codebook_size=8, color=c, mipmaps=True, raw_below=16,
                   block=b, index_bits=ib, encoder="tsvq")
            for s, (c, b, ib) in enumerate([("rgb", (4, 4), 8), ("yuv411", (2, 2), 12), ("intensity", (4, 2), 5)])]
    ts = TextureSet.combine(sets)
    rng = np.random.default_rng(9)
    n = 5000
    tex = rng.integers(0, 3, n)
    lev = rng.integers(0, 7, n)
    size = 64 >> lev
    i, j = rng.integers(0, 1 << 20, n) % size, rng.integers(0, 1 << 20, n) % size
    got = fetch(ts, tex, lev, i, j)
    for q in range(0, n, 97):
        assert np.array_equal(got[q], decode(ts, tex[q], lev[q])[j[q], i[q]])
