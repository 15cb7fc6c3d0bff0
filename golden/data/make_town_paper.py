"""Development-time tool: write golden/data/town-paper.toml, the town at the paper's texture budget.

    python golden/data/make_town_paper.py

The paper's town scene holds 85 textures in 5 MB: 64 RGB, 14 one-channel (intensity) and 7 RGBA.
This scene has exactly that mix. 19 of its textures are the bundled PNGs of golden/data (the
scikit-image photographs and their derivatives, see LICENSE-textures.md; nothing new is bundled);
the other 66 are generated at run time by golden/render/textures.py (wood, marble, checker, stripes,
bricks, facade, noise, cutout) with their own seeds and parameters. Sizes are chosen so the
uncompressed total is 5,001,216 bytes (5.00 MB; 4.77 MiB): see ``SIZES`` and docs/experiments.md.

The scene is a street 180 units long: a road with crossings and side streets (the "roads" group),
buildings on both sides (the "other" RGB and the "grey" intensity textures), signs and billboards on
their fronts (the "signs" group) and cut-out signs on poles along the kerb (the RGBA "cutouts"); the
camera drives down it in 60 frames, so every texture is seen. Codebook groups follow the paper
(signs and billboards, roads, everything else; one-channel and RGBA textures apart); the encoding
settings written here are defaults that the paper's Table 3 overrides row by row.

The output is deterministic (no randomness outside the seeds written into the file).
"""

from __future__ import annotations

from pathlib import Path

HERE = Path(__file__).resolve().parent
OUT = HERE / "town-paper.toml"

# (name, source, size (w, h)) per group; a source is a bundled file name or (generator, seed, params).
BIG, WIDE, TALL, MID, LOW, NARROW, SMALL = (256, 256), (256, 128), (128, 256), (128, 128), (128, 64), (64, 128), (64, 64)


def _signs():
    files = [("astronaut", "astronaut.png", BIG), ("coffee", "coffee.png", WIDE), ("chelsea", "chelsea.png", MID),
             ("rocket", "rocket.png", NARROW), ("ihc", "ihc.png", MID), ("hubble", "hubble.png", MID),
             ("coins", "coins.png", LOW)]
    gens = []
    sizes = [BIG, BIG, WIDE, WIDE, TALL, MID, MID, MID, MID, MID, LOW, NARROW, SMALL]
    for k, size in enumerate(sizes):
        if k % 3 == 0:
            src = ("stripes", 100 + k, {"bands": 3 + k % 5, "sectors": 2 + 2 * (k % 4)})
        elif k % 3 == 1:
            src = ("checker", 100 + k, {"squares": 2 + 2 * (k % 4)})
        else:
            src = ("cutout_rgb", 100 + k, {})
        gens.append((f"poster{k:02d}", src, size))
    return files + gens


def _roads():
    files = [("road", "road.png", MID), ("crossing", "crossing.png", MID), ("sidewalk", "sidewalk.png", MID)]
    gens = [
        ("asphalt", ("noise", 200, {"cells": 16, "colors": [[40, 40, 44], [110, 110, 116]]}), BIG),
        ("paving", ("bricks", 201, {"rows": 16, "cols": 8, "colors": [[150, 140, 130], [90, 90, 90]]}), WIDE),
        ("cobbles", ("bricks", 202, {"rows": 8, "cols": 8, "colors": [[120, 115, 110], [60, 60, 60]]}), MID),
        ("gravel_path", ("noise", 203, {"cells": 32, "colors": [[120, 105, 85], [200, 185, 160]]}), MID),
        ("kerb", ("noise", 204, {"cells": 8, "colors": [[150, 150, 150], [215, 215, 210]]}), SMALL),
    ]
    return files + gens


def _other():
    files = [("brick_red", "brick_red.png", MID), ("stone", "stone.png", SMALL), ("lawn", "lawn.png", MID)]
    sizes = [BIG] * 4 + [WIDE, TALL, WIDE] + [MID] * 18 + [LOW, NARROW, LOW, NARROW] + [SMALL] * 4
    kinds = ["facade", "bricks", "wood", "marble", "noise", "facade", "bricks"]
    gens = []
    for k, size in enumerate(sizes):
        kind = kinds[k % len(kinds)]
        params = {"facade": {"floors": 3 + k % 4, "windows": 2 + k % 3}, "bricks": {"rows": 8 + 4 * (k % 3)},
                  "wood": {"planks": 2 + k % 5}, "marble": {"veins": 2 + k % 4}, "noise": {"cells": 4 << (k % 3)}}[kind]
        gens.append((f"{kind}{k:02d}", (kind, 300 + k, params), size))
    return files + gens


