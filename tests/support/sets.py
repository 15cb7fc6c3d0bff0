"""Texture sets for tests: a noisy test image, the configuration matrix (``CONFIGS``), several
groups combined, the built-in sets of ``vqtex report area``, PowerVR2 sets made byte by byte or
from pvrtex's files, a set by name (``get_set``), the texture filter's edge-case set (``filter_set``)
and the specialised unit's configurations (``SPECIALISE_CASES``)."""

from __future__ import annotations

import functools
import os

import numpy as np

from vqtex.golden.color import DREAMCAST_YUV422
from vqtex.golden.encode import encode
from vqtex.golden.format import TextureSet
from vqtex.golden.pvr2 import pvr, pvr_set
from vqtex.golden.render.scene import build_texture_set, load_scene

from .tools import PVRTEX_DATA


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


def texture_sets():
    """Small texture sets covering the configuration matrix (kept tiny for pysim)."""
    rgb12 = encode([image((64, 64), 0, 3)], codebook_size=16, mipmaps=True, index_bits=12)
    yuv = encode([image((32, 32), 1, 3), image((32, 32), 2, 3)], codebook_size=8, color="yuv411", block=(2, 2), mipmaps=True,
                 index_bits=5)
    rgba = encode([image((32, 32), 3, 4)], codebook_size=16, color="rgba", index_bits=8)
    inten = encode([image((32, 32), 4, 1)], codebook_size=32, color="intensity", block=(2, 2), index_bits=7,
                   encoder="tsvq")
    mixed = TextureSet.combine([rgb12, yuv, rgba, inten])
    w16 = encode([image((32, 32), 5, 3)], codebook_size=32, block=(2, 2), mipmaps=True, index_bits=12, word_bits=16)
    return {"rgb12": rgb12, "mixed": mixed, "w16": w16}


def levels(ts: TextureSet):
    """Every (texture, level, width, height)."""
    for t in range(ts.n_textures):
        for L, (w, h) in enumerate(ts.level_shapes(t)):
            yield t, L, w, h


@functools.lru_cache(maxsize=None)
def builtin_set(name: str) -> TextureSet:
    """The built-in texture set ``name`` of ``vqtex report area --builtin NAME`` (``tiny``, ``four``,
    ...), encoded once per test run: tests take it from here, not from the product's modules."""
    from vqtex.sim.cli.report import BUILTINS
    from vqtex.sim.reports.synth import texture_sets
    return getattr(texture_sets, BUILTINS[name][0])()


