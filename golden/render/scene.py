"""Scenes in TOML: camera and its animation, meshes, textures and their encoding groups.

The file format (every table and key, defaults, shapes and texture generators) is documented in
docs/rendering.md, section "Scene files"; golden/data/topspin.toml and town.toml are complete
examples.

Texture ids are assigned group by group (groups in order of first appearance, textures in file
order inside a group), so one encode() per group followed by TextureSet.combine gives a texture set
whose texture k is the scene's texture k. PNG files are looked up beside the scene file, then in
golden/data/.

Any problem raises :class:`SceneError` with a one-line message ``FILE: where: problem``.
"""

from __future__ import annotations

import math
import os
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import mesh as meshes
from .camera import Camera, rotate_axis, rotate_xyz, scale as scale_m, translate as translate_m
from .imageio import ImageIOError, image_info, read_image
from .pyramid import ReferenceSource
from .textures import GENERATORS, generate, generator_params

__all__ = [
    "SceneError", "DATA_DIR", "BUILTIN_SCENES", "PAPER_SCENES", "ENCODING_DEFAULTS", "COLORS", "SHAPES",
    "TextureSpec", "MeshSpec", "Scene", "load_scene", "parse_scene", "builtin_scene_path",
    "build_texture_set", "convert_channels",
]

DATA_DIR = Path(__file__).resolve().parent.parent / "data"
BUILTIN_SCENES = ("topspin", "town")
#: Built-in scenes at the paper's texture budgets (docs/experiments.md), for the paper's tables; not
#: in BUILTIN_SCENES, so the demo and the render benchmarks keep to topspin and town.
PAPER_SCENES = ("topspin-paper", "town-paper")
COLORS = ("rgb", "rgba", "intensity", "yuv411")
ENCODING_KEYS = ("block", "codebook_size", "color", "index_bits", "mipmaps", "encoder", "seed")
# a texture may override these (its own "seed" is the generator's; the encoder seed is a group's)
TEXTURE_ENCODING_KEYS = ("block", "codebook_size", "color", "index_bits", "mipmaps", "encoder")
ENCODING_DEFAULTS = {
    "block": "4x4", "codebook_size": 256, "color": "rgb", "index_bits": None, "mipmaps": True,
    "encoder": "gla", "seed": 0,
}
MAX_TEXTURE_SIZE = 4096
#: Bounds on what a scene file may ask for (it is outside data): its size, counts, magnitudes.
MAX_SCENE_BYTES = 1 << 20
MAX_TEXTURES = 1024
MAX_MESHES = 4096
MAX_LIST = 1 << 16
MAX_MAGNITUDE = 1e9
MAX_SEGMENTS = 1024
MAX_GENERATOR_PARAM = 1024


class SceneError(ValueError):
    """A malformed scene file; the message is one line naming the file and the problem."""


# ------------------------------------------------------------------------------------------------
# value checking

class _Ctx:
    """Where we are in the file, for error messages."""

    def __init__(self, file: str):
        self.file = file

    def fail(self, where: str, problem: str):
        raise SceneError(f"{self.file}: {where}: {problem}" if where else f"{self.file}: {problem}")


def _is_num(x) -> bool:
    """A finite number of magnitude at most MAX_MAGNITUDE (TOML has inf and nan literals)."""
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) and abs(x) <= MAX_MAGNITUDE


def _is_int(x) -> bool:
    return isinstance(x, int) and not isinstance(x, bool)


def _tname(x) -> str:
    return {bool: "boolean", int: "integer", float: "float", str: "string", list: "array",
            dict: "table"}.get(type(x), type(x).__name__)


def _check_keys(ctx: _Ctx, where: str, table, allowed) -> None:
    if not isinstance(table, dict):
        ctx.fail(where, f"expected a table, got {_tname(table)}")
    for k in table:
        if k not in allowed:
            ctx.fail(where, f"unknown key '{k}' (allowed: {', '.join(sorted(allowed))})")


def _num(ctx, where, key, x, lo=None, hi=None, lo_open=False):
    if not _is_num(x) or not math.isfinite(x):
        ctx.fail(where, f"'{key}' must be a number, got {_tname(x)} {x!r}")
    if lo is not None and (x <= lo if lo_open else x < lo):
        ctx.fail(where, f"'{key}' must be {'>' if lo_open else '>='} {lo}, got {x}")
    if hi is not None and x > hi:
        ctx.fail(where, f"'{key}' must be <= {hi}, got {x}")
    return float(x)


