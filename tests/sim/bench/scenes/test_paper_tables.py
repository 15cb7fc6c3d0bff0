"""The paper's Tables 3 and 4 row for row: the configurations are the paper's, the paper-sized scenes
have the paper's texture budgets, and the table commands run (on reduced frame counts and row
lists: the full tables are the long runs of docs/experiments.md)."""

import importlib.util
import json

import pytest

from tests.support.scenes import TINY_TOPSPIN, TINY_TOWN, tiny_scene
from vqtex.golden.render.scene import DATA_DIR, PAPER_SCENES, load_scene
from vqtex.sim.bench.scenes import experiments, paper_configs
from vqtex.sim.bench.scenes.paper_configs import Codebook
from vqtex.sim.cli import main

BYTES = {"rgb": 3, "yuv411": 3, "intensity": 1, "rgba": 4}


def _table(rows):
    """(sampling, [(groups, K, block, colour, separate)]) per row."""
    return [(r.sampling, [(c.groups, c.codebook_size, c.block, c.color, c.separate) for c in r.codebooks])
            for r in rows]


def test_table3_rows_are_the_papers_town_configurations():
    rgb, rest = ("signs", "roads", "other"), [(("grey",), 256, "2x2", "intensity", False),
                                               (("cutouts",), 256, "2x2", "rgba", False)]
    assert paper_configs.TABLE3_SCENE == "town-paper"
    assert _table(paper_configs.TABLE3_PAPER) == [
        ("trilinear", [(rgb, 4096, "4x4", "rgb", False)] + rest),
        ("trilinear", [(rgb, 4096, "4x4", "yuv411", False)] + rest),
        ("trilinear", [(("signs", "roads"), 256, "2x2", "yuv411", False), (("other",), 4096, "4x4", "yuv411", False)]
         + rest),
        ("trilinear", [(("signs",), 256, "2x2", "yuv411", False), (("roads", "other"), 256, "4x4", "yuv411", False)]
         + rest),
    ]
    assert [r.paper for r in paper_configs.TABLE3_PAPER] == [(11.8, 12.12), (15.3, 16.17), (12.7, 11.27), (24.5, 16.19)]


def test_table4_rows_are_the_papers_topspin_configurations():
    top = ("floor", "marble", "top")
    assert paper_configs.TABLE4_SCENE == "topspin-paper"
    assert _table(paper_configs.TABLE4_PAPER) == [
        ("point", [(("floor", "marble"), 128, "4x4", "yuv411", False), (("top",), 128, "2x2", "yuv411", False)]),
        ("point", [(("floor", "marble"), 256, "4x4", "yuv411", False), (("top",), 256, "2x2", "yuv411", False)]),
        ("point", [(top, 256, "2x2", "yuv411", False)]),
        ("trilinear", [(top, 256, "4x4", "rgb", True)]),
        ("trilinear", [(top, 1024, "4x4", "rgb", True)]),
    ]
    assert [r.paper for r in paper_configs.TABLE4_PAPER] == [(34.7, 34.7), (28.3, 19.1), (11.5, 37.9), (17.6, 14.2),
                                                             (8.0, 13.3)]


@pytest.mark.parametrize("rows, scene", [(paper_configs.TABLE3_PAPER + paper_configs.TABLE3_OURS, "town-paper"),
                                         (paper_configs.TABLE4_PAPER + paper_configs.TABLE4_OURS, "topspin-paper")])
def test_every_row_covers_every_texture_once(rows, scene):
    s = load_scene(scene)
    groups = {t.group for t in s.textures}
    for r in rows:
        served = [g for c in r.codebooks for g in c.groups]
        assert sorted(served) == sorted(groups), r.label
    ours = {(r.sampling, r.codebooks) for r in rows if r.paper is None}
    assert not ours & {(r.sampling, r.codebooks) for r in rows if r.paper is not None}   # no row twice


def test_paper_scenes_have_the_papers_texture_budgets():
    top = load_scene("topspin-paper")
    assert len(top.textures) == 3
    assert sum(w * h * 3 for w, h in (t.size for t in top.textures)) == 1_376_256          # the paper's 1.4 MB
    town = load_scene("town-paper")
    colors = [t.color for t in town.textures]
    assert (len(colors), colors.count("intensity"), colors.count("rgba")) == (85, 14, 7)
    total = sum(t.size[0] * t.size[1] * BYTES[t.color] for t in town.textures)
    assert total == 5_001_216 and abs(total - 5e6) / 5e6 < 0.001                          # the paper's 5 MB
    for s in (top, town):
        assert {m.texture for m in s.meshes} == {t.id for t in s.textures}                 # every texture seen
    # the small scenes the demo and the other benchmarks use are untouched
    assert sum(t.size[0] * t.size[1] for t in load_scene("topspin").textures) == 256 * 256 * 2 + 256 * 128
    assert len(load_scene("town").textures) == 22
    assert set(PAPER_SCENES) == {"topspin-paper", "town-paper"}


