"""vqtex render --requests sparse|fixed and --fovea; vqtex bench skip's numbers on a small scene."""

import json

import numpy as np
import pytest

from vqtex.golden.render.imageio import read_image
from vqtex.golden.render.scene import parse_scene
from vqtex.hw.texel_fetch import LATENCY
from vqtex.sim.cli import main
from tests.support import TINY_SCENE
from tests.support import need, shared_cache_dir


@pytest.fixture
def scene_file(tmp_path):
    p = tmp_path / "tiny.toml"
    p.write_text(TINY_SCENE)
    return p


@pytest.fixture
def cache(monkeypatch):
    monkeypatch.setenv("VQTEX_CACHE", shared_cache_dir())


def _render(capsys, *argv):
    capsys.readouterr()
    code = main(["render", *map(str, argv), "--json"])
    return code, json.loads(capsys.readouterr().out)


def test_sparse_and_fixed_streams_on_the_compiled_rtl(tmp_path, scene_file, capsys, cache):
    need("g++")
    reps = {}
    for stream in ("fixed", "sparse"):
        extra = ["--compare-fixed"] if stream == "sparse" else []
        code, reps[stream] = _render(capsys, scene_file, "-o", tmp_path / f"{stream}.png", "--backend", "cxxrtl",
                                     "--requests", stream, *extra)
        assert code == 0 and reps[stream]["identical_to_golden"] is True
        assert reps[stream]["request_stream"] == stream
    for f, s in zip(reps["fixed"]["frames"], reps["sparse"]["frames"]):
        assert np.array_equal(read_image(tmp_path / f"fixed_{f['frame']:04d}.png"),
                              read_image(tmp_path / f"sparse_{f['frame']:04d}.png"))
        assert f["requests"] == f["requests_fixed"] == s["requests_fixed"]
        assert f["skipped_zero_weight"] == f["skipped_repeats"] == 0
        assert s["requests"] == s["requests_fixed"] - s["skipped_zero_weight"] - s["skipped_repeats"] < f["requests"]
        assert s["cycles"] == s["requests"] + LATENCY < f["cycles"] == f["requests"] + LATENCY
        # --compare-fixed ran the fixed stream on the same backend: the fixed run's figures
        assert s["fixed_stream"] == {"requests": f["requests"], "cycles": f["cycles"], "identical": True}
    assert reps["sparse"]["requests_per_frame"] < reps["sparse"]["fixed_requests_per_frame"]
    assert reps["sparse"]["identical_to_fixed_stream"] is True
    assert reps["sparse"]["fixed_cycles_per_frame"] == reps["fixed"]["cycles_per_frame"]


def test_fovea_report(tmp_path, scene_file, capsys):
    code, rep = _render(capsys, scene_file, "-o", tmp_path / "f.png", "--fovea", "10,8", "--fovea-radius", "5",
                        "--fovea-falloff", "2", "--report", tmp_path / "r.json")
    assert code == 0 and json.loads((tmp_path / "r.json").read_text()) == rep
    fv = rep["fovea"]
    assert {k: fv[k] for k in ("x", "y", "radius", "falloff", "frames")} == dict(x=10.0, y=8.0, radius=5.0,
                                                                                  falloff=2.0, frames=2)
    figures = {"requests", "cycles", "blocks", "index_words", "codebook_entries", "raw_words", "memory_words"}
    for f in rep["frames"]:
        regions = f["fovea"]
        assert regions["fovea"]["identical"] is True and regions["fovea"]["mse"] == 0 and regions["fovea"]["psnr"] is None
        assert regions["fovea"]["pixels"] > 0 and regions["periphery"]["pixels"] > 0
        for name in ("fovea", "periphery"):
            r = regions[name]
            for label in ("unbiased", "foveated"):
                assert set(r[label]) == figures
                n = r[label]["requests"]
                assert r[label]["cycles"] == (n + LATENCY if n else 0)
                assert r[label]["memory_words"] == sum(r[label][k] for k in ("index_words", "codebook_entries", "raw_words"))
        assert regions["fovea"]["unbiased"] == regions["fovea"]["foveated"]
        # the foveated frame's requests are the two regions' requests
        assert f["requests"] == regions["fovea"]["foveated"]["requests"] + regions["periphery"]["foveated"]["requests"]
        assert regions["periphery"]["mse"] > 0 and regions["periphery"]["identical"] is False
    assert fv["fovea"]["identical"] is True and set(fv["periphery"]["saved"]) == {"requests", "cycles", "blocks",
                                                                                   "memory_words"}
    # the text report names both regions
    assert main(["render", str(scene_file), "-o", str(tmp_path / "g.png"), "--fovea", "10,8"]) == 0
    out = capsys.readouterr().out
    assert "fovea at (10, 8), radius 4 px" in out and "periphery" in out and "request stream" in out


