"""Scene files: the built-in scenes, textures and groups, SceneError messages, build_texture_set."""

import shutil
import sys
import types

import numpy as np
import pytest

from vqtex.golden.render.scene import (
    BUILTIN_SCENES, DATA_DIR, SceneError, build_texture_set, convert_channels, load_scene, parse_scene,
)

BASE = """
[scene]
frames = 3
size = [32, 24]
[camera]
position = [0, 1, 3]
target = [0, 0, 0]
[[texture]]
name = "a"
generator = "checker"
size = [16, 16]
[[mesh]]
shape = "quad"
texture = "a"
"""


def _err(text, name="bad.toml"):
    with pytest.raises(SceneError) as e:
        parse_scene(text, name)
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith(name), msg
    return msg


def test_builtin_scenes_load():
    assert set(BUILTIN_SCENES) >= {"topspin", "town"}
    top = load_scene("topspin")
    assert (top.frames, top.width, top.height) == (50, 400, 400)
    assert len(top.textures) == 3 and {t.generator for t in top.textures} == {"wood", "marble", "stripes"}
    assert len(set(top.groups)) == 3
    town = load_scene("town")
    assert len(town.textures) >= 20
    colors = {t.group: t.color for t in town.textures}
    assert "intensity" in colors.values() and "rgba" in colors.values()
    assert {"signs", "roads", "other"} <= set(colors)
    # texture ids run group by group
    seen = []
    for g in town.groups:
        if not seen or seen[-1] != g:
            assert g not in seen
            seen.append(g)
    assert all(t.id == k for k, t in enumerate(town.textures))
    # by path too
    assert load_scene(DATA_DIR / "town.toml").name == "town"


def test_load_textures_match_their_settings():
    town = load_scene("town")
    for img, spec in town.load_textures():
        assert img.dtype == np.uint8
        assert (img.shape[1], img.shape[0]) == spec.size
        assert img.shape[2] == {"intensity": 1, "rgb": 3, "yuv411": 3, "rgba": 4}[spec.color]
    cams = [town.camera_at(f).position for f in (0, 30, 59)]
    assert np.allclose(cams[1], (1.2, 1.9, -14.0))
    clip, st, tex = town.triangles_at(10)
    assert clip.shape[1:] == (3, 4) and st.shape[1:] == (3, 2) and len(tex) == len(clip)


def test_camera_orbit_and_mesh_spin():
    s = parse_scene(BASE.replace('texture = "a"', 'texture = "a"\nspin = { degrees_per_frame = 90 }'), "x.toml")
    assert s.orbit is None and s.camera_at(2).position == s.camera.position
    m = s.meshes[0].model_matrix(1)
    assert np.allclose(m[:3, :3] @ [1, 0, 0], [0, 0, -1])  # 90 degrees about +y
    text = BASE.replace('target = [0, 0, 0]', 'target = [0, 0, 0]\n[camera.orbit]\ndegrees = 90')
    s = parse_scene(text, "x.toml")
    p0, p1 = np.array(s.camera_at(0).position), np.array(s.camera_at(3).position)
    assert np.allclose(p0, (0, 1, 3)) and np.allclose(p1, (3, 1, 0), atol=1e-12)


def test_convert_channels():
    rgb = np.array([[[255, 0, 0], [0, 0, 255]]], np.uint8)
    assert convert_channels(rgb, "intensity")[..., 0].tolist() == [[76, 29]]
    assert convert_channels(rgb, "rgba")[0, 0].tolist() == [255, 0, 0, 255]
    assert convert_channels(rgb[..., :1], "rgb").shape == (1, 2, 3)
    assert convert_channels(np.zeros((2, 2, 4), np.uint8), "yuv411").shape == (2, 2, 3)


