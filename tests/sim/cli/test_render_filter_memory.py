"""vqtex render --filter-in-rtl --memory external: the texture filter's lanes through the memory
system render golden's frames, and the golden cycle model and pysim report the same cycles and
bytes; the combinations it does not serve are one line, exit 2."""

import json

import pytest

from tests.support import TINY_SCENE, assert_one_error
from vqtex.sim.cli import main

#: test_render_filter's scene: the tiny scene with a mirrored axis, and smaller (pysim runs every cycle).
MIRRORED = TINY_SCENE.replace('address = "clamp"', 'address = ["mirror", "clamp"]').replace("size = [20, 16]",
                                                                                             "size = [12, 10]")
SMALL = ["--memory", "external", "--cache-size", "256", "--raw-cache-size", "128", "--cache-line", "16",
         "--cache-ways", "2", "--prefetch", "4", "--memory-latency", "30"]


@pytest.fixture
def scene_file(tmp_path):
    p = tmp_path / "tiny.toml"
    p.write_text(MIRRORED)
    return p


@pytest.mark.parametrize("stall", [[], ["--stall", "0.5", "--stall-seed", "3"]])
def test_golden_and_pysim_agree(tmp_path, scene_file, capsys, stall):
    reps = {}
    for backend in ("golden", "pysim"):
        code = main(["render", str(scene_file), "-o", str(tmp_path / f"{backend}.png"), "--frames", "0",
                     "--mode", "bilinear", "--filter-in-rtl", "--backend", backend, *SMALL, *stall, "--json"])
        reps[backend] = json.loads(capsys.readouterr().out)
        assert code == 0 and reps[backend]["identical_to_golden"] is True
    g, p = reps["golden"]["frames"][0], reps["pysim"]["frames"][0]
    assert g["cycles"] == p["cycles"] > g["pixels"] + 29
    assert g["memory"]["memory_bytes"] == p["memory"]["memory_bytes"]
    assert g["memory"]["fill_waits"] == p["memory"]["fill_waits"] > 0
    assert reps["golden"]["memory"]["bytes_per_pixel"] == reps["pysim"]["memory"]["bytes_per_pixel"] > 0
    assert reps["golden"]["memory"]["on_chip_pixels_per_clock"] > reps["golden"]["pixels_per_clock"]
    assert g["stall_cycles"] == p["stall_cycles"]
    assert (g["stall_cycles"]["output_backpressure"] > 0) == bool(stall)


@pytest.mark.parametrize("extra,pattern", [
    (["--index-banks", "lane"], "not with --index-banks"),
    (["--fovea", "10,10", "--mode", "bilinear"], "not with --fovea"),
])
def test_refused(tmp_path, scene_file, capsys, extra, pattern):
    assert_one_error(capsys, ["render", str(scene_file), "-o", str(tmp_path / "x.png"), "--frames", "0",
                              "--filter-in-rtl", *SMALL, *extra], pattern)
    assert not (tmp_path / "x.png").exists()


def test_loadable_filter_golden_and_pysim_agree(tmp_path, scene_file, capsys):
    """--unit loadable: the loadable filter through memory, the set loaded over its bus; the same
    frame and cycles as the baked filter's model (the set at Layout.of), and the load's cycles."""
    reps = {}
    for backend, unit in (("golden", []), ("golden", ["--unit", "loadable"]), ("pysim", ["--unit", "loadable"])):
        code = main(["render", str(scene_file), "-o", str(tmp_path / f"{backend}.png"), "--frames", "0",
                     "--mode", "bilinear", "--filter-in-rtl", "--backend", backend, *SMALL, *unit, "--json"])
        out = capsys.readouterr().out
        reps[backend, bool(unit)] = json.loads(out)
        assert code == 0 and reps[backend, bool(unit)]["identical_to_golden"] is True
    baked, g, p = (reps[k]["frames"][0] for k in (("golden", False), ("golden", True), ("pysim", True)))
    assert g["cycles"] == p["cycles"] == baked["cycles"]
    assert g["memory"]["memory_bytes"] == p["memory"]["memory_bytes"]
    assert g["memory"]["fill_waits"] == p["memory"]["fill_waits"] > 0
    assert g["load_cycles"] == p["load_cycles"] > 0 and "load_cycles" not in baked
    assert reps["pysim", True]["unit"] == "loadable"


def test_loadable_filter_refuses_full_unit(tmp_path, scene_file, capsys):
    assert_one_error(capsys, ["render", str(scene_file), "-o", str(tmp_path / "x.png"), "--frames", "0",
                              "--filter-in-rtl", "--backend", "pysim", *SMALL, "--unit", "full"], "not with --unit full")
