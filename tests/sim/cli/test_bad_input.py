"""Bad input and doubtful input through the command line: errors are one line with exit 2, warnings
one line each with exit 0; the build cache commands and its size bound."""

import json
import os

import numpy as np
import pytest

from tests.support import TINY_SCENE
from vqtex.golden.render.imageio import write_image
from vqtex.sim.backends import toolchain
from vqtex.sim.cli import main
from tests.support import run_cli as _run, assert_one_error as _one_error


def _warnings(err):
    lines = err.splitlines()
    assert all(ln.startswith("vqtex: warning: ") for ln in lines), err
    return lines


@pytest.fixture
def vqt(tmp_path):
    img = tmp_path / "a.png"
    write_image(img, np.random.default_rng(0).integers(0, 256, (32, 32, 3)).astype(np.uint8))
    assert main(["encode", str(img), "-o", str(tmp_path / "a.vqt"), "-k", "16"]) == 0
    return tmp_path / "a.vqt"


def test_experiments_frame_selection(capsys, monkeypatch):
    _one_error(capsys, ["experiments", "table3", "--frame-step", "0"], "argument --frame-step: '0' is not in 1..2^31 - 1")
    _one_error(capsys, ["experiments", "table4", "--frame-step", "-2"], "argument --frame-step: '-2' is not in 1..")
    _one_error(capsys, ["experiments", "table5", "--frames", "::0"], "step must not be 0")
    _one_error(capsys, ["experiments", "table5", "--frames", "60:70"], "selects no frame")
    _one_error(capsys, ["experiments", "table3", "--frames", "0:5", "--frame-step", "2"], "not both")
    from vqtex.sim.bench.scenes import experiments
    seen = {}
    for table in ("table3", "table4", "table5"):
        monkeypatch.setattr(experiments, table, lambda table=table, **kw: seen.setdefault(table, kw) and [])
    for argv, table, frames in ((["--frame-step", "20"], "table5", (0, 20, 40)), ([], "table5", (0, 25)),
                                (["--frames", "0:60:20"], "table3", [0, 20, 40]), ([], "table4", None)):
        seen.clear()
        code, out, err = _run(capsys, "experiments", table, *argv, "--json")
        assert code == 0, err
        assert json.loads(out)["frames"] == list(seen[table]["frames"])
        if frames is not None:
            assert seen[table]["frames"] == frames
    assert "frames 60:70" not in err


def test_library_frame_step_checked():
    from vqtex.golden.render.scene import load_scene
    from vqtex.sim.bench.scenes.experiments import table4
    with pytest.raises(ValueError, match="at least 1"):
        table4(frame_step=0)
    assert load_scene("town").frames >= 1


def test_request_files(tmp_path, vqt, capsys):
    out = tmp_path / "o.npy"
    (tmp_path / "empty.csv").write_text("")
    (tmp_path / "header.csv").write_text("texture,level,i,j\n")
    (tmp_path / "text.npy").write_text("0,0,1,1\n")
    np.save(tmp_path / "objects.npy", np.array([{"a": 1}], dtype=object))
    np.save(tmp_path / "none.npy", np.zeros((0, 4), np.int64))
    (tmp_path / "junk.vqt").write_bytes(b"not a texture set at all" * 10)
    for name, pattern in (("empty.csv", "no requests"), ("header.csv", "no requests"),
                          ("text.npy", "not an .npy file"), ("objects.npy", "not an integer request array of shape (N, 4)"),
                          ("none.npy", "no requests")):
        _one_error(capsys, ["sim", vqt, tmp_path / name, "-o", out], f"{tmp_path / name}: {pattern}")
    _one_error(capsys, ["sim", tmp_path / "junk.vqt", tmp_path / "header.csv", "-o", out], "junk.vqt")
    _one_error(capsys, ["info", tmp_path / "junk.vqt"], "junk.vqt")
    assert not out.exists()


def test_encode_warnings(tmp_path, capsys):
    rgba = np.random.default_rng(1).integers(0, 256, (32, 32, 4)).astype(np.uint8)
    write_image(tmp_path / "rgba.png", rgba)
    code, _, err = _run(capsys, "encode", tmp_path / "rgba.png", "-o", tmp_path / "o.vqt", "-k", "16")
    assert code == 0 and _warnings(err) == [
        "vqtex: warning: --color rgb drops the alpha channel of " + str(tmp_path / "rgba.png")
        + " (use --color rgba to keep it)"]
    code, _, err = _run(capsys, "encode", tmp_path / "rgba.png", "-o", tmp_path / "o.vqt", "-k", "16", "--color", "rgba")
    assert code == 0 and err == ""
    opaque = rgba.copy()
    opaque[..., 3] = 255                                   # nothing is lost: no warning
    write_image(tmp_path / "opaque.png", opaque)
    assert _run(capsys, "encode", tmp_path / "opaque.png", "-o", tmp_path / "o.vqt", "-k", "16")[2] == ""
    code, _, err = _run(capsys, "encode", tmp_path / "opaque.png", "-o", tmp_path / "o.vqt", "-k", "256")
    lines = _warnings(err)
    assert code == 0 and len(lines) == 2
    assert "256 codewords for 64 blocks" in lines[0] and "below 1:1" in lines[1]
    from vqtex.golden.format import TextureSet
    assert TextureSet.load(tmp_path / "o.vqt").rates()["overall"] < 1


