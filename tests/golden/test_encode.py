"""golden.encode: quality floors, determinism, parameters and degenerate inputs."""

import numpy as np
import pytest

from vqtex.golden.encode import EncodeError, encode, reference_pyramid
from vqtex.golden.fetch import decode
from vqtex.golden.render.imageio import read_image
from pathlib import Path

from tests.support import REPO


def _psnr(a, b):
    mse = np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2)
    return 10 * np.log10(255.0 ** 2 / max(mse, 1e-12))


def _photo():
    """A real photograph shipped with the renderer's textures (CC0), or a smooth synthetic."""
    data = Path(REPO) / "golden" / "data"
    for name in ("brick", "coffee", "astronaut", "chelsea"):
        for p in data.glob(f"{name}*.png"):
            img = read_image(p)
            h, w = img.shape[:2]
            s = min(128, h, w)
            return img[:s, :s]
    yy, xx = np.mgrid[0:128, 0:128]
    return np.stack([np.sin(xx / 9) * 100 + 120, np.cos(yy / 7) * 100 + 120, (xx + yy)], -1).astype(np.uint8)


@pytest.mark.parametrize("color,block,k,floor", [
    ("rgb", (2, 2), 256, 27.0), ("rgb", (4, 4), 256, 22.0), ("rgba", (4, 2), 128, 22.0),
    ("intensity", (4, 4), 64, 22.0), ("yuv411", (2, 2), 256, 25.0), ("yuv411", (4, 4), 256, 22.0),
])
def test_decode_approximates_original(color, block, k, floor):
    img = _photo()
    if img.ndim == 2 or img.shape[2] == 1:
        img = np.repeat(img.reshape(img.shape[0], img.shape[1], 1), 3, axis=2)
    ts = encode([img], block=block, codebook_size=k, color=color, seed=1)
    ref = reference_pyramid(img, color, False)[0]
    chans = {"rgb": 3, "yuv411": 3, "rgba": 4, "intensity": 1}[color]
    assert _psnr(decode(ts, 0, 0)[..., :chans], ref[..., :chans]) > floor


def test_deterministic():
    img = _photo()
    a = encode([img], codebook_size=32, seed=7, mipmaps=True, raw_below=8).to_bytes()
    b = encode([img], codebook_size=32, seed=7, mipmaps=True, raw_below=8).to_bytes()
    assert a == b
    t1 = encode([img], codebook_size=32, seed=7, encoder="tsvq").to_bytes()
    t2 = encode([img], codebook_size=32, seed=7, encoder="tsvq").to_bytes()
    assert t1 == t2


def test_shared_codebook_serves_every_texture():
    rng = np.random.default_rng(2)
    imgs = [rng.integers(0, 256, (32, 32, 3), dtype=np.uint8) for _ in range(3)]
    ts = encode(imgs, codebook_size=16)
    assert len(ts.codebooks) == 1 and all(t.codebook == 0 for t in ts.textures)
    assert ts.rates()["overall"] > 0


def test_joint_mip_training_helps_small_levels():
    """Beyond the paper: training on all sub-levels lowers the error of levels 1 and 2."""
    img = _photo()
    ref = reference_pyramid(img, "rgb", True)
    err = {}
    for mode in ("average", "joint"):
        ts = encode([img], codebook_size=64, mipmaps=True, mip_training=mode, seed=3)
        err[mode] = [np.mean((decode(ts, 0, L)[..., :3].astype(float) - ref[L][..., :3]) ** 2) for L in range(3)]
    assert err["joint"][1] + err["joint"][2] < err["average"][1] + err["average"][2]


def test_non_square_and_extreme_sizes():
    for h, w in ((1, 1), (1, 4096), (2, 1), (8, 4), (64, 16)):
        img = np.full((h, w, 3), 9, np.uint8)
        ts = encode([img], codebook_size=2, mipmaps=True)
        assert ts.textures[0].levels == max(h, w).bit_length()
        for L in range(ts.textures[0].levels):
            assert (decode(ts, 0, L)[..., :3] == 9).all()


@pytest.mark.parametrize("kwargs,msg", [
    (dict(block=(3, 4)), "powers of two"), (dict(block=(16, 16)), "powers of two"),
    (dict(codebook_size=1), "2..4096"), (dict(codebook_size=5000), "2..4096"),
    (dict(codebook_size=256, index_bits=7), "cannot address"), (dict(color="cmyk"), "colour format"),
    (dict(encoder="kmeans"), "encoder"), (dict(word_bits=24), "word width"),
])
def test_bad_parameters(kwargs, msg):
    with pytest.raises(EncodeError, match=msg):
        encode([np.zeros((32, 32, 3), np.uint8)], **kwargs)


def test_bad_images():
    with pytest.raises(EncodeError, match="powers of two"):
        encode([np.zeros((48, 32, 3), np.uint8)])
    with pytest.raises(EncodeError, match="powers of two"):
        encode([np.zeros((8192, 1, 3), np.uint8)])
    with pytest.raises(EncodeError, match="uint8"):
        encode([np.zeros((32, 32, 3), np.float32)])
    with pytest.raises(EncodeError, match="no images"):
        encode([])


def test_tsvq_encoder_uses_tree_search():
    """encoder="tsvq" is the paper's TSVQ: its index map is the tree search's, not a full search."""
    from vqtex.golden import codebook as vq
    from vqtex.golden.encode import block_vectors
    from vqtex.golden.format import unpack_indices
    img = _photo()
    if img.ndim == 2 or img.shape[2] == 1:
        img = np.repeat(img.reshape(img.shape[0], img.shape[1], 1), 3, axis=2)
    img = np.ascontiguousarray(img[..., :3])
    ts = encode([img], block=(2, 2), codebook_size=64, encoder="tsvq", seed=4)
    v = block_vectors(reference_pyramid(img, "rgb", False)[0], "rgb", 2, 2).astype(np.float32)
    tree = vq.tsvq_tree(v, 64, seed=4)
    d = ts.descriptor(0, 0)
    got = unpack_indices(ts.index_words, d["index_bits"], len(v), d["base"])
    assert np.array_equal(got, tree.encode(v))
    full, _ = vq.nearest(v, tree.codebook)
    assert not np.array_equal(full, got) or len(np.unique(v, axis=0)) <= 64
