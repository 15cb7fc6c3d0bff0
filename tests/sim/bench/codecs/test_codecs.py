"""vqtex.sim.bench.codecs: every codec path on tiny images (round trips, rates by construction, the
numpy BC1 decoder against texture2ddecoder and hand-made blocks), the rows' fields, and the command's
JSON. No timing is asserted (speed lives in the benchmark)."""

import json

import numpy as np
import pytest

from vqtex.sim.bench import codecs
from vqtex.sim.bench.codecs import astc, bc1, jpeg2000, vq, wavelet
from vqtex.sim.bench.codecs.measure import psnr, random_texels
from vqtex.sim.cli import main


def _image(size=64, seed=0):
    """A smooth colour picture with some texture: what codecs are built for (PSNR bands are stable)."""
    yy, xx = np.mgrid[0:size, 0:size] / size
    rng = np.random.default_rng(seed)
    base = np.stack([0.5 + 0.4 * np.sin(6 * xx + 2 * yy), 0.5 + 0.4 * np.cos(5 * yy), 0.3 + 0.5 * xx * yy], -1)
    noise = rng.normal(0, 0.02, base.shape)
    return np.clip(np.rint((base + noise) * 255), 0, 255).astype(np.uint8)


# -- BC1 ------------------------------------------------------------------------------------------

