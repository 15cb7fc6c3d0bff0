"""vqtex sim --memory external (docs/memory.md): the cached unit's report from the golden cycle model
and from the RTL on pysim, CXXRTL and Verilator agree; bad memory configurations are one line, exit 2."""

import json

import numpy as np
import pytest

from vqtex.golden.fetch import fetch, random_requests

from tests.support import assert_one_error, need, run_cli, shared_cache, texture_set

SMALL = ["--cache-size", "1024", "--raw-cache-size", "256", "--cache-line", "16"]


@pytest.fixture(scope="module")
def trace(tmp_path_factory):
    d = tmp_path_factory.mktemp("memory_cli")
    ts = texture_set("yuv_4x4_b12_mip")
    ts.save(d / "t.vqt")
    req = random_requests(ts, 60, seed=1)
    np.save(d / "r.npy", req)
    return d, ts, req


@pytest.mark.parametrize("model", [["--memory-latency", "40", "--prefetch", "1"], ["--memory-model", "dram"]])
def test_golden_and_pysim_reports_agree(capsys, trace, model):
    d, ts, req = trace
    reports = {}
    for backend in ("golden", "pysim"):
        out = d / f"{backend}.npy"
        code, text, err = run_cli(capsys, "sim", d / "t.vqt", d / "r.npy", "-o", out, "--backend", backend,
                                  "--memory", "external", *SMALL, *model, "--stall", "0.3", "--json")
        assert code == 0, err
        reports[backend] = json.loads(text)
        assert (np.load(out) == fetch(ts, *req.T)).all()
    g, p = reports["golden"], reports["pysim"]
    assert g["cycles"] == p["cycles"] and g["stall_cycles"] == p["stall_cycles"]
    for key in ("bursts", "memory_bytes", "bytes_per_texel", "references", "hit_rate", "configuration"):
        assert g["memory"][key] == p["memory"][key]
    assert g["stall_cycles"]["memory"] > 0 and g["memory"]["bursts"] > 0
    assert g["cycles"] >= g["memory"]["zero_latency_cycles"]


@pytest.mark.parametrize("backend", ["cxxrtl", "verilator"])
def test_compiled_reports_equal_golden(capsys, trace, backend):
    """The compiled backends' report equals golden's: the caches of
    tests/sim/backends/test_cached_compiled.py (its builds), a longer stream, DDR3 and a fixed memory."""
    need("g++", *(["verilator"] if backend == "verilator" else []))
    d, ts, _ = trace
    req = random_requests(ts, 2000, seed=3)
    np.save(d / "long.npy", req)
    shapes = ["--cache-size", "128", "--raw-cache-size", "64", "--cache-line", "16", "--cache-ways", "2"]
    with shared_cache():
        for model in (["--memory-latency", "90"], ["--memory-model", "dram", "--controller-cycles", "12"]):
            reports = {}
            for b in ("golden", backend):
                out = d / f"{b}.npy"
                code, text, err = run_cli(capsys, "sim", d / "t.vqt", d / "long.npy", "-o", out, "--backend", b,
                                          "--memory", "external", *shapes, *model, "--stall", "0.2", "--json")
                assert code == 0, err
                reports[b] = json.loads(text)
                assert (np.load(out) == fetch(ts, *req.T)).all()
            g, c = reports["golden"], reports[backend]
            assert g["cycles"] == c["cycles"] and g["stall_cycles"] == c["stall_cycles"]
            for key in ("bursts", "memory_bytes", "bytes_per_texel", "references", "hit_rate", "configuration"):
                assert g["memory"][key] == c["memory"][key]
            assert g["memory"]["bursts"] > 100


@pytest.mark.parametrize("argv,pattern", [
    (["--memory", "external", "--cache-line", "48"], "--cache-line"),
    (["--memory", "external", "--cache-size", "64", "--cache-line", "32"], "cannot hold 4 ways"),
    (["--cache-size", "1024"], "needs --memory external"),
    (["--memory", "external", "--memory-latency", "0"], "--memory-latency"),
    (["--memory", "external", "--memory-bandwidth", "3"], "must divide the bus width"),
    (["--memory", "external", "--dram-clock", "300"], "does not apply"),
    (["--memory", "external", "--cache-line", "8"], "narrower than the 16-byte bus"),
    (["--memory", "external", "--one-port"], "no --one-port"),
])
def test_bad_memory_configurations(capsys, trace, argv, pattern):
    d, _, _ = trace
    assert_one_error(capsys, ["sim", d / "t.vqt", d / "r.npy", "-o", d / "x.npy", *argv], pattern)
    assert not (d / "x.npy").exists()


