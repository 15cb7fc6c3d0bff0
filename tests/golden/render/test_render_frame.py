"""Frames: determinism, the two-phase split (requests -> texels -> resolve), pyramids, metrics, I/O."""

import os

import numpy as np
import pytest

from vqtex.golden.render import textures
from vqtex.golden.render.frame import (
    frame_requests, load_requests, plan_frame, render_frame, resolve_frame, save_requests,
)
from vqtex.golden.render.imageio import ImageIOError, read_image, write_image
from vqtex.golden.render.metrics import frame_mse, frame_psnr
from vqtex.golden.render.pyramid import ReferenceSource, build_pyramid, downsample
from vqtex.golden.render.scene import load_scene, parse_scene

SMALL = """
[scene]
frames = 4
size = [48, 40]
background = [10, 20, 30]
[camera]
position = [0, 1.5, 3]
target = [0, 0.3, 0]
[camera.orbit]
degrees = 90
[[texture]]
name = "floor"
generator = "checker"
size = [32, 32]
[[texture]]
name = "thing"
generator = "marble"
size = [32, 16]
address = ["wrap", "clamp"]
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


@pytest.fixture(scope="module")
def small():
    scene = parse_scene(SMALL, "small.toml")
    return scene, scene.reference_source()


@pytest.fixture(scope="module")
def topspin():
    scene = load_scene("topspin")
    return scene, scene.reference_source()


@pytest.mark.parametrize("mode", ["point", "trilinear"])
def test_render_is_deterministic(small, mode):
    scene, src = small
    a = render_frame(scene, 1, src, mode)
    b = render_frame(scene, 1, src, mode)
    scene2 = parse_scene(SMALL, "small.toml")
    c = render_frame(scene2, 1, scene2.reference_source(), mode)
    assert a.shape == (40, 48, 4) and a.dtype == np.uint8
    assert (a == b).all() and (a == c).all()
    assert (a.reshape(-1, 4) == (10, 20, 30, 255)).all(1).any()  # some background
    assert not (a.reshape(-1, 4) == (10, 20, 30, 255)).all(1).all()


@pytest.mark.parametrize("mode", ["point", "trilinear"])
def test_resolve_of_fetched_requests_equals_render_frame(small, mode, tmp_path):
    scene, src = small
    reqs, sampler = frame_requests(scene, 2, src, mode)
    assert reqs.ndim == 2 and reqs.shape[1] == 4 and np.issubdtype(reqs.dtype, np.integer)
    assert len(reqs) == sampler.counts.sum() <= len(sampler.fragments) * (1 if mode == "point" else 8)
    path = tmp_path / "reqs.npy"
    save_requests(path, reqs)
    assert sorted(os.listdir(tmp_path)) == ["reqs.npy"]
    back = load_requests(path)
    assert (back == reqs).all()
    texels = src.fetch(back[:, 0], back[:, 1], back[:, 2], back[:, 3])  # "the RTL"
    frame = resolve_frame(scene, 2, src, texels, mode)
    assert (frame == render_frame(scene, 2, src, mode)).all()
    assert (sampler.resolve(texels) == frame).all()


def test_topspin_frame_through_both_phases(topspin):
    scene, src = topspin
    sampler = plan_frame(scene, 7, src, "trilinear", stream="fixed")
    reqs = sampler.requests(sampler.fragments)
    assert len(reqs) == 8 * len(sampler.fragments) > 8 * 40_000
    assert set(np.unique(reqs[:, 0])) == {0, 1, 2}
    frame = sampler.resolve(src.fetch(*reqs.T))
    assert (frame == render_frame(scene, 7, src, "trilinear")).all()
    assert frame.shape == (400, 400, 4)


def test_source_must_match_the_scene(small):
    scene, _ = small
    wrong = ReferenceSource([np.zeros((16, 16, 3), np.uint8)] * 2)
    with pytest.raises(ValueError):
        render_frame(scene, 0, wrong)


def test_pyramid_rule():
    rng = np.random.default_rng(0)
    img = rng.integers(0, 256, (8, 32, 3), dtype=np.uint8)
    pyr = build_pyramid(img)
    assert [p.shape[:2] for p in pyr] == [(8, 32), (4, 16), (2, 8), (1, 4), (1, 2), (1, 1)]
    a = pyr[0].astype(int)
    expect = (a[0::2, 0::2] + a[0::2, 1::2] + a[1::2, 0::2] + a[1::2, 1::2] + 2) >> 2
    assert (pyr[1] == expect).all()
    b = pyr[3].astype(int)
    assert (pyr[4] == (b[:, 0::2] + b[:, 1::2] + 1) >> 1).all()
    assert (pyr[0][..., 3] == 255).all()
    tall = downsample(np.array([[[10]], [[13]]], np.uint8))
    assert tall.tolist() == [[[12]]]
    grey = build_pyramid(np.array([[7, 9], [11, 200]], np.uint8))
    assert grey[0][0, 1].tolist() == [9, 9, 9, 255]
    assert grey[1][0, 0].tolist() == [57, 57, 57, 255]
    with pytest.raises(ValueError):
        build_pyramid(np.zeros((6, 8), np.uint8))


def test_reference_source_fetch_and_range_checks():
    rng = np.random.default_rng(1)
    imgs = [rng.integers(0, 256, (4, 8, 4), dtype=np.uint8), rng.integers(0, 256, (2, 2), dtype=np.uint8)]
    src = ReferenceSource(imgs, levels=[None, 1])
    assert src.level_shapes(0) == [(8, 4), (4, 2), (2, 1), (1, 1)]
    assert src.level_shapes(1) == [(2, 2)]
    got = src.fetch([0, 0, 1], [0, 1, 0], [7, 3, 1], [3, 1, 0])
    assert got[0].tolist() == imgs[0][3, 7].tolist()
    assert got[1].tolist() == build_pyramid(imgs[0])[1][1, 3].tolist()
    assert got[2].tolist() == [imgs[1][0, 1]] * 3 + [255]
    for bad in ([0], [0], [8], [0]), ([1], [1], [0], [0]), ([2], [0], [0], [0]), ([0], [0], [-1], [0]):
        with pytest.raises(ValueError):
            src.fetch(*bad)


def test_frame_mse():
    a = np.zeros((10, 20, 4), np.uint8)
    b = a.copy()
    assert frame_mse(a, b) == 0 and frame_psnr(a, b) == float("inf")
    b[0, 0, 0] = 10  # one pixel, one channel: 100 / 200 pixels / 3 channels
    assert frame_mse(a, b) == pytest.approx(100 / 200 / 3)
    b[..., 3] = 7  # alpha is ignored
    assert frame_mse(a, b) == pytest.approx(100 / 200 / 3)
    assert frame_mse(a[..., :3], b) == pytest.approx(100 / 200 / 3)
    with pytest.raises(ValueError):
        frame_mse(a, a[:5])


def test_image_io_round_trip_and_atomic_write(tmp_path):
    rng = np.random.default_rng(2)
    for c in (1, 3, 4):
        img = rng.integers(0, 256, (5, 7, c), dtype=np.uint8)
        p = tmp_path / f"x{c}.png"
        write_image(p, img)
        assert (read_image(p) == img).all()
    assert sorted(os.listdir(tmp_path)) == ["x1.png", "x3.png", "x4.png"]
    with pytest.raises(ValueError):
        write_image(tmp_path / "bad.png", np.zeros((4, 4), np.float32))
    with pytest.raises(ImageIOError):
        read_image(tmp_path / "missing.png")
    (tmp_path / "junk.png").write_bytes(b"not a png at all")
    with pytest.raises(ImageIOError):
        read_image(tmp_path / "junk.png")
    assert not [f for f in os.listdir(tmp_path) if f.startswith(".tmp")]


@pytest.mark.parametrize("name", sorted(textures.GENERATORS))
def test_procedural_textures_are_deterministic_and_seeded(name):
    a = textures.generate(name, (64, 32), seed=1)
    channels = 4 if name == "cutout" else 3          # cutout is RGBA (textures' docstring)
    assert a.shape == (32, 64, channels) and a.dtype == np.uint8
    assert (a == textures.generate(name, (64, 32), seed=1)).all()
    if name != "checker":
        assert (a != textures.generate(name, (64, 32), seed=2)).any()
    assert a.std() > 5  # not flat


def test_periodic_noise_tiles():
    n = textures.periodic_noise(64, 64, 8, np.random.default_rng(0))
    # the wrap-around step is no larger than an ordinary neighbour step
    inner = np.abs(np.diff(n, axis=1)).max()
    assert np.abs(n[:, 0] - n[:, -1]).max() <= inner + 1e-12
