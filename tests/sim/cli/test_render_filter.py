"""vqtex render --filter-in-rtl: the texture filter in the RTL renders frames equal to golden's, pixel
for pixel, in point, bilinear and trilinear mode (with mirror addressing), on pysim and CXXRTL."""

import json

import numpy as np
import pytest

from tests.support import TINY_SCENE
from tests.support import need, shared_cache
from vqtex.golden.render.imageio import read_image
from vqtex.sim.cli import main

#: The tiny scene with a mirrored axis, and smaller (pysim runs every cycle in Python).
MIRRORED = TINY_SCENE.replace('address = "clamp"', 'address = ["mirror", "clamp"]').replace("size = [20, 16]",
                                                                                       "size = [12, 10]")


@pytest.fixture
def scene_file(tmp_path):
    p = tmp_path / "tiny.toml"
    p.write_text(MIRRORED)
    return p


@pytest.fixture
def cache():
    with shared_cache():
        yield


def _render(tmp_path, scene_file, capsys, mode, *extra):
    out = tmp_path / f"{mode}.png"
    code = main(["render", str(scene_file), "-o", str(out), "--mode", mode, "--filter-in-rtl", "--json", *extra])
    rep = json.loads(capsys.readouterr().out)
    assert code == 0 and rep["identical_to_golden"] is True and rep["filter_in_rtl"] is True
    # the golden renderer (texel requests, numpy filtering) writes the same pixels
    assert main(["render", str(scene_file), "-o", str(tmp_path / "g.png"), "--mode", mode]) == 0
    capsys.readouterr()
    for n in (0, 1):
        assert np.array_equal(read_image(tmp_path / f"{mode}_{n:04d}.png"), read_image(tmp_path / f"g_{n:04d}.png"))
    return rep


@pytest.mark.parametrize("mode", ["point", "bilinear", "trilinear"])
def test_pysim_filter_frames_identical_to_golden(tmp_path, scene_file, capsys, mode):
    rep = _render(tmp_path, scene_file, capsys, mode, "--backend", "pysim", "--lanes", "4", "--stall", "0.2")
    for f in rep["frames"]:
        assert f["pixels"] > 0 and f["lanes"] == 4
        assert f["cycles"] >= f["pixels"] * (2 if mode == "trilinear" else 1) + f["latency"]
        assert f["stall_cycles"]["output_backpressure"] > 0 and f["bank_conflicts"] == 0


@pytest.mark.parametrize("mode,lanes", [("point", 4), ("bilinear", 4), ("trilinear", 4)])
def test_cxxrtl_filter_frames_identical_to_golden(tmp_path, scene_file, capsys, cache, mode, lanes):
    need("g++")
    rep = _render(tmp_path, scene_file, capsys, mode, "--backend", "cxxrtl", "--lanes", str(lanes))
    per_pixel = {"point": 1, "bilinear": 1, "trilinear": 2}[mode]
    for f in rep["frames"]:
        assert f["cycles"] == f["pixels"] * per_pixel + f["latency"]
    # the filter is elaborated and built once, before the first frame: its set-up is reported there
    assert [f["rtl_setup_seconds"] > 0 for f in rep["frames"] if "rtl_setup_seconds" in f] == [True]
    assert "rtl_setup_seconds" in rep["frames"][0]
    assert rep["pixels_per_clock"] > 0


def test_cxxrtl_filter_with_an_index_memory_per_lane(tmp_path, scene_file, capsys, cache):
    """--index-banks lane: every lane its own index memory; the same frames and cycles as the banked one."""
    need("g++")
    banked = _render(tmp_path, scene_file, capsys, "bilinear", "--backend", "cxxrtl", "--lanes", "2")
    per_lane = _render(tmp_path, scene_file, capsys, "bilinear", "--backend", "cxxrtl", "--lanes", "2",
                       "--index-banks", "lane")
    assert banked["index_banks"] == "parity" and per_lane["index_banks"] == "lane"
    assert [f["cycles"] for f in banked["frames"]] == [f["cycles"] for f in per_lane["frames"]]
    assert all(f["bank_conflicts"] == 0 for f in banked["frames"] + per_lane["frames"])


def test_filter_in_rtl_refuses_what_it_cannot_do(tmp_path, scene_file, capsys):
    for extra in (["--backend", "pysim", "--one-port"], ["--backend", "nosuch"], ["--compare-fixed"],
                  ["--encode-needed"]):
        assert main(["render", str(scene_file), "-o", str(tmp_path / "x.png"), "--filter-in-rtl", *extra]) == 2
        err = capsys.readouterr().err
        assert err.startswith("vqtex: error:") and err.count("\n") == 1
        assert not (tmp_path / "x.png").exists()


@pytest.mark.parametrize("stream", ["sparse", "fixed"])
def test_filter_in_rtl_samples_the_foveated_lod(tmp_path, scene_file, capsys, stream):
    """--fovea with --filter-in-rtl: the filter is given the biased level of detail, and its frames are
    the golden sampler's (either request stream) pixel for pixel; the periphery differs from unbiased."""
    fov = ["--fovea", "0,0", "--fovea-radius", "1", "--fovea-falloff", "2"]
    code = main(["render", str(scene_file), "-o", str(tmp_path / "r.png"), "--mode", "bilinear", "--filter-in-rtl",
                 "--requests", stream, "--json", *fov])
    rep = json.loads(capsys.readouterr().out)
    assert code == 0 and rep["identical_to_golden"] is True and rep["request_stream"] == stream
    assert rep["fovea"]["periphery"]["identical"] is False        # the bias changed the periphery
    assert main(["render", str(scene_file), "-o", str(tmp_path / "f.png"), "--mode", "bilinear", *fov]) == 0
    assert main(["render", str(scene_file), "-o", str(tmp_path / "u.png"), "--mode", "bilinear"]) == 0
    capsys.readouterr()
    for n in (0, 1):
        rtl = read_image(tmp_path / f"r_{n:04d}.png")
        assert np.array_equal(rtl, read_image(tmp_path / f"f_{n:04d}.png"))
    assert not np.array_equal(rtl, read_image(tmp_path / "u_0001.png"))


@pytest.mark.parametrize("lanes,banks", [("1", "parity"), ("4", "parity")])
def test_export_filter_verilog_lint_clean(tmp_path, capsys, lanes, banks):
    """vqtex export --filter-lanes: the filter's SystemVerilog (one lane; four lanes sharing the
    banked index memory), Verilator lint clean with the export's waivers; its ports are the whole
    payloads and the strobes."""
    need("verilator")
    from tests.support import filter_set
    vqt = tmp_path / "set.vqt"
    filter_set().save(str(vqt))
    out = tmp_path / "tf.sv"
    assert main(["export", str(vqt), "-o", str(out), "--filter-lanes", lanes, "--index-banks", banks, "--lint",
                 "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["module"] == "texture_filter" and rep["latency"] == 24 and rep["lint"] == "clean"
    assert rep["index_banks"] == banks
    assert set(rep["ports"]) == {"i_valid", "i_ready", "i_payload", "o_valid", "o_ready", "o_payload",
                                 "stall_output", "busy", "bank_conflict"}
    assert "module texture_filter" in out.read_text()
    assert main(["export", str(vqt), "-o", str(tmp_path / "x.v"), "--filter-lanes", "1", "--one-port"]) == 2
    assert not (tmp_path / "x.v").exists()
