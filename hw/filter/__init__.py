"""The texture filter in Amaranth: (texture, s, t, level of detail, mode, addressing) in, filtered
RGBA8888 out, its twin :mod:`golden.filter`.

footprint.Footprint (texel slots and weights) -> the sequencer and the texel-fetch lanes
(hw.texel_fetch.TexelFetch, the paper's unit, unchanged) -> blend.Blend (weighted sum and
rounding), wired by texture_filter.TextureFilter. See docs/filter.md.
"""

from .texture_filter import LANES, LATENCY, TextureFilter

__all__ = ["TextureFilter", "LATENCY", "LANES"]