@pytest.mark.parametrize("edit,expect", [
    (lambda t: t.replace('frames = 3', 'frames = 3\ncolour = 1'), "unknown key 'colour'"),
    (lambda t: t.replace('frames = 3', 'frames = "three"'), "'frames' must be an integer"),
    (lambda t: t.replace('size = [32, 24]', 'size = [32]'), "'size' must be an array of 2 integers"),
    (lambda t: t.replace('texture = "a"', 'texture = "nope"'), "missing texture 'nope'"),
    (lambda t: t.replace('size = [16, 16]', 'size = [16, 12]'), "not a power of two"),
    (lambda t: t.replace('generator = "checker"', 'file = "no_such_file.png"'), "missing texture file"),
    (lambda t: t.replace('generator = "checker"', 'generator = "plasma"'), "'generator' must be one of"),
    (lambda t: t.replace('shape = "quad"', 'shape = "teapot"'), "'shape' must be one of"),
    (lambda t: t.replace('shape = "quad"', 'shape = "quad"\nradius = 2'), "unknown key 'radius'"),
    (lambda t: t.replace('[camera]\nposition = [0, 1, 3]\n', '[camera]\n'), "missing key 'position'"),
    (lambda t: t.replace('position = [0, 1, 3]', 'position = [0, 0, 0]'), "camera position equals its target"),
    (lambda t: t + '[[texture]]\nname = "a"\ngenerator = "wood"\nsize = [8, 8]\n', "duplicate texture name 'a'"),
    (lambda t: t.replace('size = [16, 16]', 'size = [16, 16]\naddress = "border"'), "'address' must be"),
    (lambda t: t.replace('size = [16, 16]', 'size = [16, 16]\ncodebook_size = 1'), "'codebook_size' must be >= 2"),
    (lambda t: t.replace('size = [16, 16]', 'size = [16, 16]\nblock = "3x4"'), "'block' must look like"),
    (lambda t: t.replace('size = [16, 16]', 'size = [16, 16]\ncolor = "cmyk"'), "'color' must be one of"),
    (lambda t: t.replace('size = [16, 16]', 'size = [16, 16]\nparams = { squares = 4, hue = 3 }'),
     "unknown parameter 'hue'"),
    (lambda t: t.replace('[scene]', '[scene\n'), "TOML syntax error"),
    (lambda t: t.replace('[[mesh]]\nshape = "quad"\ntexture = "a"\n', ''), "no meshes"),
    (lambda t: t + '[[texture]]\nname = "b"\ngenerator = "wood"\nsize = [8, 8]\ngroup = "a"\ncodebook_size = 16\n',
     "group 'a' shares one codebook but 'codebook_size' differs"),
    (lambda t: t.replace('shape = "quad"', 'shape = "quad"\nspin = { axis = [0, 0, 0] }'), "'axis' must not be zero"),
])
def test_malformed_scenes_raise_scene_error(edit, expect):
    msg = _err(edit(BASE))
    assert expect in msg, msg


def test_scene_error_names_the_file_and_where(tmp_path):
    p = tmp_path / "broken.toml"
    p.write_text(BASE.replace('texture = "a"', 'texture = "floor"'))
    with pytest.raises(SceneError) as e:
        load_scene(p)
    assert str(e.value).startswith(str(p)) and "[[mesh]] #1" in str(e.value) and "floor" in str(e.value)
    with pytest.raises(SceneError):
        load_scene("no-such-scene")
    assert issubclass(SceneError, ValueError)


def test_texture_files_beside_the_scene_and_size_checks(tmp_path):
    shutil.copy(DATA_DIR / "arrow.png", tmp_path / "sign.png")
    text = BASE.replace('generator = "checker"\nsize = [16, 16]', 'file = "sign.png"')
    s = parse_scene(text, tmp_path / "s.toml")
    assert s.textures[0].size == (64, 64)
    img, spec = s.load_textures()[0]
    assert img.shape == (64, 64, 3)  # default colour rgb: alpha dropped
    msg = _err(BASE.replace('generator = "checker"\nsize = [16, 16]', 'file = "sign.png"\nsize = [32, 32]'),
               str(tmp_path / "s.toml"))
    assert "does not match" in msg
    (tmp_path / "odd.png").write_bytes((DATA_DIR / "rocket.png").read_bytes())
    ok = parse_scene(BASE.replace('generator = "checker"\nsize = [16, 16]', 'file = "odd.png"'), tmp_path / "s.toml")
    assert ok.textures[0].size == (64, 128)


