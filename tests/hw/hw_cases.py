"""Texture sets and request streams shared by the tests/hw tests (small: pysim is slow)."""

from __future__ import annotations

import functools

import numpy as np

from golden.color import DREAMCAST_YUV422, JFIF_BT601
from golden.encode import encode
from golden.fetch import block_address, lookup_descriptor
from golden.format import TextureSet


def image(size, seed, channels=4):
    """A noisy gradient (h, w, channels) uint8: every codeword gets used, mip levels differ."""
    w, h = size
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:h, 0:w]
    base = np.stack([xx * 255 // max(1, w - 1), yy * 255 // max(1, h - 1), (xx + yy) * 127 // max(1, w + h - 2),
                     255 - yy * 200 // max(1, h - 1)], axis=2)
    img = np.clip(base + rng.integers(-60, 61, (h, w, 4)), 0, 255).astype(np.uint8)
    return img[..., :channels]


#: name -> encode() keyword arguments. Sizes 32..64, 8..16 codewords (256 for the full 8-bit range).
CONFIGS = {
    "rgb_4x4_b8_mip": dict(size=(64, 64), block=(4, 4), codebook_size=16, color="rgb", index_bits=8,
                           mipmaps=True, raw_below=4),
    "yuv_4x4_b12_mip": dict(size=(64, 64), block=(4, 4), codebook_size=16, color="yuv411", index_bits=12,
                            mipmaps=True, raw_below=4),
    "rgba_2x2_b7_mip_w16": dict(size=(32, 32), block=(2, 2), codebook_size=16, color="rgba", index_bits=7,
                                mipmaps=True, raw_below=4, word_bits=16),
    "i8_4x2_b5_w64": dict(size=(64, 32), block=(4, 2), codebook_size=12, color="intensity", index_bits=5,
                          word_bits=64),
    "yuv_2x4_b12_mip_w64": dict(size=(32, 64), block=(2, 4), codebook_size=10, color="yuv411", index_bits=12,
                                mipmaps=True, raw_below=8, word_bits=64),
    "rgb_4x4_b12_w16": dict(size=(32, 32), block=(4, 4), codebook_size=16, color="rgb", index_bits=12,
                            word_bits=16),
    "rgb_4x4_b8_k256": dict(size=(64, 64), block=(4, 4), codebook_size=256, color="rgb", index_bits=8),
    "rgb_2x2_b16_w16": dict(size=(32, 32), block=(2, 2), codebook_size=8, color="rgb", index_bits=16,
                            word_bits=16),
    "i8_4x4_b1_mip": dict(size=(32, 32), block=(4, 4), codebook_size=2, color="intensity", index_bits=1,
                          mipmaps=True, raw_below=4),
    "rgba_8x8_b9_mip": dict(size=(64, 64), block=(8, 8), codebook_size=8, color="rgba", index_bits=9,
                            mipmaps=True, raw_below=8),
    "yuv_8x2_b6": dict(size=(64, 32), block=(8, 2), codebook_size=8, color="yuv411", index_bits=6),
    "raw_only_8x8_mip": dict(size=(8, 8), block=(4, 4), codebook_size=4, color="rgb", mipmaps=True),
    "yuv_dreamcast_4x4_b12_mip": dict(size=(64, 64), block=(4, 4), codebook_size=16, color="yuv411",
                                      index_bits=12, mipmaps=True, raw_below=4, matrix=DREAMCAST_YUV422),
}


@functools.lru_cache(maxsize=None)
def texture_set(name: str, seed: int = 0, images: int = 1) -> TextureSet:
    kw = dict(CONFIGS[name])
    size = kw.pop("size")
    return encode([image(size, seed + n) for n in range(images)], seed=seed, **kw)


@functools.lru_cache(maxsize=None)
def combined_set() -> TextureSet:
    """Several groups with their own codebooks and formats (and two textures sharing one), 32-bit words."""
    parts = [
        encode([image((64, 64), 10), image((32, 32), 11)], block=(4, 4), codebook_size=16, color="rgb",
               index_bits=8, mipmaps=True, raw_below=4, seed=1),
        encode([image((32, 32), 12)], block=(2, 2), codebook_size=8, color="yuv411", index_bits=12, seed=2),
        encode([image((64, 32), 13)], block=(4, 2), codebook_size=12, color="intensity", index_bits=5,
               mipmaps=True, raw_below=8, seed=3),
        encode([image((32, 64), 14)], block=(2, 4), codebook_size=16, color="rgba", index_bits=7, seed=4),
        encode([image((8, 8), 15)], block=(4, 4), codebook_size=4, color="rgb", mipmaps=True, seed=5),  # all raw
    ]
    return TextureSet.combine(parts)


def levels(ts: TextureSet):
    """Every (texture, level, width, height)."""
    for t in range(ts.n_textures):
        for L, (w, h) in enumerate(ts.level_shapes(t)):
            yield t, L, w, h


def random_requests(ts: TextureSet, n: int, seed: int) -> np.ndarray:
    """n uniformly random (texture, level, i, j), every level equally likely."""
    rng = np.random.default_rng(seed)
    lv = np.array(list(levels(ts)))
    pick = lv[rng.integers(0, len(lv), n)]
    i = (rng.random(n) * pick[:, 2]).astype(np.int64)
    j = (rng.random(n) * pick[:, 3]).astype(np.int64)
    return np.stack([pick[:, 0], pick[:, 1], i, j], axis=1)


def adversarial_requests(ts: TextureSet, seed: int = 0) -> np.ndarray:
    """Every corner of every level; the first and last block's corners; for every compressed level,
    a texel of blocks whose index starts at every bit offset of a word (every straddle position)."""
    rng = np.random.default_rng(seed)
    out = []
    for t, L, w, h in levels(ts):
        for i, j in ((0, 0), (w - 1, 0), (0, h - 1), (w - 1, h - 1)):
            out.append((t, L, i, j))
        d = ts.descriptor(t, L)
        if not d["compressed"]:
            out.append((t, L, int(rng.integers(0, w)), int(rng.integers(0, h))))
            continue
        bw, bh = 1 << d["log2bw"], 1 << d["log2bh"]
        nbx, nby = w // bw, h // bh
        # first and last block: their far corners too
        out += [(t, L, bw - 1, bh - 1), (t, L, w - bw, h - bh)]
        # blocks 0 .. W-1 cover every offset k*b mod W (one per offset class)
        b, W = d["index_bits"], ts.word_bits
        seen = set()
        for k in range(min(nbx * nby, W)):
            off = (k * b) % W
            if off in seen:
                continue
            seen.add(off)
            bx, by = k % nbx, k // nbx
            out.append((t, L, bx * bw + int(rng.integers(0, bw)), by * bh + int(rng.integers(0, bh))))
    req = np.array(out, dtype=np.int64)
    return req[rng.permutation(len(req))]


def straddle_offsets(ts: TextureSet, req: np.ndarray) -> set:
    """Bit offsets (k*b mod W) at which the compressed requests' indices start."""
    d = lookup_descriptor(ts, req[:, 0], req[:, 1])
    comp = d["compressed"].astype(bool)
    k, _, _ = block_address(d[comp], req[comp, 2], req[comp, 3])
    return set(((k * d[comp]["index_bits"].astype(np.int64)) % ts.word_bits).tolist())


__all__ = ["image", "CONFIGS", "texture_set", "combined_set", "levels", "random_requests",
           "adversarial_requests", "straddle_offsets", "JFIF_BT601"]
