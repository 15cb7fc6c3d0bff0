"""Tiny scene files with the paper scenes' texture groups (not a test module): the paper's tables and
the hardware sweep run on them in the tests, at a size the suite can afford."""

from __future__ import annotations

__all__ = ["tiny_scene", "TINY_TOWN", "TINY_TOPSPIN"]

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
