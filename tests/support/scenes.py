"""Small scenes for tests (not a test module): tiny scene files with the paper scenes' texture
groups (the paper's tables and the hardware sweep run on them, at a size the suite can afford), the
scene text the render, demo and skip commands' tests render (``TINY_SCENE``), the one the need
analysis is checked on (``NEED_SCENE``), the built-in scenes shrunk for pruning (``small_scene``) and a
scene of pvrtex's .dt textures (``crates_scene``)."""

from __future__ import annotations

import shutil
from pathlib import Path

from vqtex.golden.render.scene import builtin_scene_path, parse_scene

from .tools import PVRTEX_DATA

__all__ = ["tiny_scene", "TINY_TOWN", "TINY_TOPSPIN", "TINY_SCENE", "NEED_SCENE", "PRUNE_SCENES", "small_scene",
           "crates_scene", "CRATE_YUV_MIP", "CRATE_ARGB"]

#: (group, colour, generator, (width, height)) per texture: the town's five groups, topspin's three.
TINY_TOWN = [("signs", "rgb", "checker", (64, 64)), ("roads", "rgb", "noise", (64, 64)),
             ("other", "rgb", "bricks", (64, 64)), ("grey", "intensity", "marble", (64, 64)),
             ("cutouts", "rgba", "cutout", (64, 64))]
TINY_TOPSPIN = [("floor", "rgb", "wood", (64, 64)), ("marble", "rgb", "marble", (64, 64)),
                ("top", "rgb", "stripes", (64, 32))]


def tiny_scene(folder, name: str, textures) -> str:
    """Write ``folder/name.toml``: three 96x64 frames, one texture per entry of ``textures``, each
    on a tilted quad facing the camera. Returns the path."""
    text = f"[scene]\nname = \"{name}\"\nframes = 3\nsize = [96, 64]\n" \
           "[camera]\nposition = [0, 0, 3.5]\ntarget = [0, 0, 0]\n"
    for k, (group, color, gen, size) in enumerate(textures):
        text += (f"[groups.{group}]\ncolor = \"{color}\"\n[[texture]]\nname = \"t{k}\"\ngenerator = \"{gen}\"\n"
                 f"size = {list(size)}\ngroup = \"{group}\"\n[[mesh]]\nshape = \"quad\"\ntexture = \"t{k}\"\n"
                 f"size = [1.6, 1.6]\ntranslate = [{k * 1.0 - 2.0}, {0.4 * (k % 2)}, {-0.3 * k}]\nrotate = [-30, 15, 0]\n")
    path = folder / f"{name}.toml"
    path.write_text(text)
    return str(path)


#: Two 20x16 frames: a 12-bit yuv411 floor (straddling indices, mipmaps) and a 5-bit rgb box.
TINY_SCENE = """
[scene]
name = "tiny"
frames = 2
size = [20, 16]
background = [0, 0, 0]

[camera]
position = [0.0, 1.2, 2.2]
target = [0.0, 0.0, 0.0]
fov = 50

[camera.orbit]
center = [0.0, 0.0, 0.0]
degrees = 90

[groups.a]
block = "4x4"
codebook_size = 16
color = "yuv411"
index_bits = 12
mipmaps = true

[groups.b]
block = "2x2"
codebook_size = 8
color = "rgb"
index_bits = 5
mipmaps = false

[[texture]]
name = "wood"
generator = "wood"
size = [64, 64]
group = "a"

[[texture]]
name = "check"
generator = "checker"
size = [32, 32]
group = "b"
address = "clamp"

[[mesh]]
name = "floor"
shape = "plane"
texture = "wood"
size = [6.0, 6.0]
tiling = [4.0, 4.0]

[[mesh]]
name = "box"
shape = "box"
texture = "check"
size = [0.8, 0.8, 0.8]
"""

#: Three textures: a 12-bit map (straddling indices) with raw small levels, a yuv411 texture of 2x2
#: blocks, and one no mesh uses (never touched).
NEED_SCENE = """
[scene]
frames = 4
size = [48, 40]
[camera]
position = [0, 1.5, 3]
target = [0, 0.3, 0]
[camera.orbit]
degrees = 90
[groups.a]
block = "4x4"
codebook_size = 16
index_bits = 12
[groups.b]
block = "2x2"
codebook_size = 8
color = "yuv411"
[[texture]]
name = "floor"
generator = "checker"
size = [64, 64]
group = "a"
[[texture]]
name = "unused"
generator = "stripes"
size = [32, 32]
group = "a"
[[texture]]
name = "thing"
generator = "marble"
size = [64, 32]
address = ["wrap", "clamp"]
group = "b"
[[mesh]]
shape = "plane"
texture = "floor"
size = [8, 8]
tiling = [4, 4]
[[mesh]]
shape = "top"
texture = "thing"
segments = 12
spin = { degrees_per_frame = 30 }
"""

#: built-in scene -> (its size line, a small size, the frames pruned for, a frame outside them)
PRUNE_SCENES = {"topspin": ("size = [400, 400]", "size = [72, 72]", [0, 6], 25),
                "town": ("size = [400, 300]", "size = [80, 60]", [0, 30], 59)}


def small_scene(name):
    """The built-in scene ``name`` at the small size of :data:`PRUNE_SCENES` (parsed)."""
    old, new, _, _ = PRUNE_SCENES[name]
    text = builtin_scene_path(name).read_text()
    assert old in text
    return parse_scene(text.replace(old, new), builtin_scene_path(name))


#: pvrtex's generated crate textures: yuv422 with mipmaps, argb1555.
CRATE_YUV_MIP = Path(PVRTEX_DATA) / "generated" / "crate_yuv422_c_m.dt"
CRATE_ARGB = Path(PVRTEX_DATA) / "generated" / "crate_argb1555_c_64.dt"


def crates_scene(folder):
    """A scene of two pvrtex .dt textures (a crate on a floor) written into ``folder``; its path."""
    for p in (CRATE_YUV_MIP, CRATE_ARGB):
        shutil.copy(p, folder / p.name)
    (folder / "crates.toml").write_text(f'''
[scene]
name = "crates"
frames = 1
size = [48, 48]
[camera]
position = [0.0, 1.2, 3.0]
target = [0.0, 0.0, 0.0]
fov = 45
[[texture]]
name = "crate"
file = "{CRATE_YUV_MIP.name}"
[[texture]]
name = "floor"
file = "{CRATE_ARGB.name}"
[[mesh]]
name = "box"
shape = "box"
texture = "crate"
[[mesh]]
name = "floor"
shape = "plane"
texture = "floor"
translate = [0.0, -0.6, 0.0]
''')
    return folder / "crates.toml"