def _int(ctx, where, key, x, lo=None, hi=None):
    if not _is_int(x):
        ctx.fail(where, f"'{key}' must be an integer, got {_tname(x)} {x!r}")
    if lo is not None and x < lo:
        ctx.fail(where, f"'{key}' must be >= {lo}, got {x}")
    if hi is not None and x > hi:
        ctx.fail(where, f"'{key}' must be <= {hi}, got {x}")
    return int(x)


def _str(ctx, where, key, x, choices=None):
    if not isinstance(x, str):
        ctx.fail(where, f"'{key}' must be a string, got {_tname(x)} {x!r}")
    if choices is not None and x not in choices:
        ctx.fail(where, f"'{key}' must be one of {', '.join(choices)}; got '{x}'")
    return x


def _bool(ctx, where, key, x):
    if not isinstance(x, bool):
        ctx.fail(where, f"'{key}' must be true or false, got {_tname(x)} {x!r}")
    return x


def _vec(ctx, where, key, x, n, integer=False, lo=None):
    if not isinstance(x, list) or len(x) != n or not all((_is_int if integer else _is_num)(v) for v in x):
        kind = "integers" if integer else "numbers"
        ctx.fail(where, f"'{key}' must be an array of {n} {kind}, got {x!r}")
    if lo is not None and any(v < lo for v in x):
        ctx.fail(where, f"'{key}' values must be >= {lo}, got {x!r}")
    return tuple(int(v) if integer else float(v) for v in x)


def _vec_list(ctx, where, key, x, n, integer=False):
    if not isinstance(x, list) or not 1 <= len(x) <= MAX_LIST:
        ctx.fail(where, f"'{key}' must be a non-empty array of at most {MAX_LIST} {n}-element arrays")
    for k, v in enumerate(x):
        _vec(ctx, where, f"{key}[{k}]", v, n, integer)
    return np.array(x, np.int64 if integer else np.float64)


def _pow2(n: int) -> bool:
    return n >= 1 and (n & (n - 1)) == 0


# ------------------------------------------------------------------------------------------------
# shapes: name -> (builder, {parameter: (kind, default)})

_TILING = ("vec2", (1.0, 1.0))
SHAPES = {
    "plane": (meshes.plane, {"size": ("vec2+", (1.0, 1.0)), "tiling": _TILING, "segments": ("ivec2", (1, 1))}),
    "quad": (meshes.quad, {"size": ("vec2+", (1.0, 1.0)), "tiling": _TILING, "segments": ("ivec2", (1, 1))}),
    "box": (meshes.box, {"size": ("vec3+", (1.0, 1.0, 1.0)), "tiling": _TILING}),
    "cylinder": (meshes.cylinder, {"radius": ("num+", 0.5), "height": ("num+", 1.0), "segments": ("int3", 32), "tiling": _TILING}),
    "cone": (meshes.cone, {"radius": ("num+", 0.5), "height": ("num+", 1.0), "segments": ("int3", 32), "tiling": _TILING}),
    "sphere": (meshes.sphere, {"radius": ("num+", 0.5), "segments": ("int3", 32), "rings": ("int3", 16), "tiling": _TILING}),
    "top": (meshes.top, {"radius": ("num+", 0.5), "height": ("num+", 1.0), "segments": ("int3", 48), "tiling": _TILING}),
    "revolve": (meshes.revolve, {"profile": ("vec2list", None), "segments": ("int3", 32), "tiling": _TILING}),
    "triangles": (meshes.triangles, {"vertices": ("vec3list", None), "texcoords": ("vec2list", None), "indices": ("ivec3list", None)}),
}


def _shape_param(ctx, where, key, kind, x):
    if kind == "vec2":
        return _vec(ctx, where, key, x, 2)
    if kind == "vec2+":
        v = _vec(ctx, where, key, x, 2)
        if min(v) <= 0:
            ctx.fail(where, f"'{key}' must be positive, got {x!r}")
        return v
    if kind == "vec3+":
        v = _vec(ctx, where, key, x, 3)
        if min(v) <= 0:
            ctx.fail(where, f"'{key}' must be positive, got {x!r}")
        return v
    if kind == "ivec2":
        v = _vec(ctx, where, key, x, 2, integer=True, lo=1)
        if max(v) > MAX_SEGMENTS:
            ctx.fail(where, f"'{key}' values must be <= {MAX_SEGMENTS}, got {x!r}")
        return v
    if kind == "num+":
        return _num(ctx, where, key, x, lo=0, lo_open=True)
    if kind == "int3":
        return _int(ctx, where, key, x, lo=3, hi=MAX_SEGMENTS)
    if kind == "vec2list":
        return _vec_list(ctx, where, key, x, 2)
    if kind == "vec3list":
        return _vec_list(ctx, where, key, x, 3)
    if kind == "ivec3list":
        return _vec_list(ctx, where, key, x, 3, integer=True)
    raise AssertionError(kind)