def test_bc1_numpy_decoder_equals_texture2ddecoder_on_random_blocks():
    rng = np.random.default_rng(1)
    data = rng.integers(0, 256, 64 * 64 // 16 * 8, dtype=np.uint8).tobytes()   # both modes, every selector
    words = np.frombuffer(data, "<u8")
    c0, c1 = words & 0xFFFF, (words >> 16) & 0xFFFF
    assert (c0 > c1).any() and (c0 <= c1).any()
    ours = bc1.decode(data, 64, 64)
    assert np.array_equal(ours, bc1.decode_library(data, 64, 64))
    y, x = np.mgrid[0:64, 0:64].reshape(2, -1)
    assert np.array_equal(bc1.texels(data, 64, 64, y, x), ours[y, x])


def test_bc1_known_blocks():
    red, blue = 0xF800, 0x001F
    sel = 0b11100100                                                   # texels 0..3 of a row: 0, 1, 2, 3
    four = np.array([red & 255, red >> 8, blue & 255, blue >> 8, sel, sel, sel, sel], np.uint8)   # c0 > c1
    three = np.array([blue & 255, blue >> 8, red & 255, red >> 8, sel, sel, sel, sel], np.uint8)  # c0 <= c1
    out = bc1.decode(np.concatenate([four, three]).tobytes(), 8, 4)
    assert out[0, :4].tolist() == [[255, 0, 0], [0, 0, 255], [170, 0, 85], [85, 0, 170]]
    assert out[3, 4:].tolist() == [[0, 0, 255], [255, 0, 0], [127, 0, 127], [0, 0, 0]]


@pytest.mark.parametrize("encoder", bc1.ENCODERS)
def test_bc1_round_trip(encoder):
    img = _image()
    data = bc1.encode(img, encoder)
    assert len(data) * 8 == 4 * 64 * 64                                # 4 bits per texel
    assert 28 < psnr(img, bc1.decode(data, 64, 64)) < 60


def test_bc1_rejects_bad_sizes():
    with pytest.raises(ValueError, match="multiples of 4"):
        bc1.decode(bytes(8), 6, 4)
    with pytest.raises(ValueError, match="blocks"):
        bc1.decode(bytes(8), 8, 4)


# -- ASTC -----------------------------------------------------------------------------------------

@pytest.mark.parametrize("block", astc.BLOCKS)
def test_astc_round_trip_and_rate(block):
    img = _image(32)
    codec = astc.Astc(block)
    data = codec.encode(img)
    blocks = (-(-32 // block)) ** 2
    assert len(data) == 16 * blocks                                    # 128 bits per block, whatever the footprint
    dec = codec.decode(data, 32, 32)
    assert 24 < psnr(img, dec) < 60
    y, x = random_texels(img.shape, 200)
    assert np.array_equal(codec.texels(data, 32, y, x), dec[y, x])


# -- JPEG 2000 ------------------------------------------------------------------------------------

@pytest.mark.parametrize("tile", jpeg2000.TILES)
def test_jpeg2000_round_trip_and_rate(tmp_path, tile):
    img = _image(128)
    path = str(tmp_path / "a.j2k")
    jp2 = jpeg2000.encode(img, path, 2.0, tile)
    bpt = (tmp_path / "a.j2k").stat().st_size * 8 / 128 ** 2
    assert 1.6 < bpt <= 2.2                                            # OpenJPEG's rate control, headers included
    dec = jpeg2000.decode(path)
    assert dec.shape == img.shape and 30 < psnr(img, dec) < 60
    assert np.array_equal(jpeg2000.decode_texel(jp2, 70, 5), dec[70, 5])


# -- wavelets -------------------------------------------------------------------------------------

def test_bior22_is_legall_53():
    import pywt
    lo = np.array(pywt.Wavelet("bior2.2").dec_lo)
    assert np.allclose(lo[1:] / np.sqrt(2), np.array([-1, 2, 6, 2, -1]) / 8) and lo[0] == 0


def test_entropy_model():
    q = [np.zeros((1, 4, 4, 3), np.int32)]
    assert wavelet.WaveletCoder.bits(q) == 0
    a = np.zeros((1, 4, 4, 3), np.int32)
    a[0, :2, :, 0] = 1                                                  # channel 0: eight 0s, eight 1s
    a[0, :, :, 2] = np.arange(16).reshape(4, 4)                         # channel 2: sixteen symbols
    assert wavelet.WaveletCoder.bits([a]) == pytest.approx(16 * 1 + 16 * 4)


@pytest.mark.parametrize("name", wavelet.WAVELETS)
@pytest.mark.parametrize("tile", wavelet.TILES)
def test_wavelet_round_trip_rate_search_and_tiles(name, tile):
    img = _image(128)
    coder = wavelet.WaveletCoder(img, name, tile)
    bands = coder.analyse(img)
    assert sum(b.size for b in bands) == img.size                      # critically sampled (periodic extension)
    fine = coder.quantise(bands, 0.05)
    assert psnr(img, coder.decode(fine, 0.05)) > 50                    # near lossless at a tiny step
    rates = [coder.bits(coder.quantise(bands, s)) for s in (1, 4, 16, 64)]
    assert rates == sorted(rates, reverse=True)
    step, q, bits = coder.search(bands, 1.0)
    assert 0.97 * 128 ** 2 <= bits <= 128 ** 2                          # at most the target, and close to it
    dec = coder.decode(q, step)
    assert 25 < psnr(img, dec) < 50
    y, x = random_texels(img.shape, 50)
    t, ty, tx = coder.tile_of(y, x)
    assert np.array_equal(coder.decode_tiles(q, step, t)[np.arange(50), ty, tx], dec[y, x])


# -- VQ and the rows ------------------------------------------------------------------------------

def test_vq_rows_count_bits_as_the_paper():
    img = _image(32)
    y, x = random_texels(img.shape, 100)
    (r,) = vq.rows("t", img, y=y, x=x, repeats=1, configs=("2x2/16 rgb",))
    assert r["index_bits_per_texel"] == 1.0                             # 4-bit indices per 2x2 block
    assert r["bits_per_texel"] == (256 * 4 + 16 * 12 * 8) / 1024        # plus the whole codebook
    assert 20 < r["psnr_db"] < 60
    with pytest.raises(ValueError, match="not like"):
        vq.parse_config("2x2 rgb")


TINY = dict(vq_configs=("2x2/16 rgb", "4x4/16 yuv411"), repeats=1, random_texels_n=64, jpeg2000_sample=2,
            astc_blocks=(8,))


def test_codec_rows_report_every_field():
    images = {"a": _image(64), "b": _image(64, seed=3)}
    rows = codecs.codec_rows(images, **TINY)
    methods = {r["method"] for r in rows}
    assert methods == set(codecs.METHODS)
    for r in rows:
        assert set(r) == set(codecs.FIELDS)
        for k in ("bits_per_texel", "psnr_db", "encode_s", "decode_s", "random_texel_s", "floor_s",
                  "random_floor_s"):
            assert isinstance(r[k], float) and r[k] > 0, (r["method"], r["config"], k)
        assert r["width"] == r["height"] == 64 and r["random_texel"] and r["library"]
    for name in images:
        targets = {r["config"]: r["bits_per_texel"] for r in rows if r["image"] == name and r["method"] == "vq"}
        for r in rows:
            if r["image"] == name and r["method"] in ("jpeg2000", "wavelet"):
                cfg = r["config"].split("@")[1]
                assert r["target_bits_per_texel"] == targets[cfg]
                if r["method"] == "wavelet":
                    assert r["bits_per_texel"] <= targets[cfg]
    # 2 VQ + 2 BC1 + 1 ASTC + 2 rates x 2 layouts of JPEG 2000 + 2 wavelets x 2 layouts x 2 rates, per image
    assert len(rows) == 2 * (2 + 2 + 1 + 4 + 8)
    assert len(codecs.summary(rows)) == len(rows) // 2


def test_codec_rows_reject_bad_images():
    with pytest.raises(ValueError, match="powers of two"):
        codecs.codec_rows({"a": np.zeros((48, 64, 3), np.uint8)})
    with pytest.raises(ValueError, match="uint8"):
        codecs.codec_rows({"a": np.zeros((64, 64, 3), np.float32)})
    with pytest.raises(ValueError, match="methods"):
        codecs.codec_rows({"a": _image(16)}, methods=("png",))


def test_bench_codecs_json(monkeypatch, capsys):
    monkeypatch.setattr(codecs, "default_images", lambda quick: {"tiny": _image(32)})
    monkeypatch.setattr(codecs, "QUICK", TINY)
    assert main(["bench", "codecs", "--quick", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["benchmark"] == "codecs" and out["quick"] is True and out["images"] == {"tiny": [32, 32]}
    assert out["fields"] == list(codecs.FIELDS)
    assert {r["method"] for r in out["rows"]} == set(codecs.METHODS)
    assert all(set(r) == set(codecs.FIELDS) for r in out["rows"])
    assert main(["bench", "codecs", "--quick"]) == 0                    # the readable table
    text = capsys.readouterr().out
    assert "tiny (32x32)" in text and "jpeg2000" in text and "floor" in text


def test_quick_is_only_for_benches_that_have_it(capsys):
    assert main(["bench", "mip", "--quick"]) == 2
    assert capsys.readouterr().err.strip() == "vqtex: error: bench mip has no --quick"


def test_codec_rows_at_given_rates_without_vq():
    rows = codecs.codec_rows({"a": _image(64)}, methods=("jpeg2000", "wavelet"), targets={"1 bpt": 1},
                             wavelets=("haar",), jpeg2000_tiles=(None,), wavelet_tiles=(None,), repeats=1,
                             random_texels_n=16, jpeg2000_sample=1)
    assert [(r["method"], r["config"], r["target_bits_per_texel"]) for r in rows] == [
        ("jpeg2000", "untiled @1 bpt", 1.0), ("wavelet", "Haar untiled @1 bpt", 1.0)]


def test_a_missing_openjpeg_is_one_line(monkeypatch, capsys):
    def missing():
        raise ImportError("glymur found no OpenJPEG library", name="libopenjp2")
    monkeypatch.setattr(jpeg2000, "openjpeg", missing)
    monkeypatch.setattr(codecs, "default_images", lambda quick: {"tiny": _image(32)})
    monkeypatch.setattr(codecs, "QUICK", dict(TINY, vq_configs=("2x2/16 rgb",)))
    assert main(["bench", "codecs", "--quick", "--json"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.strip() == "vqtex: error: bench codecs needs libopenjp2 (scripts/install-sim-tools)"


def test_a_lossless_row_has_no_psnr_and_the_table_says_exact(capsys):
    flat = np.full((16, 16, 3), 255, np.uint8)                      # every codec is exact on a white picture
    rows = codecs.codec_rows({"white": flat}, methods=("bc1",), bc1_encoders=("etcpak",), repeats=1,
                             random_texels_n=8)
    assert rows[0]["psnr_db"] is None
    out = {"images": {"white": [16, 16]}, "rows": rows, "summary": codecs.summary(rows)}
    assert out["summary"][0]["psnr_db"] is None
    json.dumps(out, allow_nan=False)
    codecs.print_table(out)
    assert "exact" in capsys.readouterr().out


def test_vq_skips_codebooks_as_large_as_the_image():
    img = _image(16)                                                # 64 blocks of 2x2
    y, x = random_texels(img.shape, 8)
    rows = vq.rows("t", img, y=y, x=x, repeats=1, configs=("2x2/64 rgb", "2x2/16 rgb", "4x4/16 rgb"))
    assert [r["config"] for r in rows] == ["2x2/16 rgb"]
