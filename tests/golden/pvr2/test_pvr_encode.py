"""The PowerVR2 encoder (golden.pvr2.pvr_encode): .dt files in pvrtex's layout that our decoder reads back
bit for bit, at a PSNR above pvrtex's own on its test image (crate.png, tests/data/pvrtex)."""

from pathlib import Path

import numpy as np
import pytest

from tests.support import PVRTEX_DATA
from vqtex.golden.pvr2 import pvr, pvr_set
from vqtex.golden.fetch import decode
from vqtex.golden.pvr2.pvr_encode import PvrEncodeError, encode_pvr2, quantize_channel
from vqtex.golden.render.imageio import read_image

DATA = Path(PVRTEX_DATA)
CRATE = read_image(DATA / "crate.png")


def _psnr(a, b):
    d = a[..., :3].astype(np.float64) - b[..., :3]
    return 10 * np.log10(255.0 ** 2 / (d * d).mean())


@pytest.mark.parametrize("color", ["rgb565", "argb1555", "argb4444", "yuv422"])
def test_beats_pvrtex_at_64_entries_and_reads_back_bit_for_bit(color):
    ts, data = encode_pvr2(CRATE, color, codebook_size=64)
    tex = pvr.parse_dt(data)
    assert (tex.header.format_name.lower(), tex.header.codebook_entries) == (color, 64)
    assert pvr_set.to_dt(ts) == data
    assert np.array_equal(decode(ts, 0, 0), tex.levels[0])
    ours = _psnr(tex.levels[0], CRATE)
    theirs = _psnr(pvr.read_dt(DATA / "generated" / f"crate_{color}_c_64.dt").levels[0], CRATE)
    assert ours > theirs, (ours, theirs)


def test_mip_chain_and_the_one_by_one_level():
    ts, data = encode_pvr2(CRATE[:64, :64], "yuv422", codebook_size=32, mipmaps=True)
    tex = pvr.parse_dt(data)
    assert tex.header.mipmapped and len(tex.levels) == 7 and len(data) % 32 == 0
    for L in range(7):
        assert np.array_equal(decode(ts, 0, L), tex.levels[L])
    # the 1x1 level is the entry whose texel 3 (as rgb565) is nearest the box-filtered 1x1 texel
    from vqtex.golden.mipmap import build_pyramid
    want = build_pyramid(CRATE[:64, :64])[-1][0, 0, :3].astype(int)
    t3 = pvr.decode_texels(tex.codebook[:, 3], pvr.RGB565)[:, :3].astype(int)
    assert ((tex.levels[-1][0, 0, :3].astype(int) - want) ** 2).sum() == ((t3 - want) ** 2).sum(-1).min()


def test_small_codebook_uses_the_top_entries_and_rectangles():
    img = np.random.default_rng(1).integers(0, 256, (16, 64, 4)).astype(np.uint8)
    ts, data = encode_pvr2(img, "argb4444", codebook_size=5)
    raw = np.frombuffer(data, np.uint8, offset=32 + 5 * 8, count=8 * 32)
    assert raw.min() >= 251 and pvr.parse_dt(data).header.codebook_entries == 5
    assert np.array_equal(decode(ts, 0, 0), pvr.parse_dt(data).levels[0])


def test_deterministic():
    img = CRATE[:32, :32]
    assert encode_pvr2(img, "rgb565", codebook_size=16, seed=3)[1] == encode_pvr2(img, "rgb565", codebook_size=16, seed=3)[1]


@pytest.mark.parametrize("bits", [1, 4, 5, 6])
def test_quantize_channel_is_the_nearest_widened_value(bits):
    v = np.linspace(-3, 258, 2000)
    widened = np.array([pvr._expand(np.array(q), bits) if bits > 1 else q * 255 for q in range(1 << bits)], float)
    got = widened[quantize_channel(v, bits)]
    assert np.allclose(np.abs(got - v), np.abs(widened[None, :] - v[:, None]).min(1))


@pytest.mark.parametrize("kw, match", [
    (dict(color="rgb"), "not one of"), (dict(codebook_size=257), "1..256"), (dict(codebook_size=0), "1..256"),
    (dict(mipmaps=True, image=np.zeros((16, 32, 3), np.uint8)), "square"),
    (dict(image=np.zeros((4, 4, 3), np.uint8)), "8..1024"), (dict(image=np.zeros((24, 24, 3), np.uint8)), "8..1024"),
    (dict(image=np.zeros((16, 16, 3), np.float32)), "uint8"),
])
def test_bad_settings(kw, match):
    image = kw.pop("image", CRATE[:16, :16])
    with pytest.raises(PvrEncodeError, match=match):
        encode_pvr2(image, **{"color": "rgb565", **kw})