# ------------------------------------------------------------------------------------------------
# parsed scene

@dataclass
class TextureSpec:
    """One texture of a scene: where its texels come from and how it is encoded."""

    name: str
    id: int
    file: Path | None
    generator: str | None
    size: tuple[int, int]                # (width, height)
    seed: int
    params: dict
    address: tuple[str, str]             # (s, t): "wrap" | "clamp" | "mirror"
    group: str
    encoding: dict                       # block (bw, bh), codebook_size, color, index_bits, ...

    @property
    def dt(self) -> bool:
        """The texture is a Dreamcast VQ ``.dt`` file: already compressed (PowerVR2 layout), used as is."""
        return self.file is not None and self.file.suffix.lower() == ".dt"

    @property
    def color(self) -> str:
        return self.encoding["color"]


@dataclass
class MeshSpec:
    name: str
    shape: str
    params: dict
    texture: int                          # texture id
    translate: tuple = (0.0, 0.0, 0.0)
    rotate: tuple = (0.0, 0.0, 0.0)
    scale: tuple = (1.0, 1.0, 1.0)
    spin: dict | None = None              # {"axis", "degrees_per_frame", "phase"}
    precess: dict | None = None           # {"tilt", "degrees_per_frame", "phase"}
    _mesh: meshes.Mesh | None = field(default=None, repr=False)

    def geometry(self) -> meshes.Mesh:
        if self._mesh is None:
            self._mesh = SHAPES[self.shape][0](**self.params)
        return self._mesh

    def model_matrix(self, frame: float) -> np.ndarray:
        m = translate_m(self.translate) @ rotate_xyz(self.rotate)
        if self.precess is not None:
            phi = self.precess["phase"] + self.precess["degrees_per_frame"] * frame
            ry = rotate_axis((0, 1, 0), phi)
            m = m @ ry @ rotate_axis((1, 0, 0), self.precess["tilt"]) @ rotate_axis((0, 1, 0), -phi)
        if self.spin is not None:
            m = m @ rotate_axis(self.spin["axis"], self.spin["phase"] + self.spin["degrees_per_frame"] * frame)
        return m @ scale_m(self.scale)