def random_dt(width: int, height: int, fmt: int, n: int, seed: int) -> bytes:
    """A Dreamcast VQ ``.dt`` made byte by byte (not by golden.pvr2.pvr_set): a random codebook of ``n``
    entries of pixel format ``fmt``, random index bytes ``256-n .. 255``, not mipmapped."""
    rng = np.random.default_rng(seed)
    body = rng.integers(0, 1 << 16, (n, 4)).astype("<u2").tobytes()
    body += rng.integers(256 - n, 256, width * height // 4).astype(np.uint8).tobytes()
    control = (1 << 30) | (fmt << 27)
    size = 32 + len(body)
    return (b"DcTx" + size.to_bytes(4, "little") + bytes([0, 0, n - 1, 0]) + width.to_bytes(2, "little")
            + height.to_bytes(2, "little") + control.to_bytes(4, "little") + bytes(12) + body)


@functools.lru_cache(maxsize=None)
def pvr2_small_sets() -> dict:
    """Tiny PowerVR2 sets for pysim: rectangles both ways, an 8x8 mip chain down to 1x1 in yuv422
    (whose 1x1 level is rgb565) and argb4444, small codebooks, one 128x128 pvrtex mip chain."""
    parts = [pvr_set.from_dt(pvr.parse_dt(random_dt(*a, seed=n), decode=False))
             for n, a in enumerate([(16, 8, 3, 17), (8, 32, 0, 256), (16, 16, 2, 5)])]
    mip = bytearray(random_dt(8, 8, 3, 200, seed=9))
    extra = np.random.default_rng(9).integers(56, 256, 6).astype(np.uint8).tobytes()   # 1x1, 2x2, 4x4 maps
    mip = bytes(mip[:32]) + bytes(mip[32:32 + 1600]) + extra + bytes(mip[32 + 1600:])
    mip = mip[:4] + len(mip).to_bytes(4, "little") + mip[8:19] + bytes([mip[19] | 0x80]) + mip[20:]
    parts.append(pvr_set.from_dt(pvr.parse_dt(mip, decode=False)))
    crate = os.path.join(PVRTEX_DATA, "generated", "crate_argb4444_c_64_m.dt")
    return {"rectangles_and_mip8": TextureSet.combine(parts), "crate_argb4444_c_64_m": pvr_set.import_dt([crate])}


@functools.lru_cache(maxsize=None)
def scene_set(name):
    return build_texture_set(load_scene(name))


@functools.lru_cache(maxsize=None)
def get_set(name):
    """A test set by name: a CONFIGS name, ``combined``, ``pvr2:NAME`` or ``scene:NAME``."""
    if name == "combined":
        return combined_set()
    if name.startswith("pvr2:"):
        return pvr2_small_sets()[name[5:]]
    if name.startswith("scene:"):
        return scene_set(name[6:])
    return texture_set(name)


@functools.lru_cache(maxsize=None)
def filter_set() -> TextureSet:
    """Nx1 and 1xN levels (32x4 and 4x16 down to 1x1), a compressed 2-level yuv411 16x16, and a
    texture without mipmaps."""
    a = encode([image((32, 4), 1), image((4, 16), 2)], block=(2, 2), codebook_size=8,
               color="rgb", mipmaps=True, raw_below=4, seed=1)
    b = encode([image((16, 16), 3)], block=(4, 4), codebook_size=8, color="yuv411", index_bits=12,
               mipmaps=True, raw_below=8, seed=2)
    c = encode([image((8, 8), 4, channels=4)], block=(2, 2), codebook_size=4, color="rgba", seed=3)
    return TextureSet.combine([a, b, c])


@functools.lru_cache(maxsize=None)
def three_widths() -> TextureSet:
    """rgb 8-bit (mipmapped), intensity 12-bit, rgba 6-bit, 32-bit words: three index widths (k*b as
    shifts and adds selected by b), straddles, raw levels, three colour formats, no yuv411."""
    return TextureSet.combine([
        encode([image((64, 64), 20, 3)], block=(4, 4), codebook_size=16, color="rgb", index_bits=8,
               mipmaps=True, raw_below=4, seed=1),
        encode([image((32, 32), 21, 1)], block=(2, 2), codebook_size=12, color="intensity", index_bits=12, seed=2),
        encode([image((32, 32), 22, 4)], block=(4, 2), codebook_size=8, color="rgba", index_bits=6, seed=3),
    ])


@functools.lru_cache(maxsize=None)
def two_widths_no_straddle() -> TextureSet:
    """rgb 8-bit and rgb 16-bit indices in 32-bit words, no mipmaps: two widths that both divide the
    word (one bank, the mask), one colour, no raw levels."""
    return TextureSet.combine([
        encode([image((32, 32), 23, 3)], block=(4, 4), codebook_size=16, color="rgb", index_bits=8, seed=4),
        encode([image((64, 32), 24, 3)], block=(2, 2), codebook_size=16, color="rgb", index_bits=16, seed=5),
    ])


#: name -> (texture set, what the specialised unit (hw.features) must be): the configurations of the issue (rgb-only
#: 8-bit, intensity, yuv411, rgba, 12-bit straddling, mixed raw/compressed, no mipmaps, mipmaps).
SPECIALISE_CASES = {
    "rgb8_no_mip": (lambda: texture_set("rgb_4x4_b8_k256"),
                    dict(colors={"rgb"}, widths=(8,), straddle=False, raw=False, matrix=False, sublevels=False)),
    "rgb8_mip": (lambda: texture_set("rgb_4x4_b8_mip"),
                 dict(colors={"rgb"}, widths=(8,), straddle=False, raw=True, matrix=False, sublevels=True)),
    "intensity_b5_w64": (lambda: texture_set("i8_4x2_b5_w64"),
                         dict(colors={"intensity"}, widths=(5,), straddle=True, raw=False, matrix=False)),
    "yuv_dreamcast_b12_mip": (lambda: texture_set("yuv_dreamcast_4x4_b12_mip"),
                              dict(colors={"yuv411"}, widths=(12,), straddle=True, raw=True, matrix=True)),
    "yuv_jfif_b12_mip": (lambda: texture_set("yuv_4x4_b12_mip"),
                         dict(colors={"yuv411"}, widths=(12,), straddle=True, raw=True, matrix=True)),
    "rgba_b7_mip_w16": (lambda: texture_set("rgba_2x2_b7_mip_w16"),
                        dict(colors={"rgba"}, widths=(7,), straddle=True, raw=True, matrix=False)),
    "rgb12_w16": (lambda: texture_set("rgb_4x4_b12_w16"),
                  dict(colors={"rgb"}, widths=(12,), straddle=True, raw=False, matrix=False)),
    "raw_only": (lambda: texture_set("raw_only_8x8_mip"),
                 dict(colors=set(), widths=(), straddle=False, raw=True, matrix=False, compressed=False)),
    "three_widths": (three_widths, dict(colors={"rgb", "intensity", "rgba"}, widths=(6, 8, 12), straddle=True,
                                        raw=True, matrix=False)),
    "two_widths_no_straddle": (two_widths_no_straddle, dict(colors={"rgb"}, widths=(8, 16), straddle=False,
                                                            raw=False, matrix=False)),
    "combined": (combined_set, dict(colors={"rgb", "rgba", "intensity", "yuv411"}, widths=(5, 7, 8, 12),
                                            straddle=True, raw=True, matrix=True)),
}
