"""vqtex need and vqtex prune from the command line: the report and its heat maps, pruned sets that
render identical frames on golden and the compiled RTL (CXXRTL), and requests outside the need set
refused with one line and exit status 2 (vqtex sim)."""

import json

import numpy as np
import pytest

from vqtex.golden.fetch import fetch
from vqtex.golden.format import TextureSet
from vqtex.golden.need.analysis import analyse, scene_streams
from vqtex.golden.render.imageio import read_image
from vqtex.golden.render.scene import build_texture_set, builtin_scene_path, load_scene
from vqtex.sim.cli import main
from tests.support import need as need_tools

#: built-in scene -> (its size line, a small size, frames pruned for, a frame outside them)
SMALL = {"topspin": ("size = [400, 400]", "size = [64, 64]", "0:7:6", 25),
         "town": ("size = [400, 300]", "size = [64, 48]", "0:31:30", 59)}


def small_scene_file(tmp_path, name):
    old, new, _, _ = SMALL[name]
    text = builtin_scene_path(name).read_text()
    path = tmp_path / f"{name}.toml"
    path.write_text(text.replace(old, new))
    return str(path)


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def topspin_set(tmp_path_factory):
    folder = tmp_path_factory.mktemp("topspin")
    scene_file = small_scene_file(folder, "topspin")
    ts = build_texture_set(load_scene(scene_file))
    ts.save(folder / "full.vqt")
    return scene_file, ts, folder


def test_need_json_matches_golden_and_writes_heatmaps(topspin_set, capsys):
    scene_file, ts, folder = topspin_set
    code, out, err = run(capsys, "need", scene_file, "--frames", "0:3", "--texture-set", folder / "full.vqt",
                         "--heatmap", folder / "heat", "--json")
    assert code == 0, err
    rep = json.loads(out)
    scene = load_scene(scene_file)
    need = analyse(ts, scene_streams(scene, ts, [0, 1, 2]))
    expect = need.summary()
    for key in ("textures", "levels", "level_groups", "compressed_blocks", "codewords", "memory_touched", "totals"):
        assert rep[key] == expect[key], key
    assert rep["per_frame"] == expect["per_frame"]
    files = rep["heatmaps"]["files"]
    assert len(files) == int(ts.descriptors["valid"].sum())
    img = read_image(str(folder / "heat" / "t00_wood_L00.png"))
    assert img.shape[0] >= 256 and img.shape[0] % need.blocks(0, 0).shape[0] == 0
    code, out, err = run(capsys, "need", scene_file, "--heatmap", folder / "no" / "such", "--frames", "0")
    assert code == 2 and err.count("\n") == 1 and "does not exist" in err


def test_prune_renders_identical_frames_and_sim_refuses_the_rest(topspin_set, tmp_path, capsys):
    scene_file, ts, folder = topspin_set
    pruned = tmp_path / "pruned.vqt"
    code, out, err = run(capsys, "prune", folder / "full.vqt", "--scene", scene_file, "--frames", "0:7:6",
                         "-o", pruned, "--json")
    assert code == 0, err
    rep = json.loads(out)
    assert rep["after"]["memory_bytes"] < rep["before"]["memory_bytes"]
    p = TextureSet.load(pruned)
    scene = load_scene(scene_file)
    own = np.concatenate([r for _, r in scene_streams(scene, ts, [0, 6])])
    other = next(scene_streams(scene, ts, [25]))[1]
    np.save(tmp_path / "own.npy", own)
    np.save(tmp_path / "other.npy", other)
    code, out, err = run(capsys, "sim", pruned, tmp_path / "other.npy", "-o", tmp_path / "r.npy")
    assert code == 2 and err.count("\n") == 1 and "pruned from this texture set" in err, err
    assert not (tmp_path / "r.npy").exists()
    # the RTL filter fetches every texel of a footprint (zero weights too): a pruned set is refused
    code, out, err = run(capsys, "render", scene_file, "--frames", "0", "--texture-set", pruned, "--filter-in-rtl",
                         "-o", tmp_path / "f.png")
    assert code == 2 and err.count("\n") == 1 and "is pruned" in err, err
    assert not (tmp_path / "f.png").exists()
    need_tools("g++")
    code, out, err = run(capsys, "sim", pruned, tmp_path / "own.npy", "-o", tmp_path / "r.npy", "--backend", "cxxrtl")
    assert code == 0, err
    assert np.array_equal(np.load(tmp_path / "r.npy"), fetch(ts, *own.T))


