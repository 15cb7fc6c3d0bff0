"""``--unit loadable --geometry NAME|FILE`` on ``sim``, ``render``, ``demo``, ``export`` and ``report
area``: the set loaded over the bus port, frames identical to golden, one CXXRTL build per geometry
for topspin, town and a .dt scene; export writes no texture data but the register map and C header;
what does not fit is refused in one line."""

from __future__ import annotations

import json
import os
import subprocess

import numpy as np
import pytest

from tests.support import (assert_one_error, need, need_synth_tools, random_requests, run_cli, shared_cache,
                           texture_set)
from vqtex.golden.fetch import fetch
from vqtex.golden.geometry import PRESETS, Geometry
from vqtex.golden.register_map import load_cycles, load_writes

from tests.support import crates_scene


@pytest.fixture(scope="module", autouse=True)
def cache():
    with shared_cache():
        yield


@pytest.fixture
def rgb8(tmp_path):
    path = tmp_path / "rgb8.vqt"
    texture_set("rgb_4x4_b8_mip").save(path)
    return path


@pytest.mark.parametrize("backend,geometry", [("pysim", None), ("cxxrtl", "paper")])
def test_sim_loadable(tmp_path, rgb8, capsys, backend, geometry):
    need("g++")
    ts = texture_set("rgb_4x4_b8_mip")
    req = random_requests(ts, 300 if backend == "cxxrtl" else 40, seed=2)
    np.save(tmp_path / "req.npy", req)
    argv = ["sim", rgb8, tmp_path / "req.npy", "-o", tmp_path / "r.npy", "--backend", backend, "--unit", "loadable",
            "--stall", "0.2", "--json"] + (["--geometry", geometry] if geometry else [])
    code, out, err = run_cli(capsys, *argv)
    assert code == 0, err
    rep = json.loads(out)
    g = PRESETS[geometry] if geometry else Geometry.of(ts)
    assert rep["unit"] == "loadable" and rep["load_cycles"] == load_cycles(len(load_writes(ts, g)))
    assert np.array_equal(np.load(tmp_path / "r.npy"), fetch(ts, *req.T))


def test_refusals(tmp_path, rgb8, capsys):
    req = tmp_path / "req.npy"
    np.save(req, random_requests(texture_set("rgb_4x4_b8_mip"), 5))
    small = tmp_path / "small.toml"
    g = Geometry.of(texture_set("rgb_4x4_b8_mip"))
    small.write_text(Geometry(**{**g.to_dict(), "index_words": 4, "colors": ["yuv411"]}).dumps())
    base = ["sim", rgb8, req, "-o", tmp_path / "r.npy", "--backend", "pysim"]
    assert_one_error(capsys, base + ["--unit", "loadable", "--geometry", small], "index memory: ")
    assert_one_error(capsys, base + ["--unit", "loadable", "--geometry", small], "colour format rgb not supported")
    assert_one_error(capsys, base + ["--geometry", "paper"], "--geometry applies to --unit loadable")
    assert_one_error(capsys, base + ["--unit", "loadable", "--geometry", "tiny"], "unknown geometry 'tiny'")
    (tmp_path / "bad.toml").write_text("textures = 'many'\n")
    assert_one_error(capsys, base + ["--unit", "loadable", "--geometry", tmp_path / "bad.toml"], "bad.toml")
    assert_one_error(capsys, ["export", "-o", tmp_path / "x.v"], "FILE.vqt is required")
    assert_one_error(capsys, ["render", "topspin", "--frames", "0", "-o", tmp_path / "f.png", "--unit", "loadable"],
                     "--unit chooses the RTL unit: it needs an RTL --backend")
    assert not (tmp_path / "r.npy").exists() and not (tmp_path / "x.v").exists()