def test_frames_beyond_the_animation_warn_and_clamp(tmp_path, capsys):
    scene = tmp_path / "tiny.toml"
    scene.write_text(TINY_SCENE)
    code, out, err = _run(capsys, "render", scene, "-o", tmp_path / "f.png", "--frames", "1:9", "--json")
    assert code == 0
    assert _warnings(err) == ["vqtex: warning: --frames 1:9: the scene has 2 frames (0..1); rendering 1 of them"]
    assert [f["frame"] for f in json.loads(out)["frames"]] == [1]
    assert sorted(os.listdir(tmp_path)) == ["f.png", "tiny.toml"]
    code, out, err = _run(capsys, "render", scene, "-o", tmp_path / "g.png", "--frames", "0:2")
    assert code == 0 and err == ""


def test_pysim_on_a_big_trace_warns(tmp_path, vqt, capsys, monkeypatch):
    """pysim would take minutes: the warning comes before the run (here answered by the golden
    backend instead, so the test does not take those minutes)."""
    from vqtex.sim.backends import interface
    real = interface.simulate
    calls = []

    def golden_instead(ts, req, backend, **kw):
        calls.append(backend)
        return real(ts, req, backend="golden", **kw)
    monkeypatch.setattr(interface, "simulate", golden_instead)
    rng = np.random.default_rng(0)
    n = 200_000
    np.save(tmp_path / "big.npy", np.column_stack([np.zeros((n, 2), int), rng.integers(0, 32, (n, 2))]))
    np.save(tmp_path / "small.npy", np.zeros((10, 4), int))
    code, _, err = _run(capsys, "sim", vqt, tmp_path / "big.npy", "-o", tmp_path / "o.npy", "--backend", "pysim")
    assert code == 0 and calls == ["pysim"]
    assert _warnings(err) == ["vqtex: warning: pysim simulates about 2000 cycles/s: 200000 requests take about "
                              "2 minutes (--backend cxxrtl takes seconds)"]
    code, _, err = _run(capsys, "sim", vqt, tmp_path / "small.npy", "-o", tmp_path / "o.npy", "--backend", "pysim")
    assert code == 0 and err == ""


def _fake_build(kind, key, size):
    def build(folder):
        with open(os.path.join(folder, "libvq.so"), "wb") as f:
            f.write(b"x" * size)
    return toolchain.cached_build(kind, key, build, "libvq.so")[0]


def test_cache_bound_evicts_least_recently_used(tmp_path, monkeypatch):
    monkeypatch.setenv("VQTEX_CACHE", str(tmp_path))
    monkeypatch.setenv("VQTEX_CACHE_MAX_MB", "0.25")          # 262144 bytes: two 100 kB entries fit
    paths = [_fake_build("cxxrtl", f"k{n}", 100_000) for n in range(2)]
    for n, p in enumerate(paths):
        os.utime(os.path.dirname(p), (1000 + n, 1000 + n))      # k0 used before k1
    _fake_build("cxxrtl", "k0", 100_000)                        # a hit: k0 is now the most recent
    _fake_build("verilator", "k2", 100_000)                      # over the bound: k1 goes
    assert sorted(e["key"] for e in toolchain.cache_entries()) == ["k0", "k2"]
    assert not [n for n in os.listdir(tmp_path / "cxxrtl") if n.startswith(".")]
    _fake_build("cxxrtl", "big", 400_000)                        # bigger than the bound: kept, others go
    assert [e["key"] for e in toolchain.cache_entries()] == ["big"]
    monkeypatch.setenv("VQTEX_CACHE_MAX_MB", "lots")
    with pytest.raises(toolchain.ToolchainError, match="VQTEX_CACHE_MAX_MB"):
        toolchain.cache_max_bytes()


def test_cache_info_and_clean(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("VQTEX_CACHE", str(tmp_path))
    monkeypatch.setenv("VQTEX_CACHE_MAX_MB", "0")
    for n in range(3):
        os.utime(os.path.dirname(_fake_build("cxxrtl", f"k{n}", 50_000)), (1000 + n, 1000 + n))
    _fake_build("verilator", "v", 70_000)
    toolchain.index_put("cxxrtl", "quick", "k0")
    code, out, _ = _run(capsys, "cache", "info", "--json")
    rep = json.loads(out)
    assert code == 0 and rep["entries"] == 4 and rep["bytes"] == 220_000 and rep["max_bytes"] == 0
    assert rep["kinds"] == {"cxxrtl": {"entries": 3, "bytes": 150_000}, "verilator": {"entries": 1, "bytes": 70_000}}
    code, out, _ = _run(capsys, "cache", "info")
    assert code == 0 and "4 builds" in out and "no bound" in out
    code, out, _ = _run(capsys, "cache", "clean", "--keep-mb", "0.1", "--json")   # 104857 bytes
    rep = json.loads(out)
    assert code == 0 and rep == {"removed": 3, "freed_bytes": 150_000, "bytes_left": 70_000}   # the oldest go first
    assert [e["key"] for e in toolchain.cache_entries()] == ["v"]
    code, out, _ = _run(capsys, "cache", "clean")
    assert code == 0 and "freed" in out
    assert toolchain.cache_entries() == [] and not (tmp_path / "index").exists()
    _one_error(capsys, ["cache", "clean", "--keep-mb", "-1"], "argument --keep-mb: '-1' is not in [0, 2^43] MB")
    _one_error(capsys, ["cache", "purge"], "invalid choice")
