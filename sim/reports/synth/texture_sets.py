"""The built-in texture sets of ``vqtex report area --builtin NAME`` (``four``, ``pvr2``, ``rgb8``,
``tiny``, ``topspin``, ``town``; the command's list is ``sim.cli.report.BUILTINS``), encoded from the
bundled images or in code, deterministic for a seed."""

from __future__ import annotations

import os

__all__ = ["bundled_image", "four_texture_set", "pvr2_texture_set", "rgb8_texture_set", "tiny_texture_set",
           "scene_texture_set", "topspin_texture_set", "town_texture_set"]


def bundled_image(name: str, size: int):
    """The bundled ``name``.png (golden/data) box-filtered to ``size`` x ``size`` (a square image
    whose side is a multiple of ``size``)."""
    import numpy as np

    from vqtex.golden.render.imageio import read_image
    from vqtex.golden.render.scene import DATA_DIR

    a = read_image(os.path.join(DATA_DIR, name + ".png"))
    h, w = a.shape[:2]
    if (h, w) != (size, size):
        if h % size or w % size or h != w:
            raise ValueError(f"{name}.png is {w}x{h}: cannot box-filter it to {size}x{size}")
        f = h // size
        a = a.reshape(size, f, size, f, -1).mean(axis=(1, 3)).round().astype(np.uint8)
    return a

def four_texture_set(size: int = 128, seed: int = 0):
    """The issue's benchmark set: four mipmapped ``size`` x ``size`` textures from the bundled images.

    ====  ==========  =====  ======  ========  =========================
    id    image       color  block   K         index bits
    ====  ==========  =====  ======  ========  =========================
    0     brick_red   rgb    4x4     256       8 (shares a codebook with 1)
    1     road        rgb    4x4     256       8
    2     chelsea     yuv411 4x4     256       12
    3     hubble      rgb    2x2     1024      12
    ====  ==========  =====  ======  ========  =========================

    combined (:meth:`golden.format.TextureSet.combine`) into one set: three codebooks, 1536 entries
    of 63 bytes, about 2.5k index words, raw words for the levels below 32x32. Deterministic (GLA
    with ``seed``); takes a few seconds.
    """
    from vqtex.golden.encode import encode
    from vqtex.golden.format import TextureSet

    def img(name):
        return bundled_image(name, size)

    rgb8 = encode([img("brick_red"), img("road")], block=(4, 4), codebook_size=256, color="rgb",
                  index_bits=8, mipmaps=True, seed=seed, names=["brick_red", "road"])
    yuv12 = encode([img("chelsea")], block=(4, 4), codebook_size=256, color="yuv411", index_bits=12,
                   mipmaps=True, seed=seed, names=["chelsea"])
    rgb2x2 = encode([img("hubble")], block=(2, 2), codebook_size=1024, color="rgb", index_bits=12,
                    mipmaps=True, seed=seed, names=["hubble"])
    return TextureSet.combine([rgb8, yuv12, rgb2x2])


def pvr2_texture_set(size: int = 128, seed: int = 0):
    """A Dreamcast PowerVR2 unit's set: four mipmapped ``size`` x ``size`` textures of the bundled
    images encoded by :func:`golden.pvr2.pvr_encode.encode_pvr2`, one per PowerVR2 colour format, each with
    its 256-entry codebook of 2x2 16-bit texels: brick_red rgb565, road argb1555, chelsea yuv422,
    hubble argb4444 (1024 codebook entries of 8 bytes, twiddled 8-bit index maps per level)."""
    from vqtex.golden.format import TextureSet
    from vqtex.golden.pvr2.pvr_encode import encode_pvr2

    sets = []
    for name, color in (("brick_red", "rgb565"), ("road", "argb1555"), ("chelsea", "yuv422"), ("hubble", "argb4444")):
        a = bundled_image(name, size)
        sets.append(encode_pvr2(a, color, codebook_size=256, mipmaps=True, seed=seed, name=name)[0])
    return TextureSet.combine(sets)


def rgb8_texture_set(size: int = 128, seed: int = 0):
    """An rgb-only set with 8-bit indices: textures 0 and 1 of :func:`four_texture_set` (brick_red and
    road, ``size`` x ``size``, mipmapped, rgb 4x4, one shared codebook of K=256), alone. What the
    specialised unit of such a set drops: the colour matrix, every multiplier, the odd index bank."""
    return _bundled_encode(["brick_red", "road"], size, block=(4, 4), codebook_size=256, color="rgb",
                           index_bits=8, mipmaps=True, seed=seed)


def _bundled_encode(names, size, **kw):
    from vqtex.golden.encode import encode
    return encode([bundled_image(name, size) for name in names], names=names, **kw)


def tiny_texture_set(seed: int = 0):
    """The small set (``--builtin tiny``; the tests' synthesis run): two mipmapped 32x32 textures
    (rgb 4x4 K=16 8-bit indices, yuv411 4x4 K=16 12-bit indices), generated in code."""
    import numpy as np

    from vqtex.golden.encode import encode
    from vqtex.golden.format import TextureSet
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:32, 0:32]
    a = np.stack([x * 8, y * 8, (x ^ y) * 8], axis=-1).astype(np.uint8)
    b = np.clip(a.astype(int) + rng.integers(-20, 20, a.shape), 0, 255).astype(np.uint8)
    s1 = encode([a], block=(4, 4), codebook_size=16, color="rgb", index_bits=8, mipmaps=True, seed=seed)
    s2 = encode([b], block=(4, 4), codebook_size=16, color="yuv411", index_bits=12, mipmaps=True, seed=seed)
    return TextureSet.combine([s1, s2])


def scene_texture_set(name: str):
    """A built-in scene's texture set (``topspin``, ``town``), encoded with the scene's settings
    (what ``vqtex render NAME`` encodes; 10-30 s)."""
    from vqtex.golden.render.scene import build_texture_set, load_scene
    return build_texture_set(load_scene(name))


def topspin_texture_set():
    """The ``topspin`` scene's set: wood (rgb 4x4), marble (yuv411 4x4), top (rgb 2x2), K=256,
    8-bit indices, mipmapped."""
    return scene_texture_set("topspin")


def town_texture_set():
    """The ``town`` scene's set: 22 textures in five groups (rgb 8- and 12-bit, intensity, rgba
    2x2), mipmapped."""
    return scene_texture_set("town")
