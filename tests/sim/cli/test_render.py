"""vqtex render / demo: RTL frames equal golden frames on small scenes; scene errors are one line."""

import json

import numpy as np
import pytest

from tests.support import TINY_SCENE
from vqtex.golden.render.imageio import read_image
from vqtex.sim.cli import main


@pytest.fixture
def scene_file(tmp_path):
    p = tmp_path / "tiny.toml"
    p.write_text(TINY_SCENE)
    return p


@pytest.mark.parametrize("mode", ["point", "trilinear"])
def test_rtl_frames_identical_to_golden(tmp_path, scene_file, capsys, mode):
    out = tmp_path / "f.png"
    code = main(["render", str(scene_file), "-o", str(out), "--mode", mode, "--backend", "pysim",
                 "--stall", "0.2", "--report", str(tmp_path / "r.json"), "--json"])
    rep = json.loads(capsys.readouterr().out)
    assert code == 0 and rep["identical_to_golden"] is True
    assert [f["frame"] for f in rep["frames"]] == [0, 1]
    for f in rep["frames"]:
        assert f["cycles"] >= f["requests"] + f["latency"]
        assert f["requests"] > 0
    assert json.loads((tmp_path / "r.json").read_text()) == rep
    # and the golden backend writes the same pixels
    assert main(["render", str(scene_file), "-o", str(tmp_path / "g.png"), "--mode", mode]) == 0
    for n in (0, 1):
        assert np.array_equal(read_image(tmp_path / f"f_{n:04d}.png"), read_image(tmp_path / f"g_{n:04d}.png"))


def test_scene_errors_are_one_line(tmp_path, scene_file, capsys):
    bad = tmp_path / "bad.toml"
    cases = [TINY_SCENE.replace('size = [64, 64]', 'size = [60, 64]'),
             TINY_SCENE.replace('shape = "box"', 'shape = "teapot"'),
             TINY_SCENE + "\n[bogus]\nx = 1\n",
             "not toml [[["]
    for text in cases:
        bad.write_text(text)
        capsys.readouterr()
        assert main(["render", str(bad), "-o", str(tmp_path / "x.png")]) == 2
        err = capsys.readouterr().err
        assert err.startswith("vqtex: error:") and err.count("\n") == 1, err
        assert not (tmp_path / "x.png").exists()
    assert main(["render", "nosuchscene", "-o", str(tmp_path / "x.png")]) == 2
    assert main(["render", str(scene_file), "-o", str(tmp_path / "x.png"), "--frames", "7:9"]) == 2
    assert "selects no frame" in capsys.readouterr().err