def test_export_loadable(tmp_path, capsys):
    """The loadable unit's Verilog holds no texture data (the same text from two different sets of
    one geometry, and from the geometry alone), lints clean, and comes with its register map and a C
    header that compiles."""
    need("verilator", "g++")
    a, b = texture_set("rgb_4x4_b8_mip"), texture_set("yuv_4x4_b12_mip")
    g = Geometry.of(a).union(Geometry.of(b))
    (tmp_path / "g.toml").write_text(g.dumps())
    a.save(tmp_path / "a.vqt")
    b.save(tmp_path / "b.vqt")
    texts = []
    for n, first in enumerate([[tmp_path / "a.vqt"], [tmp_path / "b.vqt"], []]):
        out = tmp_path / f"u{n}.v"
        code, stdout, err = run_cli(capsys, "export", *first, "--unit", "loadable", "--geometry", tmp_path / "g.toml",
                                    "-o", out, "--json", *(["--lint"] if n == 0 else []))
        assert code == 0, err
        rep = json.loads(stdout)
        assert rep["unit"] == "loadable" and rep["geometry"] == g.to_dict()
        assert {"bus_adr", "bus_dat_w", "bus_dat_r", "bus_stall", "bus_err"} <= set(rep["ports"])
        texts.append(out.read_text())
        assert (tmp_path / f"u{n}.regs.md").read_text().startswith("# vqtex loadable unit: register map")
        header = tmp_path / f"u{n}.h"
        use = tmp_path / "use.c"
        use.write_text(f'#include "{header}"\nunsigned a = VQTEX_DESCRIPTOR(1, 2, 3) + VQTEX_REG_ID + VQTEX_D_BASE_MASK;\n')
        subprocess.run(["gcc", "-fsyntax-only", "-Wall", "-Werror", str(use)], check=True)
    assert texts[0] == texts[1] == texts[2]


def test_render_topspin_town_and_dt_one_build(tmp_path, capsys, monkeypatch):
    """One CXXRTL build of the dreamcast geometry renders topspin, then town, then a scene of .dt
    textures, every frame identical to golden: the three renders open the same build (one key, in
    the build cache). The shared build cache serves it (the same build as ``test_demo_loadable``'s;
    a build of this geometry of its own took about two minutes of the suite); a build per set would
    show as three keys."""
    from vqtex.sim.backends import cxxrtl
    from vqtex.sim.backends.toolchain import cache_dir
    need("g++")
    scene = crates_scene(tmp_path)
    opened = []
    real = cxxrtl.open_design

    def open_design(build):
        opened.append(build.key)
        return real(build)
    monkeypatch.setattr(cxxrtl, "open_design", open_design)
    for scene in ("topspin", "town", scene):
        code, out, err = run_cli(capsys, "render", scene, "--frames", "0", "-o", tmp_path / "f.png",
                                 "--backend", "cxxrtl", "--unit", "loadable", "--geometry", "dreamcast",
                                 "--stall", "0.1", "--json")
        assert code == 0, err
        rep = json.loads(out)
        assert rep["identical_to_golden"] and rep["unit"] == "loadable"
        assert rep["frames"][0]["load_cycles"] > 0
    assert len(opened) == 3 and len(set(opened)) == 1
    assert os.path.isfile(os.path.join(cache_dir(), "cxxrtl", opened[0], "libvq.so"))


def test_render_filter_in_rtl_loadable(tmp_path, capsys):
    """The RTL texture filter, loadable (its own geometry, one lane), renders the .dt scene as golden."""
    need("g++")
    scene = crates_scene(tmp_path)
    code, out, err = run_cli(capsys, "render", scene, "--frames", "0", "-o", tmp_path / "f.png", "--backend", "cxxrtl",
                             "--filter-in-rtl", "--lanes", "1", "--unit", "loadable", "--json")
    assert code == 0, err
    rep = json.loads(out)
    assert rep["identical_to_golden"] and rep["unit"] == "loadable" and rep["index_banks"] == "lane"
    assert_one_error(capsys, ["render", scene, "--frames", "0", "-o", tmp_path / "g.png", "--backend", "cxxrtl",
                              "--filter-in-rtl", "--unit", "loadable", "--index-banks", "parity"], "--index-banks lane")


def test_demo_loadable(tmp_path, capsys):
    need("g++")
    code, out, err = run_cli(capsys, "demo", "-o", tmp_path / "d", "--frames", "0", "--unit", "loadable",
                             "--geometry", "dreamcast", "--json")
    assert code == 0, err
    rep = json.loads(out)
    assert rep["identical_to_golden"] and rep["unit"] == "loadable" and rep["load_cycles_per_frame"] > 0


def test_report_area_loadable(tmp_path, capsys):
    """Synthesis of a small geometry's loadable unit (no place and route: the suite's time)."""
    need_synth_tools()
    g = Geometry.of(texture_set("rgb_4x4_b8_mip"))
    (tmp_path / "g.toml").write_text(g.dumps())
    code, out, err = run_cli(capsys, "report", "area", "--unit", "loadable", "--geometry", tmp_path / "g.toml",
                             "--no-pnr", "--json")
    assert code == 0, err
    rep = json.loads(out)
    assert rep["unit"] == "loadable" and rep["geometry"] == g.to_dict() and rep["utilisation"]["luts"] > 0
