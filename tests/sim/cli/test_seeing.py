"""Seeing the error through the command line: PSNR per texture and level (encode, info), the
reference frame and the difference heat map (render), the cycle report and plot (report cycles),
and a clean one-line error when matplotlib is missing."""

import json
import sys

import numpy as np
import pytest

from tests.support import TINY_SCENE
from vqtex.golden.encode import reference_pyramid
from vqtex.golden.fetch import decode
from vqtex.golden.format import TextureSet
from vqtex.golden.render import render_frame
from vqtex.golden.render.imageio import read_image, write_image
from vqtex.golden.render.scene import load_scene
from vqtex.sim.cli import main
from tests.support import run_cli as _run


def _psnr(a, b):
    mse = np.mean((a.astype(float) - b.astype(float)) ** 2)
    return None if mse == 0 else 10 * np.log10(255 ** 2 / mse)


def test_encode_and_info_psnr_per_texture_and_level(tmp_path, capsys):
    rng = np.random.default_rng(3)
    paths = []
    for n, ch in enumerate((3, 4)):
        yy, xx = np.mgrid[0:64, 0:64]
        img = np.dstack([xx * 4, yy * 4, (xx + yy) * 2, 255 - yy * 3][:ch]) + rng.integers(0, 30, (64, 64, ch))
        paths.append(tmp_path / f"t{n}.png")
        write_image(paths[-1], np.clip(img, 0, 255).astype(np.uint8))
    vqt = tmp_path / "s.vqt"
    code, out, err = _run(capsys, "encode", *paths, "-o", vqt, "-k", "32", "--mipmaps", "--color", "rgba", "--json")
    assert code == 0, err
    rep = json.loads(out)
    ts = TextureSet.load(vqt)
    for k, t in enumerate(rep["textures"]):
        pyr = reference_pyramid(read_image(paths[k]), "rgba", True)
        assert len(t["psnr_db"]) == t["levels"]
        for level, got in enumerate(t["psnr_db"]):
            want = _psnr(decode(ts, k, level), pyr[level])
            assert (got is None and want is None) or got == pytest.approx(want, abs=1e-3), (k, level)
        assert t["psnr_db"][0] is not None and 15 < t["psnr_db"][0] < 60
        assert t["psnr_db"][-1] is None                                 # the 1x1 level is stored raw
    code, out, _ = _run(capsys, "info", vqt, "--images", *paths, "--json")
    assert code == 0 and [t["psnr_db"] for t in json.loads(out)["textures"]] == [t["psnr_db"] for t in rep["textures"]]
    code, out, _ = _run(capsys, "info", vqt, "--images", *paths)
    assert code == 0 and "PSNR against the uncompressed image" in out and "exact" in out
    code, out, _ = _run(capsys, "info", vqt, "--json")
    assert code == 0 and "psnr_db" not in out
    for argv, msg in (([paths[0]], "1 image(s) for the file's 2 textures"), ([paths[0], vqt], "s.vqt")):
        code, out, err = _run(capsys, "info", vqt, "--images", *argv)
        assert code == 2 and err.count("\n") == 1 and msg in err, err


def test_render_reference_and_difference(tmp_path, capsys):
    scene_file = tmp_path / "tiny.toml"                # bigger frames, 4 codewords: a visible error
    scene_file.write_text(TINY_SCENE.replace("size = [20, 16]", "size = [48, 40]").replace("codebook_size = 16", "codebook_size = 4"))
    code, out, err = _run(capsys, "render", scene_file, "-o", tmp_path / "f.png", "--reference", tmp_path / "ref.png",
                          "--diff", tmp_path / "d.png", "--diff-scale", "16", "--json")
    assert code == 0, err
    rep = json.loads(out)
    scene = load_scene(scene_file)
    for fr in rep["frames"]:
        n = fr["frame"]
        ref = read_image(tmp_path / f"ref_{n:04d}.png")
        assert np.array_equal(ref, render_frame(scene, n, scene.reference_source(), "trilinear"))
        frame = read_image(tmp_path / f"f_{n:04d}.png")
        assert fr["diff_max"] == int(np.abs(frame[..., :3].astype(int) - ref[..., :3]).max()) > 0
        assert fr["reference"].endswith(f"ref_{n:04d}.png") and fr["diff"].endswith(f"d_{n:04d}.png")
        heat = read_image(tmp_path / f"d_{n:04d}.png")
        assert heat.ndim == 3 and heat.shape[1] > 200                # a figure with its colour bar
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]
    code, _, err = _run(capsys, "render", scene_file, "-o", tmp_path / "x.png", "--diff-scale", "0")
    assert code == 2 and "--diff-scale: '0' is not in 1..255" in err


def test_report_cycles(tmp_path, capsys):
    img = tmp_path / "a.png"
    write_image(img, np.random.default_rng(0).integers(0, 256, (32, 32, 3)).astype(np.uint8))
    assert main(["encode", str(img), "-o", str(tmp_path / "a.vqt"), "-k", "16"]) == 0
    req = np.column_stack([np.zeros((50, 2), int), np.random.default_rng(1).integers(0, 32, (50, 2))])
    np.save(tmp_path / "r.npy", req)
    sim = _run(capsys, "sim", tmp_path / "a.vqt", tmp_path / "r.npy", "-o", tmp_path / "o.npy", "--stall", "0.3", "--json")
    code, out, err = _run(capsys, "report", "cycles", tmp_path / "a.vqt", tmp_path / "r.npy", "--stall", "0.3",
                          "--plot", tmp_path / "p.png", "--json")
    assert code == 0 and sim[0] == 0, err
    assert json.loads(out) == json.loads(sim[1])
    assert read_image(tmp_path / "p.png").shape[1] > 600
    code, out, _ = _run(capsys, "report", "cycles", tmp_path / "a.vqt", tmp_path / "r.npy")
    assert code == 0 and "texels per clock" in out


def test_missing_matplotlib_is_one_line_before_work(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "matplotlib", None)              # import matplotlib fails
    img = tmp_path / "a.png"
    write_image(img, np.zeros((32, 32, 3), np.uint8))
    assert main(["encode", str(img), "-o", str(tmp_path / "a.vqt"), "-k", "4"]) == 0
    np.save(tmp_path / "r.npy", np.zeros((4, 4), int))
    for argv in (["sim", tmp_path / "a.vqt", tmp_path / "r.npy", "-o", tmp_path / "o.npy", "--plot", tmp_path / "p.png"],
                 ["report", "cycles", tmp_path / "a.vqt", tmp_path / "r.npy", "--plot", tmp_path / "p.png"],
                 ["render", "topspin", "-o", tmp_path / "f.png", "--diff", tmp_path / "d.png"]):
        code, out, err = _run(capsys, *argv)
        assert code == 2 and out == "" and err == "vqtex: error: plots need matplotlib: pip install '.[plot]' (matplotlib)\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.png", "a.vqt", "r.npy"]
