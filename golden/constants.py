"""The format's constants and its one error: what the memory images and the ``.vqt`` container are
made of (colour codes, size limits, word widths, the descriptor row). :mod:`.format` re-exports all of
it; :mod:`.vqt_header` checks untrusted headers against it.
"""

from __future__ import annotations

import numpy as np

__all__ = ["COLORS", "COLOR_CODES", "MAX_LEVELS", "MAX_SIZE", "WORD_BITS_ALLOWED", "RAW_WORD_BITS", "RAW_BELOW",
           "DESCRIPTOR_FIELDS", "DESCRIPTOR_DTYPE", "FormatError"]

#: Colour formats and their 2-bit codes in the descriptor.
COLORS = ("rgb", "rgba", "intensity", "yuv411")
COLOR_CODES = {name: code for code, name in enumerate(COLORS)}
#: Descriptor rows per texture (levels of a 4096x4096 texture: 13).
MAX_LEVELS = 16
MAX_SIZE = 4096
WORD_BITS_ALLOWED = (16, 32, 64)
RAW_WORD_BITS = 32
#: Below this size (in either direction) a mip level is stored raw.
RAW_BELOW = 32

#: Descriptor row: field name -> meaning. All unsigned integers.
DESCRIPTOR_FIELDS = {
    "valid": "1 if this (texture, level) exists",
    "compressed": "1: index map + codebook; 0: raw texels",
    "base": "compressed: index memory word of the level group's map; raw: raw memory word of texel (0,0)",
    "log2w": "log2 of the level's width",
    "log2h": "log2 of the level's height",
    "log2bw": "log2 of the block width at this level ((block width) >> sub-level)",
    "log2bh": "log2 of the block height at this level",
    "index_bits": "b, 1..16",
    "cb_base": "codebook memory entry of codeword 0 of this texture's codebook",
    "sublevel": "0, 1, 2: which part of the extended codeword this level reads",
    "color": "colour format code (0 rgb, 1 rgba, 2 intensity, 3 yuv411)",
    "texel_off": "byte offset in the entry of this sub-level's texels (the Y plane for yuv411)",
    "u_off": "yuv411: byte offset of the sub-level's U plane (else 0)",
    "v_off": "yuv411: byte offset of the sub-level's V plane (else 0)",
}
DESCRIPTOR_DTYPE = np.dtype([(name, "<u4") for name in DESCRIPTOR_FIELDS])


class FormatError(ValueError):
    """A texture set or ``.vqt`` file is malformed (truncated, corrupted, foreign, inconsistent)."""
