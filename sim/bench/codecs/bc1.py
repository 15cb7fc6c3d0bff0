"""BC1 (DXT1, S3TC): 4x4 texels in 64 bits, 4 bits per texel, the block format every GPU decodes.

A block is two RGB565 endpoints ``c0``, ``c1`` (little-endian 16-bit words) and sixteen 2-bit
selectors, row-major, texel (x, y) at bits ``2x`` of byte ``4 + y``. The palette is ``c0``, ``c1``
expanded to 8 bits (``r8 = r5 << 3 | r5 >> 2``, ``g8 = g6 << 2 | g6 >> 4``) and, when ``c0 > c1``,
``(2 c0 + c1) / 3`` and ``(c0 + 2 c1) / 3``; otherwise ``(c0 + c1) / 2`` and black. Divisions floor,
as texture2ddecoder's decoder does (hardware decoders differ in these roundings by one level; the
tests pin this decoder to texture2ddecoder on every selector of random blocks). Alpha is not kept.

Encoders (PyPI): etcpak (the fast, real-time encoder games use) and quicktex (a port of rgbcx, the
quality encoder, at a chosen level). Decoders: :func:`decode` and :func:`texels` here (numpy,
vectorised: a whole image, or single texels from one 64-bit word each) and texture2ddecoder (C++),
cross-checked in the tests.
"""

from __future__ import annotations

import numpy as np

from .measure import best_time, copy_floor, gather_floor, psnr
from .schema import row

__all__ = ["decode", "texels", "encode", "decode_library", "rows", "ENCODERS", "QUICKTEX_LEVEL"]

#: quicktex's quality level (0..18; rgbcx's level 10 is its default "good" setting).
QUICKTEX_LEVEL = 10
ENCODERS = ("etcpak", "quicktex")


