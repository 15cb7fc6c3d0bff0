"""The texel-fetch hardware in Amaranth, one file per stage of the paper's pipeline:
descriptor -> address (block address shifter) -> index_reader -> codebook_rom -> color_matrix,
in two halves, front_end.FrontEnd (descriptor, address, index reader, pipeline control) and
back_end.BackEnd (codebook ROM, colour matrix), joined by pipeline.LinkLayout and wired by
texel_fetch.TexelFetch; banked_rom holds the index, codebook and raw memories in 512-word
block RAM banks; features.Features is what a texture set needs of the unit, the one place the
unit is specialised (TexelFetch(ts, specialise=False) is the full unit). See docs/hardware.md."""