def test_town_paper_file_is_what_its_script_writes():
    spec = importlib.util.spec_from_file_location("make_town_paper", DATA_DIR / "make_town_paper.py")
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    assert (DATA_DIR / "town-paper.toml").read_text() == script.scene_text()


def test_topspin_paper_point_rates_are_the_papers():
    """The rate depends only on sizes, K and index widths, so the paper-sized topspin reproduces the
    paper's point-sampled rates (row 1: 34.7:1) to within 0.1 %."""
    s = load_scene("topspin-paper")
    images = [img for img, _ in s.load_textures()]
    for row in paper_configs.TABLE4_PAPER[:1]:
        ts, ids = experiments.encode_config(s, images, row.codebooks, row.mipmaps)
        assert sorted(ids) == [0, 1, 2]
        assert abs(ts.rates()["overall"] / row.paper[0] - 1) < 1e-3, row.label
        assert experiments.rate_level0(ts) == pytest.approx(ts.rates()["overall"])       # no mipmaps


def test_encode_config_rejects_a_configuration_that_leaves_a_texture_out():
    s = load_scene("topspin")
    images = [img for img, _ in s.load_textures()]
    with pytest.raises(ValueError, match="missing"):
        experiments.encode_config(s, images, (Codebook(("floor", "marble"), 16, "4x4", "rgb"),), False)


@pytest.fixture
def tiny_town(tmp_path):
    return tiny_scene(tmp_path, "tiny-town", TINY_TOWN)


@pytest.fixture
def tiny_topspin(tmp_path):
    return tiny_scene(tmp_path, "tiny-topspin", TINY_TOPSPIN)


FIELDS = {"row", "source", "label", "codebooks", "sampling", "n_codebooks", "overall_rate", "rate_level0", "mse",
          "paper_rate", "paper_mse", "frames", "encode_seconds", "render_seconds"}


def _small(monkeypatch, name, paper_rows, own_rows):
    monkeypatch.setattr(paper_configs, f"{name}_PAPER", paper_rows)
    monkeypatch.setattr(paper_configs, f"{name}_OURS", own_rows)


def test_table4_command_on_one_frame(monkeypatch, capsys, tiny_topspin):
    """The command a user runs, on one frame of a tiny topspin (its three groups, 64x64 textures),
    with the paper's first row and one of ours (the whole table is the long run)."""
    own = (paper_configs.Row("separate 16 4x4 RGB, point", "point",
                             (Codebook(("floor", "marble", "top"), 16, "4x4", "rgb", separate=True),)),)
    _small(monkeypatch, "TABLE4", paper_configs.TABLE4_PAPER[:1], own)
    assert main(["experiments", "table4", "--scene", tiny_topspin, "--frames", "1", "--scheduler", "serial",
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["frames"] == [1] and out["table"] == "table4"
    paper, ours = out["rows"]
    assert set(paper) == FIELDS and set(ours) == FIELDS
    assert (paper["row"], paper["source"], paper["paper_rate"], paper["paper_mse"]) == (1, "paper", 34.7, 34.7)
    assert (ours["row"], ours["source"], ours["paper_rate"], ours["n_codebooks"]) == (2, "ours", None, 3)
    assert paper["frames"] == 1 and paper["mse"] > 0 and paper["overall_rate"] > 1
    assert ours["mse"] > paper["mse"]                     # 16 RGB codewords against 128 YUV ones


def test_table3_command_on_one_frame(monkeypatch, capsys, tiny_town):
    """Table 3's last paper row (256-codeword codebooks) on one frame of a tiny town (its five
    groups), in text."""
    _small(monkeypatch, "TABLE3", paper_configs.TABLE3_PAPER[3:], ())
    assert main(["experiments", "table3", "--scene", tiny_town, "--frames", "2", "--scheduler", "serial"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == 2 and lines[0].split()[:3] == ["row", "source", "label"]
    assert "24.5" in lines[1] and "16.19" in lines[1] and "mipmap" in lines[1]


def test_table_rows_equal_on_dask_and_serially(monkeypatch, tiny_topspin):
    """Two cheap rows as a sweep on a two-worker LocalCluster give the serial results (times apart)."""
    rows = (paper_configs.Row("a", "point", (Codebook(("floor", "marble", "top"), 8, "4x4", "rgb"),)),
            paper_configs.Row("b", "point", (Codebook(("floor", "marble", "top"), 8, "2x2", "rgb", separate=True),)))
    _small(monkeypatch, "TABLE4", rows, ())
    run = lambda **sweep: experiments.table4(frames=[0], own=False, scene=tiny_topspin, sweep=sweep)  # noqa: E731
    serial = run(scheduler="serial", progress=False)
    dask = run(scheduler=None, workers=2, progress=False)
    strip = lambda rs: [{k: v for k, v in r.items() if not k.endswith("_seconds")} for r in rs]  # noqa: E731
    assert strip(dask) == strip(serial) and len(serial) == 2
