"""vqtex sim --memory external (docs/memory.md): the cached unit's report from the golden cycle model
and from the RTL on pysim agree; bad memory configurations are one line, exit 2."""

import json

import numpy as np
import pytest

from vqtex.golden.fetch import fetch, random_requests

from tests.support import assert_one_error, run_cli, texture_set

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


@pytest.mark.parametrize("argv,pattern", [
    (["--memory", "external", "--cache-line", "48"], "--cache-line"),
    (["--memory", "external", "--cache-size", "64", "--cache-line", "32"], "cannot hold 4 ways"),
    (["--cache-size", "1024"], "needs --memory external"),
    (["--memory", "external", "--memory-latency", "0"], "--memory-latency"),
    (["--memory", "external", "--memory-bandwidth", "3"], "must divide the bus width"),
    (["--memory", "external", "--backend", "cxxrtl"], "golden or pysim"),
    (["--memory", "external", "--dram-clock", "300"], "does not apply"),
    (["--memory", "external", "--cache-line", "8"], "narrower than the 16-byte bus"),
    (["--memory", "external", "--one-port"], "no --one-port"),
])
def test_bad_memory_configurations(capsys, trace, argv, pattern):
    d, _, _ = trace
    assert_one_error(capsys, ["sim", d / "t.vqt", d / "r.npy", "-o", d / "x.npy", *argv], pattern)
    assert not (d / "x.npy").exists()


def test_render_with_external_memory(capsys, tmp_path):
    """render --memory external: the frame is golden's, the cycles and memory figures are the cached
    unit's cycle model on the frame's requests."""
    from vqtex.golden.memory.cache import CacheShape
    from vqtex.golden.memory.system import MemoryConfig
    from vqtex.golden.render.frame import frame_requests
    from vqtex.golden.render.scene import build_texture_set, parse_scene
    from vqtex.sim.backends.cycle_model import run_cached
    from tests.golden.need.test_need import SMALL
    scene_file = tmp_path / "small.toml"
    scene_file.write_text(SMALL)
    code, text, err = run_cli(capsys, "render", scene_file, "--frames", "1", "-o", tmp_path / "f.png", "--memory",
                              "external", "--cache-size", "512", "--raw-cache-size", "256", "--prefetch", "4",
                              "--json")
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
    assert rep["memory"]["of_zero_latency"] == model["of_zero_latency"]
    assert_one_error(capsys, ["render", scene_file, "--frames", "1", "-o", tmp_path / "g.png", "--memory", "external",
                              "--compare-fixed"], "not with --compare-fixed")
