"""Dreamcast .dt textures through the command line: vqtex import, every command that reads a .vqt
reading a .dt too (info, decode, sim, export, report's input), scenes naming .dt textures, and
damaged or foreign .dt files as one-line errors with exit status 2."""

import json
from pathlib import Path

import numpy as np
import pytest

from tests.support import PVRTEX_DATA, crates_scene, need, shared_cache_dir
from vqtex.golden.pvr2 import pvr, pvr_set
from vqtex.golden.format import TextureSet
from vqtex.golden.render.imageio import read_image
from tests.support import run_cli as _run, assert_one_error as _one_error

DATA = Path(PVRTEX_DATA) / "generated"
YUV_MIP = DATA / "crate_yuv422_c_m.dt"
ARGB = DATA / "crate_argb1555_c_64.dt"


@pytest.fixture(autouse=True)
def cache(monkeypatch):
    monkeypatch.setenv("VQTEX_CACHE", shared_cache_dir())


def test_import_several_files_into_one_set(capsys, tmp_path):
    out = tmp_path / "crates.vqt"
    code, text, _ = _run(capsys, "import", YUV_MIP, ARGB, "-o", out, "--json")
    assert code == 0
    rep = json.loads(text)
    assert [t["color"] for t in rep["textures"]] == ["yuv422", "argb1555"]
    ts = TextureSet.load(out)
    assert ts.n_textures == 2 and [c.size for c in ts.codebooks] == [256, 64]


def test_info_and_decode_read_a_dt(capsys, tmp_path):
    code, text, _ = _run(capsys, "info", YUV_MIP, "--json")
    t = json.loads(text)["textures"][0]
    assert code == 0 and (t["color"], t["levels"], t["block"], t["index_bits"]) == ("yuv422", 8, "2x2", 8)
    for level in (0, 3, 7):
        img = tmp_path / f"l{level}.png"
        assert _run(capsys, "decode", YUV_MIP, "--level", level, "-o", img)[0] == 0
        assert np.array_equal(read_image(img), pvr.read_dt(YUV_MIP).levels[level][..., :3])
    img = tmp_path / "a.png"
    assert _run(capsys, "decode", ARGB, "-o", img)[0] == 0
    assert np.array_equal(read_image(img), pvr.read_dt(ARGB).levels[0])          # alpha kept


def test_sim_on_a_dt_through_cxxrtl(capsys, tmp_path):
    need("g++")
    rng = np.random.default_rng(0)
    n = 3000
    level = rng.integers(0, 8, n)
    size = 128 >> level
    req = np.stack([np.zeros(n, np.int64), level, rng.integers(0, 1 << 20, n) % size, rng.integers(0, 1 << 20, n) % size], 1)
    np.save(tmp_path / "req.npy", req)
    code, text, _ = _run(capsys, "sim", YUV_MIP, tmp_path / "req.npy", "-o", tmp_path / "resp.npy",
                         "--backend", "cxxrtl", "--stall", "0.2", "--json")
    assert code == 0 and json.loads(text)["requests"] == n
    resp = np.load(tmp_path / "resp.npy")
    levels = pvr.read_dt(YUV_MIP).levels
    want = np.stack([levels[L][j, i] for L, i, j in req[:, 1:]])
    assert np.array_equal(resp, want)


def test_export_a_dt_lint_clean(capsys, tmp_path):
    need("verilator")
    out = tmp_path / "crate.v"
    code, text, err = _run(capsys, "export", YUV_MIP, "-o", out, "--lint", "--json")
    assert code == 0, err
    assert json.loads(text)["lint"] == "clean" and "module texel_fetch" in out.read_text()


def test_render_a_scene_naming_dt_textures(capsys, tmp_path):
    need("g++")
    crates_scene(tmp_path)
    code, text, err = _run(capsys, "render", tmp_path / "crates.toml", "-o", tmp_path / "f.png", "--backend", "cxxrtl",
                           "--json")
    assert code == 0, err
    rep = json.loads(text)
    assert rep["identical_to_golden"] is True and rep["frames"][0]["requests"] > 1000
    assert rep["overall_rate"] == round(TextureSet.combine([pvr_set.import_dt([YUV_MIP]),
                                                            pvr_set.import_dt([ARGB])]).rates()["overall"], 4)
    (tmp_path / "bad.toml").write_text((tmp_path / "crates.toml").read_text().replace(
        'file = "crate_argb1555_c_64.dt"', 'file = "crate_argb1555_c_64.dt"\ncodebook_size = 16'))
    _one_error(capsys, ["render", tmp_path / "bad.toml", "-o", tmp_path / "g.png"], "does not apply to a .dt")


