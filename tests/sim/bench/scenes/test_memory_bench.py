"""sim.bench.scenes.memory on a small scene: the uncompressed set is the same textures with every
level raw; the benchmark's rows hold what it prints, VQ against uncompressed through the same caches."""

import numpy as np

from vqtex.golden.fetch import decode
from vqtex.golden.render.scene import build_texture_set, parse_scene
from vqtex.sim.bench.scenes.memory import claim, plot_claim, scene_memory, uncompressed_set

from tests.support import NEED_SCENE as SMALL


def test_uncompressed_set_is_every_level_raw():
    scene = parse_scene(SMALL, "small.toml")
    vq = build_texture_set(scene)
    raw = uncompressed_set(scene)
    assert not raw.descriptors["compressed"][raw.descriptors["valid"].astype(bool)].any()
    images = [img for img, _ in scene.load_textures()]
    for t in range(vq.n_textures):
        assert raw.level_shapes(t) == vq.level_shapes(t)
        top = decode(raw, t, 0)
        assert (top[..., :images[t].shape[2]] == images[t]).all()       # level 0 is the image itself


def test_rows_compare_vq_and_uncompressed():
    scene = parse_scene(SMALL, "small.toml")
    r = scene_memory(scene, frame=1, latency=50, sizes=(1,), prefetch=8, dram=False)
    rows = {(x["textures"], x["prefetch"]): x for x in r["rows"]}
    assert set(rows) == {("vq", 1), ("vq", 8), ("uncompressed", 1), ("uncompressed", 8)}
    assert r["pixels"] > 0 and r["requests"] > 0
    for x in r["rows"]:
        assert x["cycles"] >= x["zero_latency_cycles"] and 0 < x["of_zero_latency"] <= 1
        assert np.isclose(x["cycles_per_pixel"] * r["pixels"], x["cycles"])
    assert rows[("uncompressed", 8)]["hit_rate"]["index"] is None       # nothing compressed: no index reads
    assert rows[("vq", 8)]["cycles"] <= rows[("vq", 1)]["cycles"]


def test_claim_rows_are_the_cycle_model(tmp_path):
    """--claim's rows: per set and cache size, the bytes, hit rates and cycles of run_cached on the
    same frame (the zero-latency cycles run once per set are the same stream's); the plot is written."""
    from vqtex.golden.memory.cache import CacheShape
    from vqtex.golden.memory.system import MemoryConfig
    from vqtex.golden.render.frame import frame_requests
    from vqtex.sim.backends.cycle_model import run_cached
    scene = parse_scene(SMALL, "small.toml")
    r = claim(scene, frame=1, sizes=(1, 4), latency=40, prefetch=4)
    assert [(x["textures"], x["cache_kb"]) for x in r["rows"]] == [("vq", 1), ("vq", 4), ("uncompressed", 1),
                                                                    ("uncompressed", 4)]
    sets = {"vq": build_texture_set(scene), "uncompressed": uncompressed_set(scene)}
    req, sampler = frame_requests(scene, 1, sets["vq"], "trilinear")
    for x in r["rows"]:
        shape = CacheShape(x["cache_kb"] * 1024, 32, 4)
        model = run_cached(sets[x["textures"]], req, MemoryConfig(index_cache=shape, raw_cache=shape, prefetch=4,
                                                                  latency=40))
        assert x["cycles"] == model["cycles"] and x["of_zero_latency"] == model["of_zero_latency"]
        assert x["hit_rate"] == model["hit_rate"]
        assert x["bytes_per_pixel"] == sum(model["memory_bytes"].values()) / len(sampler.fragments)
    assert r["rows"][2]["bytes_per_pixel"] > r["rows"][0]["bytes_per_pixel"] > 0
    plot_claim([r], str(tmp_path / "claim.png"))
    assert (tmp_path / "claim.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_claim_sums_frames_and_takes_the_dram():
    """--claim over several frames is the sum of each frame's own run (the caches empty at each
    frame's start); with the DRAM model the rows are run_cached's with the DDR3 part."""
    from vqtex.golden.memory.cache import CacheShape
    from vqtex.golden.memory.system import MemoryConfig
    from vqtex.golden.render.frame import frame_requests
    from vqtex.sim.backends.cycle_model import run_cached
    scene = parse_scene(SMALL, "small.toml")
    one = [claim(scene, frame=f, sizes=(1,), latency=40, prefetch=4) for f in (0, 2)]
    both = claim(scene, frame=(0, 2), sizes=(1,), latency=40, prefetch=4)
    assert both["frame"] == [0, 2] and both["pixels"] == one[0]["pixels"] + one[1]["pixels"]
    for k, row in enumerate(both["rows"]):
        assert row["cycles"] == one[0]["rows"][k]["cycles"] + one[1]["rows"][k]["cycles"]
        assert np.isclose(row["bytes_per_pixel"] * both["pixels"],
                          sum(o["rows"][k]["bytes_per_pixel"] * o["pixels"] for o in one))
    dram = claim(scene, frame=1, sizes=(1,), prefetch=4, kind="dram")
    assert dram["memory"] == "dram" and dram["latency"] is None
    ts = build_texture_set(scene)
    req, _ = frame_requests(scene, 1, ts, "trilinear")
    shape = CacheShape(1024, 32, 4)
    model = run_cached(ts, req, MemoryConfig(index_cache=shape, raw_cache=shape, prefetch=4, kind="dram"))
    assert dram["rows"][0]["cycles"] == model["cycles"]
    assert dram["rows"][0]["cycles"] != claim(scene, frame=1, sizes=(1,), latency=40, prefetch=4)["rows"][0]["cycles"]