@pytest.mark.parametrize("name", sorted(SMALL))
def test_pruned_frames_identical_on_golden_and_cxxrtl(name, tmp_path, capsys):
    need_tools("g++")
    scene_file = small_scene_file(tmp_path, name)
    frames = SMALL[name][2]
    assert run(capsys, "render", scene_file, "--frames", frames, "-o", tmp_path / "full.png")[0] == 0
    ts = build_texture_set(load_scene(scene_file))
    ts.save(tmp_path / "full.vqt")
    code, out, err = run(capsys, "prune", tmp_path / "full.vqt", "--scene", scene_file, "--frames", frames,
                         "-o", tmp_path / "p.vqt")
    assert code == 0, err
    code, out, err = run(capsys, "render", scene_file, "--frames", frames, "--texture-set", tmp_path / "p.vqt",
                         "--backend", "cxxrtl", "-o", tmp_path / "pruned.png")
    assert code == 0 and "identical to golden: yes" in out, err
    for f in range(*(int(x) for x in frames.split(":"))):
        assert np.array_equal(read_image(str(tmp_path / f"pruned_{f:04d}.png")),
                              read_image(str(tmp_path / f"full_{f:04d}.png"))), (name, f)
    other = str(SMALL[name][3])
    code, out, err = run(capsys, "render", scene_file, "--frames", other, "--texture-set", tmp_path / "p.vqt",
                         "-o", tmp_path / "x.png")
    assert code == 2 and err.count("\n") == 1 and "pruned from this texture set" in err


def test_render_encode_needed_and_prune_without_a_set(topspin_set, tmp_path, capsys):
    scene_file, ts, folder = topspin_set
    code, out, err = run(capsys, "render", scene_file, "--frames", "3", "--encode-needed", "-o", tmp_path / "f.png",
                         "--report", tmp_path / "r.json")
    assert code == 0, err
    rep = json.loads((tmp_path / "r.json").read_text())
    assert rep["frames"][0]["need"]["requests"] == rep["frames"][0]["requests"] > 0
    assert rep["need"]["levels"]["touched"] == rep["need"]["levels"]["stored"]      # only what frame 3 reads
    code, out, err = run(capsys, "prune", "--scene", scene_file, "--frames", "3", "-o", tmp_path / "n.vqt",
                         "--compare", "--json")
    assert code == 0, err
    r = json.loads(out)
    assert r["after"]["levels"] < r["before"]["levels"] and "full_encode_seconds" in r and "encode_seconds" in r
    code, out, err = run(capsys, "prune", folder / "full.vqt", "--scene", scene_file, "--compare", "-o",
                         tmp_path / "x.vqt")
    assert code == 2 and err.count("\n") == 1 and not (tmp_path / "x.vqt").exists()


def test_need_of_the_fixed_and_sparse_streams(topspin_set, capsys):
    scene_file, ts, folder = topspin_set
    reps = {}
    for stream in ("sparse", "fixed"):
        code, out, err = run(capsys, "need", scene_file, "--frames", "2", "--texture-set", folder / "full.vqt",
                             "--requests", stream, "--json")
        assert code == 0, err
        reps[stream] = json.loads(out)
    scene = load_scene(scene_file)
    fixed = analyse(ts, scene_streams(scene, ts, [2], stream="fixed")).summary()
    assert reps["fixed"]["totals"] == fixed["totals"]
    assert reps["sparse"]["totals"]["requests"] < reps["fixed"]["totals"]["requests"]
    assert reps["sparse"]["levels"]["touched"] <= reps["fixed"]["levels"]["touched"]