def _grey():
    files = [("brick_grey", "brick.png", MID), ("gravel", "gravel.png", MID), ("grass", "grass.png", MID),
             ("camera", "camera.png", MID)]
    sizes = [BIG, BIG] + [MID] * 8
    kinds = ["facade", "noise", "bricks", "marble", "wood"]
    gens = [(f"grey_{kinds[k % 5]}{k:02d}", (kinds[k % 5], 400 + k, {}), size) for k, size in enumerate(sizes)]
    return files + gens


def _cutouts():
    files = [("cat_badge", "cat_badge.png", MID), ("arrow", "arrow.png", SMALL)]
    gens = [(f"cutout{k}", ("cutout", 500 + k, {"sides": [0, 3, 4, 6, 8][k], "rings": 2 + k % 3}), MID)
            for k in range(5)]
    return files + gens


#: group -> (encoding defaults, textures)
GROUPS = {
    "signs": ({"block": "4x4", "codebook_size": 256, "color": "rgb"}, _signs()),
    "roads": ({"block": "4x4", "codebook_size": 256, "color": "rgb"}, _roads()),
    "other": ({"block": "4x4", "codebook_size": 256, "color": "rgb"}, _other()),
    "grey": ({"block": "2x2", "codebook_size": 256, "color": "intensity"}, _grey()),
    "cutouts": ({"block": "2x2", "codebook_size": 256, "color": "rgba"}, _cutouts()),
}
BYTES = {"rgb": 3, "intensity": 1, "rgba": 4}


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return f'"{v}"'
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {_toml_value(x)}" for k, x in v.items()) + " }"
    return "[" + ", ".join(_toml_value(x) for x in v) + "]"


def _table(header: str, items: dict) -> str:
    return f"[{header}]\n" + "".join(f"{k} = {_toml_value(v)}\n" for k, v in items.items()) + "\n"


def _texture(name, src, size, group) -> str:
    t = {"name": name}
    if isinstance(src, str):
        t["file"] = src
    else:
        gen, seed, params = src
        if gen == "cutout_rgb":   # a poster: a polygon sign on a plain ground (the RGB of cutout)
            gen, params = "cutout", {"sides": 3 + seed % 5, "rings": 3}
        t.update(generator=gen, size=list(size), seed=seed)
        if params:
            t["params"] = params
    t["group"] = group
    if group in ("signs", "cutouts"):
        t["address"] = "clamp"
    return "[[texture]]\n" + "".join(f"{k} = {_toml_value(v)}\n" for k, v in t.items()) + "\n"


def _mesh(**m) -> str:
    return "[[mesh]]\n" + "".join(f"{k} = {_toml_value(v)}\n" for k, v in m.items()) + "\n"


