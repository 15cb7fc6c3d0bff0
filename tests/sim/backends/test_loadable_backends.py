"""The loadable unit on the compiled backends (CXXRTL, Verilator): one build per geometry; in one
simulation (one library handle) set after set is loaded over the bus port and then fetched, equal to
golden bit for bit and cycle for cycle, with backpressure; the load takes golden's cycles; reads
back and errors as the register map says; the golden, pysim and compiled backends agree."""

from __future__ import annotations

import numpy as np
import pytest

from tests.support import (adversarial_requests, assert_same, combined_set, need, pvr2_small_sets, random_requests,
                           shared_cache, texture_set)
from vqtex.golden.geometry import Geometry
from vqtex.golden.register_map import (RegisterMap, expected_reads, load_cycles, load_writes, mapped)
from vqtex.sim.backends import cxxrtl, verilator
from vqtex.sim.backends.interface import simulate


@pytest.fixture(scope="module", autouse=True)
def cache():
    with shared_cache():
        yield


@pytest.fixture(scope="module")
def sets():
    """Sets of one word width (32 bits) covering the paper's formats, widths 1..12, blocks 2x2 to
    8x8, extended codewords, raw levels, and PowerVR2 sets (twiddled, 16-bit formats, yuv422)."""
    names = ["rgb_4x4_b8_mip", "yuv_4x4_b12_mip", "i8_4x4_b1_mip", "rgba_8x8_b9_mip", "yuv_8x2_b6",
             "yuv_dreamcast_4x4_b12_mip", "raw_only_8x8_mip"]
    out = {n: texture_set(n) for n in names}
    out["combined"] = combined_set()
    out.update(pvr2_small_sets())
    return out


@pytest.fixture(scope="module")
def geometry(sets):
    g = None
    for ts in sets.values():
        g = Geometry.of(ts) if g is None else g.union(Geometry.of(ts))
    return g


OPEN = {"cxxrtl": cxxrtl.open_cxxrtl, "verilator": verilator.open_verilator}


@pytest.mark.parametrize("backend", ["cxxrtl", "verilator"])
def test_one_build_many_sets(backend, sets, geometry):
    need("g++", *(["verilator"] if backend == "verilator" else []))
    lib, info, build = OPEN[backend](None, geometry=geometry)
    try:
        # the build is the geometry's: asking with a set gives the same library
        again = (cxxrtl.build_cxxrtl if backend == "cxxrtl" else verilator.build_verilator)(
            sets["combined"], geometry=geometry)
        assert again.key == build.key and again.cached
        for n, (name, ts) in enumerate(list(sets.items()) * (2 if backend == "cxxrtl" else 1)):
            load = cxxrtl.load_set(lib, ts, geometry)
            assert load == load_cycles(len(load_writes(ts, geometry))), name
            req = np.concatenate([random_requests(ts, 3000, seed=n), adversarial_requests(ts, seed=n)])
            stall = (0.0, 0.3, 0.6)[n % 3]
            got = cxxrtl.run_batch(lib, info, req, stall=stall, seed=n)
            gold = simulate(ts, req, backend="golden", stall=stall, seed=n)
            assert_same(got, gold, f"{backend} {name}")
    finally:
        lib.close()


@pytest.mark.parametrize("backend", ["cxxrtl", "verilator"])
def test_read_back_and_errors_compiled(backend, sets, geometry):
    need("g++", *(["verilator"] if backend == "verilator" else []))
    ts = sets["yuv_dreamcast_4x4_b12_mip"]
    rmap = RegisterMap(geometry)
    lib, _, _ = OPEN[backend](None, geometry=geometry)
    try:
        cxxrtl.load_set(lib, ts, geometry)
        writes = load_writes(ts, geometry).astype(np.int64)
        rng = np.random.default_rng(1)
        addrs = np.concatenate([writes[rng.choice(len(writes), 500, replace=False), 0],
                                rng.integers(0, 1 << rmap.addr_bits, 300)])
        ops = np.stack([addrs, np.zeros_like(addrs), np.zeros_like(addrs)], 1)
        data, err, _ = lib.bus(ops)
        want, want_err = expected_reads(ts, geometry, addrs)
        known = np.isin(addrs, writes[:, 0]) | want_err
        assert np.array_equal(err, [not mapped(rmap, a) for a in addrs])
        assert np.array_equal(data[known & ~err], want[known & ~err])
        assert want_err.any() and (~want_err).any()
    finally:
        lib.close()