def _check(width: int, height: int, data) -> np.ndarray:
    if width % 4 or height % 4:
        raise ValueError(f"BC1 needs sides that are multiples of 4, not {width}x{height}")
    words = np.frombuffer(data, dtype="<u8") if not isinstance(data, np.ndarray) else data.view("<u8").ravel()
    if len(words) != (width // 4) * (height // 4):
        raise ValueError(f"{len(words)} BC1 blocks for a {width}x{height} image")
    return words


def _palette(words: np.ndarray) -> np.ndarray:
    """(..., 4, 3) int32 palettes of the blocks ``words`` (uint64)."""
    c = np.stack([words & 0xFFFF, (words >> 16) & 0xFFFF], -1).astype(np.int32)      # (..., 2)
    r, g, b = (c >> 11) & 31, (c >> 5) & 63, c & 31
    e = np.stack([(r << 3) | (r >> 2), (g << 2) | (g >> 4), (b << 3) | (b >> 2)], -1)  # (..., 2, 3)
    e0, e1 = e[..., 0, :], e[..., 1, :]
    four = (c[..., 0] > c[..., 1])[..., None]
    p2 = np.where(four, (2 * e0 + e1) // 3, (e0 + e1) // 2)
    p3 = np.where(four, (e0 + 2 * e1) // 3, 0)
    return np.stack([e0, e1, p2, p3], -2)


def decode(data, width: int, height: int) -> np.ndarray:
    """BC1 blocks (bytes or uint8 array, row-major blocks) -> (height, width, 3) uint8 (numpy)."""
    words = _check(width, height, data).reshape(height // 4, width // 4)
    pal = _palette(words)                                                  # (by, bx, 4, 3)
    shifts = np.arange(16, dtype=np.uint64) * np.uint64(2) + np.uint64(32)
    sel = ((words[..., None] >> shifts) & np.uint64(3)).astype(np.intp)    # (by, bx, 16), row-major texels
    out = np.take_along_axis(pal, sel[..., None], axis=2)                  # (by, bx, 16, 3)
    out = out.reshape(height // 4, width // 4, 4, 4, 3).transpose(0, 2, 1, 3, 4)
    return out.reshape(height, width, 3).astype(np.uint8)


def texels(data, width: int, height: int, y, x) -> np.ndarray:
    """The texels (y, x) of a BC1 image, (n, 3) uint8, each from its block's one 64-bit word: the
    random-access path (no block is decoded beyond the texel's selector and palette entry)."""
    words = _check(width, height, data)
    y = np.asarray(y, dtype=np.int64)
    x = np.asarray(x, dtype=np.int64)
    w = words[(y >> 2) * (width // 4) + (x >> 2)]
    s = ((w >> (np.uint64(32) + ((y & 3) * 8 + (x & 3) * 2).astype(np.uint64))) & np.uint64(3)).astype(np.intp)
    pal = _palette(w)                                                      # (n, 4, 3)
    return pal[np.arange(len(s)), s].astype(np.uint8)


def _rgba(image: np.ndarray) -> bytes:
    h, w = image.shape[:2]
    return np.concatenate([image[..., :3], np.full((h, w, 1), 255, np.uint8)], axis=2).tobytes()


def encode(image: np.ndarray, encoder: str = "etcpak") -> bytes:
    """(H, W, 3) uint8 -> BC1 blocks, row-major, with ``etcpak`` or ``quicktex`` (level
    :data:`QUICKTEX_LEVEL`)."""
    h, w = image.shape[:2]
    if w % 4 or h % 4:
        raise ValueError(f"BC1 needs sides that are multiples of 4, not {w}x{h}")
    if encoder == "etcpak":
        import etcpak
        return etcpak.compress_bc1(_rgba(image), w, h)
    if encoder == "quicktex":
        from quicktex import RawTexture
        from quicktex.s3tc.bc1 import BC1Encoder
        return BC1Encoder(QUICKTEX_LEVEL).encode(RawTexture.frombytes(_rgba(image), w, h)).tobytes()
    raise ValueError(f"unknown BC1 encoder {encoder!r} (one of {', '.join(ENCODERS)})")


def decode_library(data: bytes, width: int, height: int) -> np.ndarray:
    """texture2ddecoder's BC1 decoder (C++; it writes BGRA) -> (height, width, 3) uint8 RGB."""
    import texture2ddecoder
    bgra = np.frombuffer(texture2ddecoder.decode_bc1(bytes(data), width, height), np.uint8)
    return bgra.reshape(height, width, 4)[..., 2::-1]


def rows(name: str, image: np.ndarray, *, y, x, repeats: int = 3, encoders=ENCODERS) -> list[dict]:
    """One row per encoder: 4 bits per texel; the whole-image decode with texture2ddecoder (C++,
    what a tool would call); one random texel with :func:`texels` (numpy, one 64-bit word and its
    palette per texel, amortised over the batch (y, x))."""
    from importlib.metadata import version
    h, w = image.shape[:2]
    out = []
    for enc in encoders:
        data, enc_s = best_time(lambda: encode(image, enc), repeats)
        dec, dec_s = best_time(lambda: decode_library(data, w, h), repeats)
        _, rnd_s = best_time(lambda: texels(data, w, h, y, x), repeats)
        lib = (f"{enc} {version(enc)}" + (f" level {QUICKTEX_LEVEL}" if enc == "quicktex" else "")
               + f"; decode texture2ddecoder {version('texture2ddecoder')}; texels numpy")
        out.append(row(method="bc1", config=enc, image=name, bits_per_texel=len(data) * 8 / (w * h),
                       psnr_db=psnr(image, dec), encode_s=enc_s, decode_s=dec_s,
                       random_texel_s=rnd_s / len(y), floor_s=copy_floor(dec, repeats),
                       random_floor_s=gather_floor(dec, y, x, repeats),
                       random_texel=f"numpy: the texel's block word, palette and selector; batch of {len(y)}",
                       library=lib, width=w, height=h))
    return out
