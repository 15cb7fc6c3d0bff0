"""vqtex sim/render/export --memory external --unit loadable: the loadable cached unit from the command
line (docs/memory.md, "The loadable cached unit"): golden's and pysim's reports agree (cycles, stalls,
memory figures, load cycles); a scene frame rendered on CXXRTL is golden's frame with the cycle
model's cycles after the load; export writes no texture data and the register map with the base
registers; bad combinations are one line, exit 2."""

import json

import numpy as np
import pytest

from vqtex.golden.fetch import fetch, random_requests
from vqtex.golden.format import TextureSet
from vqtex.golden.geometry import Geometry, preset
from vqtex.golden.memory.system import Layout
from vqtex.golden.register_map import load_cycles, load_writes

from tests.support import assert_one_error, need, run_cli, shared_cache, texture_set

SMALL = ["--cache-size", "256", "--raw-cache-size", "128", "--cache-line", "16", "--cache-ways", "2", "--prefetch", "8"]


@pytest.fixture(scope="module")
def trace(tmp_path_factory):
    d = tmp_path_factory.mktemp("loadable_memory_cli")
    ts = texture_set("yuv_4x4_b12_mip")
    ts.save(d / "t.vqt")
    req = random_requests(ts, 80, seed=2)
    np.save(d / "r.npy", req)
    return d, ts, req


def test_golden_and_pysim_agree(capsys, trace):
    d, ts, req = trace
    reports = {}
    for backend in ("golden", "pysim"):
        out = d / f"{backend}.npy"
        code, text, err = run_cli(capsys, "sim", d / "t.vqt", d / "r.npy", "-o", out, "--backend", backend,
                                  "--memory", "external", "--unit", "loadable", *SMALL, "--memory-latency", "30",
                                  "--stall", "0.2", "--json")
        assert code == 0, err
        reports[backend] = json.loads(text)
        assert (np.load(out) == fetch(ts, *req.T)).all()
    g, p = reports["golden"], reports["pysim"]
    assert g["unit"] == p["unit"] == "loadable"
    assert g["cycles"] == p["cycles"] and g["stall_cycles"] == p["stall_cycles"]
    for key in ("bursts", "memory_bytes", "references", "hit_rate", "configuration"):
        assert g["memory"][key] == p["memory"][key]
    want = load_cycles(len(load_writes(ts, Geometry.of(ts), Layout.of(ts))))
    assert g["load_cycles"] == p["load_cycles"] == want and g["memory"]["bursts"] > 0


def test_render_scene_frame_on_cxxrtl(capsys, tmp_path):
    """Topspin at 72 x 72 pixels (its textures: the set fits ``paper``) on the ``paper`` geometry's
    loadable cached unit (the build of tests/sim/backends/test_cached_loadable_compiled.py): golden's
    frame, the cycle model's cycles after the load, golden's load cycles."""
    need("g++")
    from vqtex.golden.memory.cache import CacheShape
    from vqtex.golden.memory.system import MemoryConfig
    from vqtex.golden.render.frame import frame_requests
    from vqtex.golden.render.scene import build_texture_set, builtin_scene_path, parse_scene
    from vqtex.sim.backends.cycle_model import run_cached
    from tests.support.scenes import PRUNE_SCENES
    path = builtin_scene_path("topspin")
    old, small, _, _ = PRUNE_SCENES["topspin"]
    text = path.read_text().replace(old, small).replace('file = "', f'file = "{path.parent}/')
    scene_file = tmp_path / "topspin_small.toml"
    scene_file.write_text(text)
    with shared_cache():
        code, out, err = run_cli(capsys, "render", scene_file, "--frames", "0", "-o", tmp_path / "f.png",
                                 "--memory", "external", "--unit", "loadable", "--geometry", "paper",
                                 "--cache-size", "1024", "--raw-cache-size", "512", "--cache-ways", "2",
                                 "--prefetch", "16", "--backend", "cxxrtl", "--stall", "0.1", "--json")
    assert code == 0, err
    rep = json.loads(out)
    scene = parse_scene(text, str(scene_file))
    ts = build_texture_set(scene)
    req, _ = frame_requests(scene, 0, ts, "trilinear")
    cfg = MemoryConfig(index_cache=CacheShape(1024, 32, 2), raw_cache=CacheShape(512, 32, 2), prefetch=16)
    model = run_cached(ts, req, cfg, stall=0.1, seed=0, zero_latency=False)      # (--stall-seed: 0)
    frame = rep["frames"][0]
    assert rep["unit"] == "loadable" and frame["identical_to_golden"]
    assert frame["cycles"] == model["cycles"] and model["bursts"] > 0
    want = load_cycles(len(load_writes(ts, preset("paper"), Layout.of(ts))))
    assert frame["load_cycles"] == want
    with shared_cache():                    # the text names the load
        code, out, err = run_cli(capsys, "render", scene_file, "--frames", "0", "-o", tmp_path / "g.png",
                                 "--memory", "external", "--unit", "loadable", "--geometry", "paper",
                                 "--cache-size", "1024", "--raw-cache-size", "512", "--cache-ways", "2",
                                 "--prefetch", "16", "--backend", "cxxrtl")
    assert code == 0, err
    assert f"the set loaded over its bus in {want:,} cycles" in out and "identical to golden: yes" in out


