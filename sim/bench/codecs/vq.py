"""VQ's own rows: the project's encoder (:func:`vqtex.golden.encode.encode`, GLA, TSVQ-initialised)
at a few configurations, one texture and one codebook per image, no mipmaps.

``bits_per_texel`` is counted as the paper counts it (:meth:`TextureSet.rates`): the index map plus
the whole codebook (here each image has its own; the paper's scenes share codebooks between
textures, which lowers the codebook's share). ``index_bits_per_texel`` is the index map alone.
Decoding the whole image is :func:`vqtex.golden.fetch.decode` (numpy: index maps unpacked, codewords
tiled). One random texel is :func:`vqtex.golden.fetch.fetch`, the bit-exact model of the hardware's
texel fetch (descriptor, block address, packed index read, codeword read, colour matrix), run on
the whole batch of requests at once and divided by its size.
"""

from __future__ import annotations

import numpy as np

from .measure import best_time, copy_floor, gather_floor, psnr
from .schema import row

__all__ = ["parse_config", "applicable", "encode", "rows", "CONFIGS", "QUICK_CONFIGS"]

#: Default configurations: ``BWxBH/K colour``.
CONFIGS = ("2x2/256 rgb", "2x2/256 yuv411", "4x4/256 rgb", "4x4/1024 rgb", "2x2/4096 rgb")
QUICK_CONFIGS = ("2x2/256 rgb", "4x4/256 rgb")


def parse_config(text: str) -> tuple[tuple[int, int], int, str]:
    """``'4x2/256 yuv411'`` -> ((bw, bh), k, colour)."""
    try:
        shape, color = text.split()
        block, k = shape.split("/")
        bw, bh = (int(v) for v in block.split("x"))
        return (bw, bh), int(k), color
    except ValueError:
        raise ValueError(f"VQ configuration {text!r} is not like '2x2/256 rgb'") from None


def applicable(configs, shape) -> list[str]:
    """The configurations with fewer codewords than an image of ``shape`` has blocks (with as many,
    the codebook could hold every block: the image stored exactly, in more bits than raw)."""
    h, w = shape[:2]
    out = []
    for cfg in configs:
        (bw, bh), k, _ = parse_config(cfg)
        if k < (w // bw) * (h // bh):
            out.append(cfg)
    return out


def encode(image: np.ndarray, config: str, seed: int = 0):
    """A one-texture :class:`TextureSet` of ``image`` (H, W, 3) uint8 at ``config``."""
    from vqtex.golden.encode import encode as vq_encode
    block, k, color = parse_config(config)
    return vq_encode([image], block=block, codebook_size=k, color=color, seed=seed)


def rows(name: str, image: np.ndarray, *, y, x, repeats: int = 3, configs=CONFIGS, seed: int = 0) -> list[dict]:
    """One row per :func:`applicable` configuration."""
    from vqtex.golden.fetch import decode, fetch
    h, w = image.shape[:2]
    zeros = np.zeros(len(y), np.int64)
    out = []
    for cfg in applicable(configs, image.shape):
        (bw, bh), k, color = parse_config(cfg)
        ts, enc_s = best_time(lambda: encode(image, cfg, seed), repeats)
        dec, dec_s = best_time(lambda: decode(ts, 0, 0), repeats)
        _, rnd_s = best_time(lambda: fetch(ts, zeros, zeros, x, y), repeats)
        rgb = np.ascontiguousarray(dec[..., :3])
        index_bits = (w // bw) * (h // bh) * ts.textures[0].index_bits
        out.append(row(method="vq", config=cfg, image=name, bits_per_texel=ts.rates(0)["stored_bits"] / (w * h),
                       psnr_db=psnr(image, dec), encode_s=enc_s, decode_s=dec_s, random_texel_s=rnd_s / len(y),
                       floor_s=copy_floor(rgb, repeats), random_floor_s=gather_floor(rgb, y, x, repeats),
                       random_texel=f"golden fetch (vqtex.golden.fetch.fetch), batch of {len(y)} requests",
                       library=f"vqtex golden encode (gla, seed {seed}) and fetch",
                       index_bits_per_texel=index_bits / (w * h), width=w, height=h))
    return out