@dataclass
class Scene:
    """A parsed scene. Texture ids are positions in ``textures``."""

    path: Path
    name: str
    frames: int
    width: int
    height: int
    background: tuple
    camera: Camera
    orbit: dict | None
    keyframes: list | None
    textures: list[TextureSpec]
    meshes: list[MeshSpec]
    groups: list[str]                      # group names in texture-id order

    # -- camera ---------------------------------------------------------------------------------
    def camera_at(self, frame: float) -> Camera:
        c = self.camera
        if self.orbit is not None:
            o = self.orbit
            ang = o["start"] + o["degrees"] * frame / self.frames
            r = rotate_axis(o["axis"], ang)[:3, :3]
            center = np.asarray(o["center"])
            pos = center + r @ (np.asarray(c.position) - center)
            tgt = center + r @ (np.asarray(c.target) - center)
            return Camera(tuple(pos), tuple(tgt), c.up, c.fov, c.near)
        if self.keyframes:
            ks = self.keyframes
            if frame <= ks[0]["frame"]:
                k = ks[0]
                return Camera(k["position"], k["target"], c.up, k["fov"], c.near)
            if frame >= ks[-1]["frame"]:
                k = ks[-1]
                return Camera(k["position"], k["target"], c.up, k["fov"], c.near)
            n = next(i for i in range(1, len(ks)) if ks[i]["frame"] >= frame)
            a, b = ks[n - 1], ks[n]
            f = (frame - a["frame"]) / (b["frame"] - a["frame"])
            lerp = lambda p, q: tuple((1 - f) * np.asarray(p) + f * np.asarray(q))  # noqa: E731
            return Camera(lerp(a["position"], b["position"]), lerp(a["target"], b["target"]), c.up,
                          (1 - f) * a["fov"] + f * b["fov"], c.near)
        return c

    # -- geometry -------------------------------------------------------------------------------
    def triangles_at(self, frame: float):
        """Clip-space triangles of a frame: (clip (T, 3, 4), st (T, 3, 2), tex (T,)), mesh order."""
        vp = self.camera_at(frame).view_projection(self.width, self.height)
        clips, sts, texs = [], [], []
        for m in self.meshes:
            g = m.geometry()
            if not len(g.triangles):
                continue
            mvp = vp @ m.model_matrix(frame)
            p = np.concatenate([g.positions, np.ones((len(g.positions), 1))], 1) @ mvp.T
            clips.append(p[g.triangles])
            sts.append(g.texcoords[g.triangles])
            texs.append(np.full(len(g.triangles), m.texture, np.int64))
        if not clips:
            return np.zeros((0, 3, 4)), np.zeros((0, 3, 2)), np.zeros(0, np.int64)
        return np.concatenate(clips), np.concatenate(sts), np.concatenate(texs)

    # -- textures -------------------------------------------------------------------------------
    @property
    def texture_ids(self) -> dict[str, int]:
        return {t.name: t.id for t in self.textures}

    @property
    def addressing(self) -> list[tuple[str, str]]:
        return [t.address for t in self.textures]

    def load_texture(self, spec: TextureSpec) -> np.ndarray:
        """The uint8 image (H, W, C) of one texture as its encoding holds it (C = 1, 3 or 4)."""
        if spec.generator is not None:
            try:
                img = generate(spec.generator, spec.size, spec.seed, **spec.params)
            except (TypeError, ValueError) as e:
                raise SceneError(f"{self.path}: texture '{spec.name}': generator failed: {e}") from None
        elif spec.dt:                    # the .dt's own level 0 is its uncompressed reference
            from ..pvr2.pvr import PvrError, read_dt
            try:
                return read_dt(spec.file).levels[0]
            except PvrError as e:
                raise SceneError(f"{self.path}: texture '{spec.name}': {e}") from None
        else:
            try:
                img = read_image(spec.file)
            except ImageIOError as e:
                raise SceneError(f"{self.path}: texture '{spec.name}': {e}") from None
            h, w = img.shape[:2]
            if (w, h) != tuple(spec.size):
                raise SceneError(f"{self.path}: texture '{spec.name}': {spec.file.name} is {w}x{h}, "
                                 f"expected {spec.size[0]}x{spec.size[1]}")
        return convert_channels(img, spec.color)

    def load_textures(self) -> list[tuple[np.ndarray, TextureSpec]]:
        """(image, settings) of every texture, in texture-id order."""
        return [(self.load_texture(t), t) for t in self.textures]

    def reference_source(self, images=None) -> ReferenceSource:
        """The uncompressed reference TextureSource (pyramids; level 0 only where mipmaps = false)."""
        if images is None:
            images = [img for img, _ in self.load_textures()]
        levels = [None if t.encoding["mipmaps"] else 1 for t in self.textures]
        return ReferenceSource(images, levels=levels)


def convert_channels(img: np.ndarray, color: str) -> np.ndarray:
    """An image as a texture of colour format ``color`` holds it.

    intensity -> (H, W, 1) (RGB becomes luma rint(0.299 R + 0.587 G + 0.114 B)); rgb and yuv411 ->
    (H, W, 3) (grey replicated, alpha dropped); rgba -> (H, W, 4) (missing alpha = 255).
    """
    img = np.asarray(img, np.uint8)
    if img.ndim == 2:
        img = img[:, :, None]
    c = img.shape[2]
    if c == 2:
        img = np.concatenate([img[:, :, :1]] * 3 + [img[:, :, 1:]], 2)
        c = 4
    if color == "intensity":
        if c == 1:
            return img
        y = np.rint(img[:, :, :3].astype(np.float64) @ np.array([0.299, 0.587, 0.114]))
        return np.clip(y, 0, 255).astype(np.uint8)[:, :, None]
    rgb = np.repeat(img, 3, axis=2) if c == 1 else img[:, :, :3]
    if color == "rgba":
        alpha = img[:, :, 3:4] if c == 4 else np.full(img.shape[:2] + (1,), 255, np.uint8)
        return np.ascontiguousarray(np.concatenate([rgb, alpha], 2))
    return np.ascontiguousarray(rgb)


# ------------------------------------------------------------------------------------------------
# parsing

def _encoding(ctx, where, table, base: dict) -> dict:
    enc = dict(base)
    for k in ENCODING_KEYS:
        if k not in table:
            continue
        x = table[k]
        if k == "block":
            s = _str(ctx, where, k, x)
            parts = s.lower().split("x")
            if len(parts) != 2 or not all(p.isdigit() for p in parts) or not all(_pow2(int(p)) for p in parts):
                ctx.fail(where, f"'block' must look like \"4x4\" with power-of-two sides, got '{s}'")
            enc[k] = s.lower()
        elif k == "codebook_size":
            enc[k] = _int(ctx, where, k, x, 2, 4096)
        elif k == "color":
            enc[k] = _str(ctx, where, k, x, COLORS)
        elif k == "index_bits":
            enc[k] = _int(ctx, where, k, x, 1, 16)
        elif k == "mipmaps":
            enc[k] = _bool(ctx, where, k, x)
        elif k == "encoder":
            enc[k] = _str(ctx, where, k, x, _known_encoders())
        elif k == "seed":
            enc[k] = _int(ctx, where, k, x, 0)
    return enc


