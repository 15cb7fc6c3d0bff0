"""The Sega Dreamcast's PowerVR2 VQ textures (docs/pvr2.md), in three modules callers import by name:

- :mod:`.pvr`: pvrtex's ``.dt`` files read and decoded (header, codebook of 2x2 blocks of 16-bit
  texels, twiddled index maps, mip chains, the YUV422 pairing);
- :mod:`.pvr_set`: a ``.dt`` as a texture of a :class:`vqtex.golden.format.TextureSet` in the
  PowerVR2 layout, and back to a ``.dt``;
- :mod:`.pvr_encode`: our encoder of PowerVR2 textures (``vqtex encode --layout pvr2``).

Nothing is re-exported here: ``from vqtex.golden.pvr2 import pvr`` or
``from vqtex.golden.pvr2.pvr_encode import encode_pvr2``.
"""
