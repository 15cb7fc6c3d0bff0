"""The format's constants and its one error: what the memory images and the ``.vqt`` container are
made of (colour codes, size limits, word widths, the descriptor row). :mod:`.format` re-exports all of
it; :mod:`.vqt_header` checks untrusted headers against it.
"""

from __future__ import annotations

import numpy as np

__all__ = ["COLORS", "COLOR_CODES", "PVR2_COLORS", "LAYOUTS", "LAYOUT_CODES", "LEGACY_DESCRIPTOR_FIELDS", "LEGACY_DESCRIPTOR_DTYPE", "MAX_LEVELS", "MAX_SIZE", "WORD_BITS_ALLOWED", "RAW_WORD_BITS", "RAW_BELOW",
           "DESCRIPTOR_FIELDS", "DESCRIPTOR_DTYPE", "FormatError"]

#: Colour formats and their codes in the descriptor: the paper's four (codes 0-3, a 2-bit field), then
#: the Dreamcast PowerVR2 codebook formats (codes 4-7: 16-bit texels, see :mod:`.pvr_set`; a set that
#: holds one has a 3-bit colour field).
COLORS = ("rgb", "rgba", "intensity", "yuv411", "argb1555", "rgb565", "argb4444", "yuv422")
#: The PowerVR2 colour formats (16-bit texels, 2x2 blocks, twiddled index maps).
PVR2_COLORS = ("argb1555", "rgb565", "argb4444", "yuv422")
#: Descriptor ``layout`` codes: the paper's row-major index maps, or PowerVR2 twiddled (Morton) maps.
LAYOUTS = ("paper", "pvr2")
LAYOUT_CODES = {name: code for code, name in enumerate(LAYOUTS)}
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
    "color": "colour format code (0 rgb, 1 rgba, 2 intensity, 3 yuv411, 4 argb1555, 5 rgb565, 6 argb4444, 7 yuv422)",
    "texel_off": "byte offset in the entry of this sub-level's texels (the Y plane for yuv411)",
    "u_off": "yuv411: byte offset of the sub-level's U plane (else 0); yuv422: of the U texel pair's first byte",
    "v_off": "yuv411: byte offset of the sub-level's V plane (else 0); yuv422: of the V texel pair's first byte",
    "layout": "0: the paper's row-major index map; 1: PowerVR2 twiddled (Morton) map, offsets transposed",
}
#: The fields of ``.vqt`` files written before the ``layout`` field existed (read as layout 0).
LEGACY_DESCRIPTOR_FIELDS = tuple(name for name in DESCRIPTOR_FIELDS if name != "layout")
DESCRIPTOR_DTYPE = np.dtype([(name, "<u4") for name in DESCRIPTOR_FIELDS])
LEGACY_DESCRIPTOR_DTYPE = np.dtype([(name, "<u4") for name in LEGACY_DESCRIPTOR_FIELDS])


class FormatError(ValueError):
    """A texture set or ``.vqt`` file is malformed (truncated, corrupted, foreign, inconsistent)."""