def test_export_writes_the_register_map(capsys, trace, tmp_path):
    """No texture data; the Verilog has the bus and AXI ports; the map and header name the base
    registers and no index or raw words; the on-chip loadable unit's map has no base registers."""
    from vqtex.golden.register_map import RegisterMap
    d, ts, _ = trace
    out = tmp_path / "lc.sv"
    small = ["--cache-size", "1024", "--raw-cache-size", "256"]
    code, text, err = run_cli(capsys, "export", d / "t.vqt", "--unit", "loadable", "--memory", "external", *small,
                              "-o", out, "--json")        # (the set's own geometry; its contents not written)
    assert code == 0, err
    rep = json.loads(text)
    verilog = out.read_text()
    assert "bus_adr" in verilog and "axi_araddr" in verilog
    regs, header = (tmp_path / "lc.regs.md").read_text(), (tmp_path / "lc.h").read_text()
    assert "| INDEX_BASE | 0x1e | rw |" in regs and "| RAW_BASE | 0x1f | rw |" in regs
    assert "VQTEX_REG_INDEX_BASE" in header and "#define VQTEX_INDEX_WORDS 0u" in header
    assert rep["bus_addr_bits"] == RegisterMap(Geometry.of(ts), external=True).addr_bits
    assert run_cli(capsys, "export", d / "t.vqt", "--unit", "loadable", "-o", tmp_path / "chip.sv")[0] == 0
    assert "INDEX_BASE" not in (tmp_path / "chip.regs.md").read_text()


@pytest.mark.parametrize("argv,pattern", [
    (["sim", "T", "R", "-o", "X.npy", "--memory", "external", "--unit", "full"], "no --unit full"),
    (["sim", "T", "R", "-o", "X.npy", "--memory", "external", "--unit", "loadable", "--one-port"], "no --one-port"),
    (["sim", "T", "R", "-o", "X.npy", "--memory", "external", "--geometry", "paper"], "--geometry applies"),
    (["export", "T", "-o", "X.sv", "--memory", "external", "--unit", "full"], "no --one-port, --unit full"),
])
def test_bad_combinations(capsys, trace, argv, pattern):
    d, _, _ = trace
    names = {"T": d / "t.vqt", "R": d / "r.npy", "X.npy": d / "x.npy", "X.sv": d / "x.sv", "TB": d / "tb"}
    assert_one_error(capsys, [names.get(a, a) for a in argv], pattern)
    assert not (d / "x.npy").exists() and not (d / "x.sv").exists()


def test_export_lints_clean(capsys, trace):
    """The loadable cached unit's Verilog (the set's own geometry) passes Verilator's lint (--lint)."""
    need("verilator")
    d, _, _ = trace
    code, text, err = run_cli(capsys, "export", d / "t.vqt", "--unit", "loadable", "--memory", "external",
                              "--cache-size", "1024", "--raw-cache-size", "256", "-o", d / "lint.sv", "--lint", "--json")
    assert code == 0, err
    assert json.loads(text)["lint"] == "clean"


def test_demo_loadable_cached(capsys, tmp_path):
    """demo --memory external --unit loadable --geometry paper: topspin's frame through the loadable
    cached unit on CXXRTL (the build of test_render_scene_frame_on_cxxrtl: paper, 1 KB + 512 B caches of
    2 ways, FIFO 16), the set loaded over the bus before it: the frame identical to golden, the load's
    cycles golden's count; a geometry topspin does not fit is one line, exit 2."""
    need("g++")
    small = ["--cache-size", "1024", "--raw-cache-size", "512", "--cache-ways", "2", "--prefetch", "16"]
    with shared_cache():
        code, text, err = run_cli(capsys, "demo", "-o", tmp_path / "d", "--frames", "0", "--memory", "external",
                                  "--unit", "loadable", "--geometry", "paper", *small)
    assert code == 0, err
    assert "RTL (cxxrtl, loadable cached unit) frames identical to golden: yes" in text
    rep = json.loads((tmp_path / "d" / "report.json").read_text())
    ts = TextureSet.load(tmp_path / "d" / "topspin.vqt")
    want = load_cycles(len(load_writes(ts, preset("paper"), Layout.of(ts))))
    assert rep["unit"] == "loadable cached" and rep["identical_to_golden"] and rep["geometry"] == preset("paper").to_dict()
    assert rep["load_cycles_per_frame"] == rep["frames"][0]["load_cycles"] == want
    assert f"loaded over the bus port before each frame: {want} cycles" in text
    m = rep["memory"]
    assert m["configuration"].startswith("index cache 1 KB") and 0.9 < m["hit_rate"]["index"] < 1
    assert rep["frames"][0]["cycles"] > rep["frames"][0]["requests"] and rep["frames"][0]["latency"] == 21
    small_geometry = tmp_path / "small.toml"
    small_geometry.write_text(Geometry.of(texture_set("rgb_4x4_b8_mip")).dumps())
    assert_one_error(capsys, ["demo", "-o", tmp_path / "e", "--memory", "external", "--unit", "loadable",
                              "--geometry", small_geometry], "does not fit geometry")
    assert not (tmp_path / "e").exists()
