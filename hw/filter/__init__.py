"""The texture filter in Amaranth: (texture, s, t, level of detail, mode, addressing) in, filtered
RGBA8888 out, its twin :mod:`golden.filter`.

footprint.Footprint (texel slots and weights) -> the sequencer and the texel-fetch lanes
(hw.texel_fetch.TexelFetch, the paper's unit, sharing index_banks.IndexBanks: one index memory
banked by block parity) -> blend.Blend (weighted sum and
rounding), wired by texture_filter.TextureFilter. See docs/filter.md.
"""

from .texture_filter import INDEX_BANKS, LANES, LATENCY, TextureFilter

__all__ = ["TextureFilter", "LATENCY", "LANES", "INDEX_BANKS"]