def _good() -> bytes:
    return (DATA / "crate_argb4444_c_64_m.dt").read_bytes()


def _with(data: bytes, offset: int, new: bytes) -> bytes:
    return data[:offset] + new + data[offset + len(new):]


BAD = {
    "wrong magic": (lambda d: _with(d, 0, b"PVRT"), "magic"),
    "size field larger": (lambda d: _with(d, 4, (len(d) + 64).to_bytes(4, "little")), "truncated"),
    "size field smaller": (lambda d: _with(d, 4, (len(d) - 64).to_bytes(4, "little")), "oversized"),
    "truncated": (lambda d: d[:3000], "truncated"),
    "header only": (lambda d: d[:20], "truncated"),
    "empty": (lambda d: b"", "truncated"),
    "palettised 8bpp": (lambda d: _with(d, 19, bytes([(d[19] & ~0x38) | (6 << 3)])), "PAL8BPP"),
    "palettised 4bpp": (lambda d: _with(d, 19, bytes([(d[19] & ~0x38) | (5 << 3)])), "PAL4BPP"),
    "not VQ": (lambda d: _with(d, 19, bytes([d[19] & ~0x40])), "not VQ"),
    "not twiddled": (lambda d: _with(d, 19, bytes([d[19] | 0x04])), "twiddled"),
    "width not a power of two": (lambda d: _with(d, 12, (100).to_bytes(2, "little")), "dimensions"),
    "index past a small codebook": (lambda d: _with(d, 32 + 512 + 100, b"\x00"), "outside the 64-entry codebook"),
}


@pytest.mark.parametrize("name", sorted(BAD))
def test_damaged_or_foreign_dt_is_one_line_exit_2(capsys, tmp_path, name):
    damage, pattern = BAD[name]
    path = tmp_path / "bad.dt"
    path.write_bytes(damage(_good()))
    _one_error(capsys, ["info", path], pattern)
    _one_error(capsys, ["import", path, "-o", tmp_path / "x.vqt"], pattern)
    assert not (tmp_path / "x.vqt").exists()


def test_missing_dt_is_one_line(capsys, tmp_path):
    _one_error(capsys, ["decode", tmp_path / "nothing.dt", "-o", tmp_path / "a.png"], "cannot read")


def test_encode_layout_pvr2_writes_a_dt_read_back_bit_for_bit(capsys, tmp_path):
    src = DATA.parent / "crate.png"
    out = tmp_path / "crate.dt"
    code, text, err = _run(capsys, "encode", src, "--layout", "pvr2", "--color", "yuv422", "--mipmaps", "-k", "64",
                           "-o", out, "--json")
    assert code == 0, err
    rep = json.loads(text)
    t = rep["textures"][0]
    assert (t["color"], t["levels"], t["codebook_size"]) == ("yuv422", 8, 64) and len(t["psnr_db"]) == 8
    tex = pvr.read_dt(out)
    for level in (0, 4):
        img = tmp_path / f"l{level}.png"
        assert _run(capsys, "decode", out, "--level", level, "-o", img)[0] == 0
        assert np.array_equal(read_image(img), tex.levels[level][..., :3])
    assert pvr_set.to_dt(pvr_set.import_dt([out])) == out.read_bytes()


def test_encode_layout_pvr2_bad_options(capsys, tmp_path):
    src = DATA.parent / "crate.png"
    _one_error(capsys, ["encode", src, "--layout", "pvr2", "--color", "rgb", "-o", tmp_path / "a.dt"], "takes --color")
    _one_error(capsys, ["encode", src, "--layout", "pvr2", "-k", "300", "-o", tmp_path / "a.dt"], "1..256")
    _one_error(capsys, ["encode", src, "--layout", "pvr2", "--block", "2x2", "-o", tmp_path / "a.dt"], "does not apply")
    _one_error(capsys, ["encode", src, src, "--layout", "pvr2", "-o", tmp_path / "a.dt"], "holds one texture")
    _one_error(capsys, ["encode", src, "--color", "rgb565", "-o", tmp_path / "a.vqt"], "--layout pvr2")
    _one_error(capsys, ["encode", src, "--layout", "pvr2", "-o", tmp_path / "a.png"], "extension")
    assert not list(tmp_path.iterdir())