def meshes() -> list[str]:
    """Every texture on at least one mesh: the street, its buildings, signs and poles."""
    out = []
    signs = [n for n, _, _ in GROUPS["signs"][1]]
    roads = [n for n, _, _ in GROUPS["roads"][1]]
    other = [n for n, _, _ in GROUPS["other"][1]]
    grey = [n for n, _, _ in GROUPS["grey"][1]]
    cut = [n for n, _, _ in GROUPS["cutouts"][1]]
    length, z0 = 190.0, -85.0
    out.append(_mesh(name="ground", shape="plane", texture="lawn", size=[300.0, 300.0], tiling=[100.0, 100.0],
                     translate=[0.0, -0.02, z0]))
    out.append(_mesh(name="road", shape="plane", texture="road", size=[8.0, length], tiling=[1.0, 24.0],
                     translate=[0.0, 0.0, z0]))
    for s, x in (("left", -6.0), ("right", 6.0)):
        out.append(_mesh(name=f"sidewalk_{s}", shape="box", texture="sidewalk", size=[4.0, 0.15, length],
                         tiling=[2.0, 95.0], translate=[x, 0.0, z0]))
        out.append(_mesh(name=f"kerb_{s}", shape="box", texture="kerb", size=[0.3, 0.2, length],
                         tiling=[1.0, 190.0], translate=[x * 0.68, 0.0, z0]))
    # crossings and side streets
    for k, (name, z) in enumerate((("crossing", -20.0), ("asphalt", -60.0), ("paving", -100.0),
                                   ("cobbles", -140.0), ("gravel_path", -170.0))):
        w = 4.0 if name == "crossing" else 6.0
        out.append(_mesh(name=f"street{k}", shape="plane", texture=name, size=[60.0, w],
                         tiling=[1.0 if name == "crossing" else 10.0, 1.0], translate=[0.0, 0.01, z]))
    # buildings: "other" RGB and "grey" intensity textures alternate down both sides
    walls = [n for n in other if n != "lawn"] + grey
    walls = [w for pair in zip(walls[:len(walls) // 2], walls[len(walls) // 2:]) for w in pair] + \
        walls[2 * (len(walls) // 2):]
    step = 2 * length / len(walls)
    for k, wall in enumerate(walls):
        side = -1 if k % 2 == 0 else 1
        z = 5.0 - (k // 2) * step
        h = 5.0 + (k * 7) % 11
        out.append(_mesh(name=f"house{k:02d}", shape="box", texture=wall, size=[6.0, float(h), step * 0.9],
                         tiling=[2.0, float(max(1, h // 4))], translate=[side * 12.0, 0.0, round(z, 3)]))
    # signs and billboards on the building fronts (the face at x = +-9)
    for k, sign in enumerate(signs):
        side = -1 if k % 2 == 0 else 1
        z = 2.0 - k * (length - 20) / len(signs)
        w = 4.0 if k % 3 else 6.0
        out.append(_mesh(name=f"sign_{sign}", shape="quad", texture=sign, size=[w, w * 0.75],
                         rotate=[0.0, 90.0 * -side, 0.0], translate=[side * 8.95, 3.0 + k % 3, round(z, 3)]))
    # cut-out signs on poles along the kerb
    for k, c in enumerate(cut):
        side = 1 if k % 2 == 0 else -1
        z = -8.0 - k * 22.0
        out.append(_mesh(name=f"pole{k}", shape="cylinder", texture="gravel", radius=0.07, height=3.0, segments=12,
                         translate=[side * 4.6, 0.15, z]))
        out.append(_mesh(name=f"cutout_{c}", shape="quad", texture=c, size=[1.2, 1.2],
                         translate=[side * 4.6, 2.6, z + 0.1]))
    # a stone bench and a wooden kiosk by the road (the textures left over)
    out.append(_mesh(name="bench", shape="box", texture="stone", size=[2.0, 0.5, 0.6], translate=[-5.0, 0.15, -12.0]))
    return out


def scene_text() -> str:
    head = [
        "# The town at the paper's texture budget: 85 textures, 64 RGB, 14 one-channel, 7 RGBA, 5,001,216",
        "# bytes uncompressed (the paper's town: 85 textures in 5 MB, 14 one-channel, 7 RGBA).",
        "# Written by golden/data/make_town_paper.py: edit that script, not this file.",
        "",
    ]
    parts = ["\n".join(head) + "\n",
             _table("scene", {"name": "town-paper", "frames": 60, "size": [400, 300], "background": [150, 190, 230]}),
             _table("camera", {"position": [0.0, 1.7, 10.0], "target": [0.0, 1.6, -20.0], "fov": 55, "near": 0.1})]
    for f, pos, tgt in ((0, [0.0, 1.7, 10.0], [-1.0, 2.0, -20.0]), (30, [1.2, 1.9, -70.0], [-4.0, 2.6, -100.0]),
                        (59, [-0.8, 2.4, -150.0], [3.0, 2.0, -180.0])):
        parts.append("[[camera.keyframe]]\n" + f"frame = {f}\nposition = {_toml_value(pos)}\n"
                     f"target = {_toml_value(tgt)}\n\n")
    for g, (enc, _) in GROUPS.items():
        parts.append(_table(f"groups.{g}", dict(enc, mipmaps=True)))
    for g, (_, texs) in GROUPS.items():
        parts.append(f"# --- {g} " + "-" * (90 - len(g)) + "\n")
        parts += [_texture(n, src, size, g) for n, src, size in texs]
    parts.append("# " + "=" * 96 + "\n")
    parts += meshes()
    return "".join(parts).rstrip() + "\n"


def totals() -> dict:
    """Texture count and uncompressed bytes per colour format."""
    out = {}
    for enc, texs in GROUPS.values():
        n, b = out.get(enc["color"], (0, 0))
        out[enc["color"]] = (n + len(texs), b + sum(w * h * BYTES[enc["color"]] for _, _, (w, h) in texs))
    return out


def main() -> None:
    OUT.write_text(scene_text())
    t = totals()
    print(f"{OUT.name}: " + ", ".join(f"{c}: {n} textures, {b} bytes" for c, (n, b) in t.items())
          + f"; total {sum(n for n, _ in t.values())} textures, {sum(b for _, b in t.values())} bytes")


if __name__ == "__main__":
    main()
