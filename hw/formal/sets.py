"""The small texture sets the proofs are done on, encoded in code (deterministic, in milliseconds).

A proof is about the hardware built for one set (the ROMs hold its memories, the specialised unit
holds what it needs), and the solver's work grows with the memories, so the sets are as small as
the paths they must exercise allow:

* :func:`yuv_set`: one 8x8 yuv411 texture, 2x2 blocks, 4 codewords, 12-bit indices in 32-bit words
  (indices straddle words: both banks and the word pair), mipmapped with the levels below 4x4 raw
  (sub-levels of extended codewords, the raw path): the colour matrix, the straddle, the raw
  memory and the plane offsets all in one set;
* :func:`rgb_set`: two 8x8 rgb textures sharing a codebook of 4 codewords, 4x2 blocks, 8-bit indices
  (no straddle, no colour matrix, no raw level): the specialised unit at its smallest;
* :func:`pvr2_set`: two PowerVR2 textures (:func:`golden.pvr2.pvr_encode.encode_pvr2`), an 8x8
  argb1555 and a 16x8 yuv422, 4 codewords each: twiddled index maps (a non-square block grid: the
  twiddled squares follow one another), 16-bit texel expansion, the yuv422 pair select and the
  Dreamcast colour matrix; its full unit is the PowerVR2 unit (both layouts, all eight formats).
"""

from __future__ import annotations

import functools

import numpy as np

from vqtex.golden.encode import encode
from vqtex.golden.format import TextureSet

__all__ = ["yuv_set", "rgb_set", "pvr2_set", "noise"]


def noise(width: int, height: int, channels: int, seed: int) -> np.ndarray:
    """A (height, width, channels) uint8 image of seeded uniform noise."""
    return np.random.default_rng(seed).integers(0, 256, (height, width, channels), dtype=np.uint8)


@functools.lru_cache(maxsize=None)
def yuv_set() -> TextureSet:
    return encode([noise(8, 8, 3, 1)], block=(2, 2), codebook_size=4, color="yuv411", index_bits=12,
                  mipmaps=True, raw_below=4, seed=0)


@functools.lru_cache(maxsize=None)
def rgb_set() -> TextureSet:
    return encode([noise(8, 8, 3, 2), noise(8, 8, 3, 3)], block=(4, 2), codebook_size=4, color="rgb",
                  index_bits=8, seed=0)


@functools.lru_cache(maxsize=None)
def pvr2_set() -> TextureSet:
    from vqtex.golden.pvr2.pvr_encode import encode_pvr2
    return TextureSet.combine([encode_pvr2(noise(8, 8, 4, 4), "argb1555", codebook_size=4, seed=0)[0],
                               encode_pvr2(noise(16, 8, 3, 5), "yuv422", codebook_size=4, seed=0)[0]])