def _known_encoders() -> tuple[str, ...] | None:
    try:
        from ..encode import ENCODERS  # lazily: the encoder may be absent
        return tuple(ENCODERS)
    except Exception:  # noqa: BLE001
        return None


def _find_file(ctx, where, name: str, scene_dir: Path) -> Path:
    for folder in (scene_dir, DATA_DIR):
        p = (folder / name)
        if p.is_file():
            return p
    ctx.fail(where, f"missing texture file '{name}' (looked in {scene_dir} and {DATA_DIR})")


def parse_scene(text: str, path: str | os.PathLike = "<scene>") -> Scene:
    """Parse scene TOML text; ``path`` names the file in messages and anchors relative files."""
    path = Path(path)
    ctx = _Ctx(str(path))
    if len(text) > MAX_SCENE_BYTES:
        ctx.fail("", f"{len(text)} characters; a scene file has at most {MAX_SCENE_BYTES}")
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        ctx.fail("", f"TOML syntax error: {str(e).splitlines()[0]}")
    except RecursionError:
        ctx.fail("", "TOML nests too deeply")
    _check_keys(ctx, "top level", doc, {"scene", "camera", "groups", "texture", "mesh"})
    scene_dir = path.resolve().parent

    # [scene]
    sc = doc.get("scene", {})
    _check_keys(ctx, "[scene]", sc, {"name", "frames", "size", "background"})
    name = _str(ctx, "[scene]", "name", sc.get("name", path.stem))
    frames = _int(ctx, "[scene]", "frames", sc.get("frames", 1), 1, 1_000_000)
    if "size" not in sc:
        ctx.fail("[scene]", "missing key 'size' ([width, height])")
    width, height = _vec(ctx, "[scene]", "size", sc["size"], 2, integer=True, lo=1)
    if width > 8192 or height > 8192:
        ctx.fail("[scene]", f"'size' {width}x{height} is too large (at most 8192x8192)")
    bg = sc.get("background", [0, 0, 0])
    if not isinstance(bg, list) or len(bg) not in (3, 4) or not all(_is_int(c) and 0 <= c <= 255 for c in bg):
        ctx.fail("[scene]", f"'background' must be 3 or 4 integers 0..255, got {bg!r}")
    background = tuple(bg) + ((255,) if len(bg) == 3 else ())

    # [camera]
    if "camera" not in doc:
        ctx.fail("", "missing [camera] table")
    cam = doc["camera"]
    where = "[camera]"
    _check_keys(ctx, where, cam, {"position", "target", "up", "fov", "near", "orbit", "keyframe"})
    for k in ("position", "target"):
        if k not in cam:
            ctx.fail(where, f"missing key '{k}'")
    position = _vec(ctx, where, "position", cam["position"], 3)
    target = _vec(ctx, where, "target", cam["target"], 3)
    up = _vec(ctx, where, "up", cam.get("up", [0, 1, 0]), 3)
    fov = _num(ctx, where, "fov", cam.get("fov", 45.0), 0, 179, lo_open=True)
    near = _num(ctx, where, "near", cam.get("near", 0.1), 0, lo_open=True)
    try:
        camera = Camera(position, target, up, fov, near)
        camera.view()
    except ValueError as e:
        ctx.fail(where, str(e))
    orbit = keyframes = None
    if "orbit" in cam and "keyframe" in cam:
        ctx.fail(where, "give either 'orbit' or 'keyframe', not both")
    if "orbit" in cam:
        w = "[camera.orbit]"
        o = cam["orbit"]
        _check_keys(ctx, w, o, {"center", "axis", "degrees", "start"})
        orbit = {
            "center": _vec(ctx, w, "center", o.get("center", list(target)), 3),
            "axis": _vec(ctx, w, "axis", o.get("axis", list(up)), 3),
            "degrees": _num(ctx, w, "degrees", o.get("degrees", 360.0)),
            "start": _num(ctx, w, "start", o.get("start", 0.0)),
        }
        if not any(orbit["axis"]):
            ctx.fail(w, "'axis' must not be zero")
    if "keyframe" in cam:
        ks = cam["keyframe"]
        if not isinstance(ks, list) or not ks:
            ctx.fail(where, "'keyframe' must be an array of tables ([[camera.keyframe]])")
        keyframes = []
        for n, k in enumerate(ks):
            w = f"[[camera.keyframe]] #{n + 1}"
            _check_keys(ctx, w, k, {"frame", "position", "target", "fov"})
            if "frame" not in k or "position" not in k:
                ctx.fail(w, "needs 'frame' and 'position'")
            kf = {
                "frame": _int(ctx, w, "frame", k["frame"], 0),
                "position": _vec(ctx, w, "position", k["position"], 3),
                "target": _vec(ctx, w, "target", k.get("target", list(target)), 3),
                "fov": _num(ctx, w, "fov", k.get("fov", fov), 0, 179, lo_open=True),
            }
            if keyframes and kf["frame"] <= keyframes[-1]["frame"]:
                ctx.fail(w, "keyframes must have increasing 'frame' numbers")
            keyframes.append(kf)

    # [groups.NAME]
    groups_tab = doc.get("groups", {})
    if not isinstance(groups_tab, dict):
        ctx.fail("[groups]", "expected a table of groups ([groups.NAME])")
    group_enc = {}
    for g, tab in groups_tab.items():
        w = f"[groups.{g}]"
        _check_keys(ctx, w, tab, set(ENCODING_KEYS))
        group_enc[g] = _encoding(ctx, w, tab, ENCODING_DEFAULTS)

    # [[texture]]
    texs = doc.get("texture", [])
    if not isinstance(texs, list) or not texs:
        ctx.fail("", "no textures: add [[texture]] tables")
    if len(texs) > MAX_TEXTURES:
        ctx.fail("", f"{len(texs)} textures; at most {MAX_TEXTURES}")
    specs = []
    seen = set()
    for n, t in enumerate(texs):
        tname = t.get("name") if isinstance(t, dict) else None
        w = f"[[texture]] #{n + 1}" + (f" '{tname}'" if isinstance(tname, str) else "")
        _check_keys(ctx, w, t, {"name", "file", "generator", "size", "seed", "params", "address", "group",
                                *TEXTURE_ENCODING_KEYS})
        if "name" not in t:
            ctx.fail(w, "missing key 'name'")
        tname = _str(ctx, w, "name", t["name"])
        if tname in seen:
            ctx.fail(w, f"duplicate texture name '{tname}'")
        seen.add(tname)
        if ("file" in t) == ("generator" in t):
            ctx.fail(w, "give exactly one of 'file' or 'generator'")
        seed = _int(ctx, w, "seed", t.get("seed", 0), 0)
        params = t.get("params", {})
        if not isinstance(params, dict):
            ctx.fail(w, f"'params' must be a table, got {_tname(params)}")
        size = _vec(ctx, w, "size", t["size"], 2, integer=True, lo=1) if "size" in t else None
        file = gen = dt_header = None
        if "generator" in t:
            gen = _str(ctx, w, "generator", t["generator"], tuple(sorted(GENERATORS)))
            if size is None:
                ctx.fail(w, "a generated texture needs 'size' ([width, height])")
            for k, v in params.items():
                _num(ctx, w, f"params.{k}", v, -MAX_GENERATOR_PARAM, MAX_GENERATOR_PARAM) if not isinstance(v, list) \
                    else _vec_list(ctx, w, f"params.{k}", v, 3, integer=True)
            bad = set(params) - generator_params(gen)
            if bad:
                ctx.fail(w, f"unknown parameter '{sorted(bad)[0]}' for generator '{gen}' "
                            f"(known: {', '.join(sorted(generator_params(gen))) or 'none'})")
        else:
            if params:
                ctx.fail(w, "'params' only applies to generated textures")
            file = _find_file(ctx, w, _str(ctx, w, "file", t["file"]), scene_dir)
            if file.suffix.lower() == ".dt":      # a Dreamcast VQ texture, used as it is compressed
                from ..pvr2.pvr import PvrError, read_dt
                try:
                    dt_header = read_dt(file, decode=False).header
                except PvrError as e:
                    ctx.fail(w, str(e))
                fw, fh = dt_header.width, dt_header.height
                bad = sorted(set(t) & set(TEXTURE_ENCODING_KEYS))
                if bad:
                    ctx.fail(w, f"'{bad[0]}' does not apply to a .dt texture (it is already compressed)")
            else:
                try:
                    fw, fh, _ = image_info(file)
                except ImageIOError as e:
                    ctx.fail(w, str(e))
            if size is not None and size != (fw, fh):
                ctx.fail(w, f"'size' {size[0]}x{size[1]} does not match {file.name} ({fw}x{fh})")
            size = (fw, fh)
        if not (_pow2(size[0]) and _pow2(size[1])):
            ctx.fail(w, f"size {size[0]}x{size[1]} is not a power of two")
        if max(size) > MAX_TEXTURE_SIZE:
            ctx.fail(w, f"size {size[0]}x{size[1]} exceeds {MAX_TEXTURE_SIZE}")
        addr = t.get("address", "wrap")
        if isinstance(addr, str):
            addr = [addr, addr]
        if not (isinstance(addr, list) and len(addr) == 2 and all(a in ("wrap", "clamp", "mirror") for a in addr)):
            ctx.fail(w, f"'address' must be \"wrap\", \"clamp\", \"mirror\" or a pair of them, got {t.get('address')!r}")
        group = _str(ctx, w, "group", t.get("group", tname))
        enc = _encoding(ctx, w, {k: v for k, v in t.items() if k in TEXTURE_ENCODING_KEYS},
                        group_enc.get(group, ENCODING_DEFAULTS))
        if file is not None and dt_header is not None:
            if group != tname:
                ctx.fail(w, "a .dt texture has its own codebook: it cannot join group "
                            f"'{group}'")
            enc = dict(enc, color="rgba", mipmaps=dt_header.mipmapped)    # decoded texels; the file's levels
        specs.append(TextureSpec(tname, -1, file, gen, tuple(size), seed, dict(params), tuple(addr), group, enc))

    # groups: consistent settings, ids group by group
    order = []
    for s in specs:
        if s.group not in order:
            order.append(s.group)
    for g in order:
        members = [s for s in specs if s.group == g]
        for s in members[1:]:
            for k in ENCODING_KEYS:
                if s.encoding[k] != members[0].encoding[k]:
                    ctx.fail(f"[[texture]] '{s.name}'", f"group '{g}' shares one codebook but '{k}' differs "
                                                        f"from texture '{members[0].name}' "
                                                        f"({s.encoding[k]!r} vs {members[0].encoding[k]!r})")
    specs = [s for g in order for s in specs if s.group == g]
    for k, s in enumerate(specs):
        s.id = k
    by_name = {s.name: s.id for s in specs}

    # [[mesh]]
    ms = doc.get("mesh", [])
    if not isinstance(ms, list) or not ms:
        ctx.fail("", "no meshes: add [[mesh]] tables")
    if len(ms) > MAX_MESHES:
        ctx.fail("", f"{len(ms)} meshes; at most {MAX_MESHES}")
    mesh_specs = []
    for n, m in enumerate(ms):
        mname = m.get("name") if isinstance(m, dict) else None
        w = f"[[mesh]] #{n + 1}" + (f" '{mname}'" if isinstance(mname, str) else "")
        if not isinstance(m, dict):
            ctx.fail(w, "expected a table")
        if "shape" not in m:
            ctx.fail(w, "missing key 'shape'")
        shape = _str(ctx, w, "shape", m["shape"], tuple(SHAPES))
        params_spec = SHAPES[shape][1]
        _check_keys(ctx, w, m, {"name", "shape", "texture", "translate", "rotate", "scale", "spin", "precess",
                                *params_spec})
        mname = _str(ctx, w, "name", m.get("name", f"mesh{n + 1}"))
        if "texture" not in m:
            ctx.fail(w, "missing key 'texture'")
        tex = _str(ctx, w, "texture", m["texture"])
        if tex not in by_name:
            ctx.fail(w, f"missing texture '{tex}' (not defined by any [[texture]])")
        params = {}
        for k, (kind, default) in params_spec.items():
            if k in m:
                params[k] = _shape_param(ctx, w, k, kind, m[k])
            elif default is None:
                ctx.fail(w, f"shape '{shape}' needs '{k}'")
            else:
                params[k] = default
        if shape == "triangles":
            if len(params["texcoords"]) != len(params["vertices"]):
                ctx.fail(w, "'texcoords' needs one (s, t) per vertex")
            if params["indices"].min() < 0 or params["indices"].max() >= len(params["vertices"]):
                ctx.fail(w, "'indices' refer to a vertex that does not exist")
        sc_ = m.get("scale", 1.0)
        scl = (float(_num(ctx, w, "scale", sc_)),) * 3 if _is_num(sc_) else _vec(ctx, w, "scale", sc_, 3)
        spin = precess = None
        if "spin" in m:
            ww = w + " spin"
            _check_keys(ctx, ww, m["spin"], {"axis", "degrees_per_frame", "phase"})
            spin = {"axis": _vec(ctx, ww, "axis", m["spin"].get("axis", [0, 1, 0]), 3),
                    "degrees_per_frame": _num(ctx, ww, "degrees_per_frame", m["spin"].get("degrees_per_frame", 0.0)),
                    "phase": _num(ctx, ww, "phase", m["spin"].get("phase", 0.0))}
            if not any(spin["axis"]):
                ctx.fail(ww, "'axis' must not be zero")
        if "precess" in m:
            ww = w + " precess"
            _check_keys(ctx, ww, m["precess"], {"tilt", "degrees_per_frame", "phase"})
            precess = {"tilt": _num(ctx, ww, "tilt", m["precess"].get("tilt", 0.0)),
                       "degrees_per_frame": _num(ctx, ww, "degrees_per_frame", m["precess"].get("degrees_per_frame", 0.0)),
                       "phase": _num(ctx, ww, "phase", m["precess"].get("phase", 0.0))}
        mesh_specs.append(MeshSpec(
            mname, shape, params, by_name[tex],
            _vec(ctx, w, "translate", m.get("translate", [0, 0, 0]), 3),
            _vec(ctx, w, "rotate", m.get("rotate", [0, 0, 0]), 3),
            scl, spin, precess,
        ))
        try:
            mesh_specs[-1].geometry()
        except ValueError as e:
            ctx.fail(w, str(e))

    return Scene(path, name, frames, width, height, background, camera, orbit, keyframes, specs, mesh_specs,
                 [s.group for s in specs])