@pytest.mark.parametrize("backend", ["golden", "cxxrtl"])
def test_render_with_external_memory(capsys, tmp_path, backend):
    """render --memory external: the frame is golden's, the cycles and memory figures are the cached
    unit's cycle model on the frame's requests (golden: the model itself; cxxrtl: the compiled RTL,
    the build of tests/sim/backends/test_cached_compiled.py's scene frame)."""
    if backend != "golden":
        need("g++")
    from vqtex.golden.memory.cache import CacheShape
    from vqtex.golden.memory.system import MemoryConfig
    from vqtex.golden.render.frame import frame_requests
    from vqtex.golden.render.scene import build_texture_set, parse_scene
    from vqtex.sim.backends.cycle_model import run_cached
    from tests.support import NEED_SCENE as SMALL
    scene_file = tmp_path / "small.toml"
    scene_file.write_text(SMALL)
    with shared_cache():
        code, text, err = run_cli(capsys, "render", scene_file, "--frames", "1", "-o", tmp_path / "f.png", "--memory",
                                  "external", "--cache-size", "512", "--raw-cache-size", "256", "--prefetch", "4",
                                  "--backend", backend, "--json")
    assert code == 0, err
    rep = json.loads(text)
    scene = parse_scene(SMALL, str(scene_file))
    ts = build_texture_set(scene)
    req, sampler = frame_requests(scene, 1, ts, "trilinear")
    cfg = MemoryConfig(index_cache=CacheShape(512, 32, 4), raw_cache=CacheShape(256, 32, 4), prefetch=4)
    model = run_cached(ts, req, cfg)
    frame = rep["frames"][0]
    assert frame["cycles"] == model["cycles"] and rep["cycles_per_frame"] == model["cycles"]
    assert rep["memory"]["bytes_per_texel"] == model["bytes_per_texel"]
    assert rep["memory"]["bytes_per_pixel"] == sum(model["memory_bytes"].values()) / len(sampler.fragments)
    if backend == "golden":
        assert rep["memory"]["of_zero_latency"] == model["of_zero_latency"]
        assert model["bursts"] > 0
    else:
        assert frame["identical_to_golden"] and model["bursts"] > 0
    assert_one_error(capsys, ["render", scene_file, "--frames", "1", "-o", tmp_path / "g.png", "--memory", "external",
                              "--compare-fixed"], "not with --compare-fixed")


def test_demo_with_external_memory(capsys, tmp_path):
    """demo --memory external: topspin's frame through the cached unit (its default caches) on the
    default backend, identical to golden, with the memory report render prints; --unit is refused."""
    need("g++")
    with shared_cache():
        code, text, err = run_cli(capsys, "demo", "-o", tmp_path / "d", "--frames", "0", "--memory", "external")
        assert code == 0, err
        lines = text.splitlines()
        assert "RTL (cxxrtl, cached unit) frames identical to golden: yes" in text
        mem = [ln for ln in lines if ln.strip().startswith("external memory (index cache 16 KB")]
        assert len(mem) == 1 and "bytes read per texel" in mem[0] and "hit rates index" in mem[0]
        rep = json.loads((tmp_path / "d" / "report.json").read_text())
        assert rep["unit"] == "cached" and rep["identical_to_golden"]
        m = rep["memory"]
        assert 0.99 < m["hit_rate"]["index"] < 1 and 0.99 < m["hit_rate"]["raw"] < 1
        assert m["bytes_per_pixel"] > 0 and rep["frames"][0]["stall_cycles"]["memory"] > 0
        assert rep["frames"][0]["latency"] == 21
    assert_one_error(capsys, ["demo", "-o", tmp_path / "e", "--memory", "external", "--unit", "full"], "no --unit")
    assert_one_error(capsys, ["demo", "-o", tmp_path / "e", "--cache-size", "4096"], "needs --memory external")


def test_report_cycles_plot_draws_the_memory_figures(capsys, trace):
    """``report cycles --memory external --plot``: the cycle bar's memory stall names its miss and
    bandwidth split, and a second row draws each cache's hit rate, the bytes per texel by cache and
    the texels per clock beside the zero-latency unit's, each equal to the report's numbers."""
    from vqtex.sim.reports.plotting import cycle_figure
    from vqtex.golden.render.imageio import read_image
    d, _, _ = trace
    png = d / "memory.png"
    code, text, err = run_cli(capsys, "report", "cycles", d / "t.vqt", d / "r.npy", "--memory", "external", *SMALL,
                              "--memory-latency", "60", "--plot", png, "--json")
    assert code == 0, err
    rep = json.loads(text)
    mem = rep["memory"]
    assert read_image(png).shape[0] > 400
    fig = cycle_figure(rep)
    bar, hit, rates, bytes_ = fig.axes
    legend = [t.get_text() for t in bar.get_legend().get_texts()]
    detail = mem["stall_detail"]
    assert detail["miss"] > 0 and any(f"miss {detail['miss']}, bandwidth {detail['bandwidth']}" in t for t in legend)
    assert [p.get_height() for p in hit.patches] == pytest.approx([100 * mem["hit_rate"]["index"],
                                                                   100 * mem["hit_rate"]["raw"]])
    assert [p.get_height() for p in bytes_.patches] == pytest.approx(
        [mem["memory_bytes"]["index"] / rep["requests"], mem["memory_bytes"]["raw"] / rep["requests"]])
    this, zero = [p.get_height() for p in rates.patches]
    assert this == pytest.approx(rep["texels_per_clock"]) and zero == pytest.approx(
        rep["requests"] / mem["zero_latency_cycles"]) and this < zero
