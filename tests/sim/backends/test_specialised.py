"""Every specialised configuration of TexelFetch (tests.support's SPECIALISE_CASES) bit-exact
against golden on the compiled CXXRTL backend with random backpressure, the full unit beside it, the
build cache keeping the two apart, and the exported Verilog of the most specialised units under
Icarus Verilog."""


import numpy as np
import pytest

from tests.support import SPECIALISE_CASES as CASES
from tests.support import assert_same, back_to_back_requests, need, random_requests, shared_cache
from vqtex.golden.fetch import fetch
from vqtex.sim.backends.interface import simulate


@pytest.fixture(scope="module", autouse=True)
def cache():
    with shared_cache():
        yield


def _requests(ts, seed):
    return np.concatenate([back_to_back_requests(ts, limit=150), random_requests(ts, 1500, seed=seed)])


# "combined" is the suite's "mixed" kind of set, already run specialised by test_backends.py.
@pytest.mark.parametrize("name", [n for n in CASES if n != "combined"])
def test_cxxrtl_specialised_bit_exact_with_backpressure(name):
    need("g++")
    ts = CASES[name][0]()
    req = _requests(ts, seed=17)
    got = simulate(ts, req, backend="cxxrtl", stall=0.35, seed=23)
    assert np.array_equal(got.responses, fetch(ts, *req.T))
    assert_same(got, simulate(ts, req, backend="golden", stall=0.35, seed=23), f"{name} cxxrtl")


def test_cxxrtl_full_unit_and_distinct_cache_keys():
    """The full unit of the same set: a library of its own (its key differs), the same answers."""
    need("g++")
    from vqtex.sim.backends.cxxrtl import build_cxxrtl
    ts = CASES["three_widths"][0]()
    spec, full = build_cxxrtl(ts), build_cxxrtl(ts, specialise=False)
    assert spec.library != full.library and spec.key != full.key
    assert spec.info.link_width < full.info.link_width
    req = _requests(ts, seed=19)
    gold = simulate(ts, req, backend="golden", stall=0.3, seed=4)
    assert_same(simulate(ts, req, backend="cxxrtl", stall=0.3, seed=4, specialise=False), gold, "full cxxrtl")
    assert_same(simulate(ts, req, backend="cxxrtl", stall=0.3, seed=4), gold, "specialised cxxrtl")


@pytest.mark.parametrize("name", ["rgb8_no_mip", "raw_only", "two_widths_no_straddle"])
def test_icarus_specialised_export(name):
    """No descriptor table, no index reader, one index bank with the mask: the exported Verilog runs
    X-free under Icarus and answers golden."""
    need("iverilog", "vvp")
    from vqtex.sim.backends.verilog import run_icarus
    ts = CASES[name][0]()
    req = np.concatenate([back_to_back_requests(ts, limit=100), random_requests(ts, 100, seed=4)])
    res = run_icarus(ts, req, stall=0.3, seed=2)
    assert res["xerrors"] == 0 and res["unknown"] == 0
    assert np.array_equal(res["responses"], fetch(ts, *req.T))
    assert res["cycles"] == simulate(ts, req, stall=0.3, seed=2).cycles


@pytest.mark.parametrize("name", ["rgb8_no_mip", "raw_only", "yuv_dreamcast_b12_mip"])
def test_verilator_lint_clean_specialised(tmp_path, name, capsys):
    """The most specialised units export lint clean too (the documented waivers only)."""
    need("verilator")
    from vqtex.sim.cli import main
    path = tmp_path / "set.vqt"
    CASES[name][0]().save(path)
    code = main(["export", str(path), "-o", str(tmp_path / "tf.v"), "--lint"])
    assert code == 0, capsys.readouterr().err


def test_pruned_small_town_specialised_on_cxxrtl():
    """A set pruned for two frames of a small town (absent levels, fewer codewords, 12-bit indices
    renumbered narrower): its specialised unit is no wider than the unpruned set's, and answers
    those frames' requests on the compiled backend exactly as golden answers the unpruned set."""
    need("g++")
    from tests.support import PRUNE_SCENES as SMALL, small_scene
    from vqtex.golden.need.analysis import analyse, scene_streams
    from vqtex.golden.need.prune import prune
    from vqtex.golden.render.scene import build_texture_set
    from vqtex.hw.features import Features
    scene = small_scene("town")
    ts = build_texture_set(scene)
    frames = SMALL["town"][2]
    p = prune(ts, analyse(ts, scene_streams(scene, ts, frames)))
    full, pruned = Features.of(ts), Features.of(p)
    assert pruned.index_bits <= full.index_bits and set(pruned.colors) <= set(full.colors)
    assert (p.descriptors["valid"] == 0).sum() > (ts.descriptors["valid"] == 0).sum()     # absent levels
    req = np.concatenate([r for _, r in scene_streams(scene, ts, frames)])
    req = req[np.random.default_rng(0).permutation(len(req))[:4000]]
    got = simulate(p, req, backend="cxxrtl", stall=0.2, seed=6)
    assert np.array_equal(got.responses, fetch(ts, *req.T))
    assert_same(got, simulate(p, req, backend="golden", stall=0.2, seed=6), "pruned town")