def builtin_scene_path(name: str) -> Path:
    """Path of a built-in scene (golden/data/NAME.toml)."""
    return DATA_DIR / f"{name}.toml"


def load_scene(name_or_path: str | os.PathLike) -> Scene:
    """Load a scene by file path or by built-in name ("topspin", "town", "topspin-paper", "town-paper")."""
    p = Path(name_or_path)
    if not p.is_file():
        if str(name_or_path) in BUILTIN_SCENES or builtin_scene_path(str(name_or_path)).is_file():
            p = builtin_scene_path(str(name_or_path))
        else:
            raise SceneError(f"{name_or_path}: no such scene file or built-in scene "
                             f"(built-in: {', '.join(BUILTIN_SCENES + PAPER_SCENES)})")
    try:
        if p.stat().st_size > MAX_SCENE_BYTES:
            raise SceneError(f"{p}: {p.stat().st_size} bytes; a scene file has at most {MAX_SCENE_BYTES}")
        text = p.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise SceneError(f"{p}: cannot read: {e}") from None
    return parse_scene(text, p)


def build_texture_set(scene: Scene, images=None, keep_levels=None, train_texels=None):
    """Encode a scene's textures into one compressed TextureSet; texture k is scene texture k.
    ``keep_levels`` (per scene texture, the level numbers to store; None: all) encodes only those
    (``golden.encode.encode``'s ``keep_levels``; ``golden.need.prune.encode_needed``); ``train_texels``
    (per scene texture, None or (N, 3) level, i, j) trains the codebooks on those texels' blocks only.

    One ``golden.encode.encode`` call per group (its textures share a codebook), then
    ``golden.format.TextureSet.combine`` in group order (texture ids were assigned group by group).
    """
    from ..encode import encode  # lazily: the encoder is another package
    from ..format import TextureSet

    if images is None:
        images = [img for img, _ in scene.load_textures()]
    sets = []
    for g in dict.fromkeys(scene.groups):
        members = [t for t in scene.textures if t.group == g]
        if members[0].dt:                            # already compressed: imported as it is
            from ..pvr2.pvr import PvrError
            from ..pvr2.pvr_set import import_dt
            try:
                sets.append(import_dt([members[0].file]))
            except PvrError as e:
                raise SceneError(f"{scene.path}: texture '{members[0].name}': {e}") from None
            sets[-1].textures[0].name = members[0].name
            continue
        enc = members[0].encoding
        bw, bh = (int(x) for x in enc["block"].split("x"))
        kwargs = dict(block=(bw, bh), codebook_size=enc["codebook_size"], color=enc["color"],
                      index_bits=enc["index_bits"], mipmaps=enc["mipmaps"], encoder=enc["encoder"],
                      seed=enc["seed"], names=[t.name for t in members])
        if keep_levels is not None:
            kwargs["keep_levels"] = [keep_levels[t.id] for t in members]
        if train_texels is not None:
            kwargs["train_texels"] = [train_texels[t.id] for t in members]
        sets.append(encode([images[t.id] for t in members], **kwargs))
    return sets[0] if len(sets) == 1 else TextureSet.combine(sets)