def test_simulate_geometry_all_backends(sets, geometry):
    """``simulate(..., geometry=)`` on golden, pysim and CXXRTL: the same result and load cycles; a set
    that does not fit is refused before any backend runs."""
    need("g++")
    ts = sets["combined"]
    req = random_requests(ts, 80, seed=3)
    small = Geometry.of(sets["rgb_4x4_b8_mip"])
    gold = simulate(ts, req, backend="golden", stall=0.2, seed=1, geometry=small.union(Geometry.of(ts)))
    for backend in ("pysim", "cxxrtl"):
        got = simulate(ts, req, backend=backend, stall=0.2, seed=1, geometry=small.union(Geometry.of(ts)))
        assert_same(got, gold, backend)
        assert got.load_cycles == gold.load_cycles > len(req)
    from vqtex.golden.register_map import LoadError
    with pytest.raises(LoadError, match="textures"):
        simulate(ts, req, backend="cxxrtl", geometry=small)


def test_guarded_writes_match_every_write_port(geometry):
    """The CXXRTL rewrite that skips idle write ports finds every write port of the loadable unit
    (one per memory: a Yosys update that changes CXXRTL's text fails here, not as a slowdown), and
    none in the baked unit."""
    from vqtex.sim.backends.design import design_info
    info = design_info(None, geometry=geometry)
    src = cxxrtl.write_cxxrtl(info.fragment, info.ports)
    _, count = cxxrtl.guarded_writes(src)
    assert count == len(info.memories) > 0
    baked = design_info(texture_set("rgb_4x4_b8_mip"))
    assert all(cxxrtl.guarded_writes(cxxrtl.write_cxxrtl(*baked.halves[h]))[1] == 0 for h in baked.halves)


def test_guarded_writes_test_the_enable_first(geometry):
    """A write port's mask spread from its enables (Yosys writes a wide memory's per-bit mask as the
    per-word enable bits repeated and concatenated: 504 bits from 16 enables, some thirty shifts of the
    whole mask a cycle) is built only when an enable is set: every write port of the loadable unit is
    guarded by its enable value (2.2x the loadable unit's speed, docs/simulation.md); a mask with a
    constant, or from two values, keeps the mask test alone."""
    import re
    from vqtex.sim.backends.design import design_info
    info = design_info(None, geometry=geometry)
    out, count = cxxrtl.guarded_writes(cxxrtl.write_cxxrtl(info.fragment, info.ports))
    assert len(re.findall(r"if \(!([\w.]+)\.is_zero\(\)\) \{ const auto vq_mask = ", out)) == count
    assert cxxrtl._mask_source("vq_slice<3>(p_en).repeat<31>().concat(vq_slice<3,2>(p_en)).val()") == "p_en"
    assert cxxrtl._mask_source("p_en_24_7.curr.repeat<32>().val()") == "p_en_24_7.curr"
    assert cxxrtl._mask_source("i_en.slice<3>().val().repeat<31>().concat(i_en.slice<3,2>())") == "i_en"
    for other in ("p_en.repeat<31>().concat(value<1>{1u})", "p_en.concat(p_we)", "not_u<8>(p_en)"):
        assert cxxrtl._mask_source(other) is None


def test_loadable_model_runs_in_place(geometry):
    """The loadable unit's CXXRTL model gets the in-place cycle (write ports queued, then committed
    after the register updates): its generated code keeps the shape the pass needs (whole-register
    assignments, no ROM made of a case statement)."""
    from vqtex.sim.backends.design import design_info
    _, header = cxxrtl.cxxrtl_program(design_info(None, geometry=geometry))
    assert "#define VQ_WHOLE 1" in header and "#define VQ_TOP_INPLACE 1" in header