@pytest.mark.parametrize("extra,message", [
    (["--fovea", "10"], "gaze point"),
    (["--fovea", "10,nan"], "gaze point"),
    (["--fovea", "1,2", "--fovea-radius", "0"], "radius"),
    (["--fovea", "1,2", "--fovea-falloff", "-1"], "falloff"),
    (["--fovea-radius", "3"], "needs --fovea"),
    (["--fovea", "1,2", "--mode", "point"], "trilinear"),
    (["--requests", "fixed", "--compare-fixed"], "needs --requests sparse"),
    (["--encode-needed", "--requests", "fixed"], "--encode-needed"),
    (["--encode-needed", "--fovea", "1,2"], "--encode-needed"),
])
def test_bad_options_are_one_line(tmp_path, scene_file, capsys, extra, message):
    capsys.readouterr()
    assert main(["render", str(scene_file), "-o", str(tmp_path / "x.png"), *extra]) == 2
    err = capsys.readouterr().err
    assert err.startswith("vqtex: error:") and err.count("\n") == 1 and message in err, err
    assert not list(tmp_path.glob("x*.png"))


def test_bench_skip_on_a_small_scene(cache, capsys):
    need("g++")
    from vqtex.sim.bench.scenes.skip import run
    capsys.readouterr()
    rows = run(json_out=True, scenes=[parse_scene(TINY_SCENE, "tiny.toml")])          # its two frames
    assert json.loads(capsys.readouterr().out) == {"skip": json.loads(json.dumps(rows))}
    row = rows[0]
    assert row["frames"] == 2 and row["frames_identical"] is True
    f, s = row["fixed"], row["sparse"]
    assert f["requests_per_frame"] == 8 * row["covered_pixels_per_frame"]
    assert s["requests_per_frame"] == f["requests_per_frame"] - row["skipped_zero_weight_per_frame"] \
        - row["skipped_repeats_per_frame"]
    assert s["cycles_per_frame"] == s["requests_per_frame"] + LATENCY
    assert 0 < row["requests_saved"] < 1 and row["cycles_saved"] > 0


def test_small_topspin_frames_on_the_compiled_rtl(cache):
    """topspin at 96x96 (the same textures, so the same texture set and CXXRTL build as the full
    scene): both streams through the compiled RTL give identical frames, the sparse one in fewer
    cycles."""
    need("g++")
    from vqtex.golden.render.frame import frame_requests
    from vqtex.golden.render.pyramid import VQSource
    from vqtex.golden.render.scene import DATA_DIR, build_texture_set
    from vqtex.sim.backends import simulate
    text = (DATA_DIR / "topspin.toml").read_text()
    assert text.count("size = [400, 400]") == 1
    scene = parse_scene(text.replace("size = [400, 400]", "size = [96, 96]"), str(DATA_DIR / "small_topspin.toml"))
    ts = build_texture_set(scene)
    src = VQSource(ts)
    for frame in (0, 30):
        out = {}
        for stream in ("fixed", "sparse"):
            reqs, sampler = frame_requests(scene, frame, src, stream=stream)
            res = simulate(ts, reqs, backend="cxxrtl")
            out[stream] = (len(reqs), res.cycles, sampler.resolve(res.responses))
        assert np.array_equal(out["fixed"][2], out["sparse"][2])
        assert out["sparse"][0] < out["fixed"][0] and out["sparse"][1] == out["sparse"][0] + LATENCY < out["fixed"][1]


def test_a_fovea_off_the_frame_is_all_periphery(tmp_path, scene_file, capsys):
    code, rep = _render(capsys, scene_file, "-o", tmp_path / "f.png", "--frames", "0", "--fovea=-50,-50",
                        "--fovea-radius", "2")
    assert code == 0
    regions = rep["frames"][0]["fovea"]
    assert regions["fovea"]["pixels"] == 0 and regions["fovea"]["identical"] is True
    assert regions["fovea"]["foveated"]["requests"] == regions["fovea"]["foveated"]["cycles"] == 0
    assert rep["fovea"]["fovea"]["saved"]["requests"] == 0.0
    assert regions["periphery"]["foveated"]["requests"] == rep["frames"][0]["requests"]