def _fake_encoder(monkeypatch):
    calls = []

    class FakeSet:
        def __init__(self, n):
            self.n = n

        @classmethod
        def combine(cls, sets):
            calls.append(("combine", [s.n for s in sets]))
            return FakeSet(sum(s.n for s in sets))

    def encode(images, *, block, codebook_size, color, index_bits, mipmaps, encoder, seed, names=None):
        calls.append(("encode", len(images), block, codebook_size, color, index_bits, mipmaps, encoder, seed,
                      tuple(names), tuple(im.shape[2] for im in images)))
        return FakeSet(len(images))

    monkeypatch.setitem(sys.modules, "vqtex.golden.encode", types.SimpleNamespace(encode=encode, ENCODERS=("gla",)))
    monkeypatch.setitem(sys.modules, "vqtex.golden.format", types.SimpleNamespace(TextureSet=FakeSet))
    return calls


def test_build_texture_set_encodes_one_group_at_a_time(monkeypatch):
    text = BASE.replace('name = "a"', 'name = "a"\ngroup = "g1"') + """
[groups.g1]
codebook_size = 16
block = "2x2"
seed = 5
[groups.g2]
color = "intensity"
index_bits = 12
codebook_size = 1024
mipmaps = false
[[texture]]
name = "b"
generator = "wood"
size = [8, 8]
group = "g2"
[[texture]]
name = "c"
generator = "marble"
size = [8, 4]
group = "g1"
"""
    s = parse_scene(text, "g.toml")
    assert [t.name for t in s.textures] == ["a", "c", "b"]  # ids group by group
    calls = _fake_encoder(monkeypatch)
    ts = build_texture_set(s)
    assert ts.n == 3
    assert calls[0] == ("encode", 2, (2, 2), 16, "rgb", None, True, "gla", 5, ("a", "c"), (3, 3))
    assert calls[1] == ("encode", 1, (4, 4), 1024, "intensity", 12, False, "gla", 0, ("b",), (1,))
    assert calls[2] == ("combine", [2, 1])
    src = s.reference_source()
    assert len(src.level_shapes(2)) == 1 and len(src.level_shapes(0)) == 5


def test_build_texture_set_with_the_real_encoder_renders():
    """Scene -> compressed TextureSet -> bit-exact fetch -> frame."""
    import vqtex.golden.encode as encode_mod
    import vqtex.golden.fetch as fetch_mod
    assert encode_mod
    from vqtex.golden.render.frame import render_frame
    from vqtex.golden.render.metrics import frame_mse

    text = BASE.replace('size = [16, 16]', 'size = [16, 16]\ncodebook_size = 4\nblock = "2x2"') + """
[[texture]]
name = "g"
generator = "wood"
size = [16, 8]
color = "intensity"
codebook_size = 8
[[mesh]]
shape = "plane"
texture = "g"
size = [4, 4]
translate = [0, -0.5, 0]
"""
    s = parse_scene(text, "real.toml")
    ts = build_texture_set(s)
    assert ts.n_textures == 2
    for t in s.textures:
        assert tuple(ts.level_shapes(t.id)[0]) == t.size

    class Compressed:
        def level_shapes(self, tex):
            return ts.level_shapes(tex)

        def fetch(self, tex, level, i, j):
            return fetch_mod.fetch(ts, tex, level, i, j)

    for mode in ("point", "trilinear"):
        vq = render_frame(s, 1, Compressed(), mode)
        ref = render_frame(s, 1, s.reference_source(), mode)
        assert vq.shape == ref.shape == (24, 32, 4)
        assert frame_mse(vq, ref) < 2000
