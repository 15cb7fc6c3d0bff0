"""The texture filter on the compiled backends: CXXRTL bit-exact against golden on large streams of
hard cases with random backpressure, the same cycles and stalls as pysim; the exported Verilog under
Verilator the same as CXXRTL."""


import numpy as np
import pytest

from tests.support import edge_pixels, filter_set
from tests.support import need, shared_cache
from vqtex.golden import filter as spec
from vqtex.hw.filter import LATENCY
from vqtex.hw.filter.footprint import level_table
from vqtex.sim.backends.filter import golden_colors, simulate_filter


@pytest.fixture(scope="module", autouse=True)
def cache():
    with shared_cache():
        yield


def _pixels(n, seed):
    ts = filter_set()
    frac = spec.coordinate_frac_bits(level_table(ts).max_log2)
    return ts, frac, edge_pixels(level_table(ts), frac, n, seed)


@pytest.mark.parametrize("lanes,stall", [(1, 0.3), (4, 0.0), (4, 0.5)])
def test_cxxrtl_filter_against_golden(lanes, stall):
    need("g++")
    ts, frac, px = _pixels(20000, lanes + int(10 * stall))
    res = simulate_filter(ts, px, backend="cxxrtl", lanes=lanes, stall=stall, seed=11)
    assert (res.colors == golden_colors(ts, px, frac)).all()
    groups = int((-(-np.array([1, 4, 8])[px["mode"]] // lanes)).sum())
    if stall == 0:
        assert res.cycles == groups + LATENCY
        assert res.stall_cycles["output_backpressure"] == 0
    else:
        assert res.cycles > groups + LATENCY
        assert res.stall_cycles["output_backpressure"] > 0


def test_cxxrtl_and_pysim_count_the_same_cycles():
    need("g++")
    ts, frac, px = _pixels(50, 9)
    a = simulate_filter(ts, px, backend="cxxrtl", lanes=1, stall=0.4, seed=5)
    b = simulate_filter(ts, px, backend="pysim", lanes=1, stall=0.4, seed=5)
    assert (a.colors == b.colors).all()
    assert (a.cycles, a.stall_cycles) == (b.cycles, b.stall_cycles)


def test_verilator_filter_equals_cxxrtl():
    need("g++", "verilator")
    ts, frac, px = _pixels(3000, 4)
    v = simulate_filter(ts, px, backend="verilator", lanes=2, stall=0.3, seed=2)
    c = simulate_filter(ts, px, backend="cxxrtl", lanes=2, stall=0.3, seed=2)
    assert (v.colors == golden_colors(ts, px, frac)).all()
    assert (v.colors == c.colors).all() and (v.cycles, v.stall_cycles) == (c.cycles, c.stall_cycles)


def test_filter_library_runs_again_and_describes_the_filter():
    """The filter is one model on the unit's CXXRTL driver (VQ_WHOLE, no bus): its ports.h asks for
    several payload words and its own strobes, and one library handle runs stream after stream
    (vq_run's reset is the rst input; the memories stay loaded), each equal to golden."""
    need("g++")
    from vqtex.sim.backends import cxxrtl
    from vqtex.sim.backends.design import FIELDS, filter_design_info
    from vqtex.sim.backends.filter import TAG_WIDTH
    ts, frac, px = _pixels(600, 7)
    info = filter_design_info(ts, lanes=2, frac=frac, tag_width=TAG_WIDTH)
    header = cxxrtl.ports_header(info)
    assert f"#define VQ_REQUEST_FIELDS {len(FIELDS)}" in header and info.payload_words > 1
    assert f"#define VQ_PAYLOAD_WORDS {info.payload_words}" in header
    assert info.strobes == ["stall_output", "busy", "bank_conflict"] and not info.halves and not info.bus
    lib, info, _ = cxxrtl.open_design(cxxrtl.build_design(info))
    try:
        assert lib.strobes == info.strobes and lib.request_fields == len(FIELDS)
        rows = np.stack([px[f] for f in FIELDS], 1)
        want = golden_colors(ts, px, frac)
        for stall in (0.0, 0.4, 0.0):
            rgba, counters = cxxrtl.run_checked(lib, rows, cxxrtl.batch_layout(info), n=len(rows), transfers=8 * len(rows),
                                                latency=info.latency, worst=8 * len(rows) + 64, stall=stall, seed=1,
                                                tag_width=TAG_WIDTH, what="colour")
            assert (rgba == want).all()
            assert (cxxrtl.strobe_sums(info, counters)["stall_output"] > 0) == (stall > 0)
    finally:
        lib.close()


@pytest.mark.parametrize("backend", ["cxxrtl", "verilator"])
def test_loadable_filter_compiled(backend):
    """The loadable filter (its set loaded over the bus port) on the compiled backends: golden's
    colours, and the cycles and stalls of the baked filter with a copy of the memories per lane."""
    need("g++", *(["verilator"] if backend == "verilator" else []))
    from vqtex.golden.geometry import Geometry
    ts, frac, px = _pixels(2000 if backend == "cxxrtl" else 600, 21)
    g = Geometry.of(ts)
    loaded = simulate_filter(ts, px, backend=backend, lanes=2, stall=0.3, seed=4, index_banks="lane", geometry=g)
    baked = simulate_filter(ts, px, backend=backend, lanes=2, stall=0.3, seed=4, index_banks="lane")
    assert (loaded.colors == golden_colors(ts, px, frac)).all()
    assert (loaded.cycles, loaded.stall_cycles) == (baked.cycles, baked.stall_cycles)


def test_filter_elaborated_once_per_process(monkeypatch):
    """A series of runs of one filter (a renderer's frames) elaborates it once: filter_design_info
    gives the same description for the same options and contents, another for other contents; after
    prepare_filter, simulate_filter elaborates nothing (issue 26: 0.45 s a frame of topspin)."""
    need("g++")
    from vqtex.sim.backends import design
    from vqtex.sim.backends.filter import prepare_filter
    ts, frac, px = _pixels(200, 3)
    made = []
    real = design._filter_design_info
    monkeypatch.setattr(design, "_filter_design_info", lambda *a, **k: made.append(k) or real(*a, **k))
    monkeypatch.setattr(design, "_designs", type(design._designs)())
    assert prepare_filter("cxxrtl", ts, lanes=2, frac=frac) > 0
    assert len(made) == 1
    first = simulate_filter(ts, px, backend="cxxrtl", lanes=2, frac=frac)
    again = simulate_filter(ts, px, backend="cxxrtl", lanes=2, frac=frac)
    assert len(made) == 1
    assert (first.colors == again.colors).all() and first.cycles == again.cycles
    assert design.filter_design_info(ts, lanes=2, frac=frac, tag_width=16) is design.filter_design_info(
        ts, lanes=2, frac=frac, tag_width=16)
    assert design.filter_design_info(ts, lanes=1, frac=frac, tag_width=16) is not design.filter_design_info(
        ts, lanes=2, frac=frac, tag_width=16)
    assert prepare_filter("golden", ts, lanes=2) == 0.0


def test_design_info_keyed_by_contents():
    """The texel-fetch unit's description is kept the same way, by its contents: a set with other
    texels is another description (other memory images), the same set the same one."""
    from vqtex.golden.encode import encode
    from tests.support import image
    from vqtex.sim.backends.design import design_info
    a = encode([image((16, 16), 0, 3)], codebook_size=8, index_bits=12)
    b = encode([image((16, 16), 5, 3)], codebook_size=8, index_bits=12)
    assert design_info(a) is design_info(a)
    assert design_info(b) is not design_info(a)
    assert [m.init for m in design_info(b).memories] != [m.init for m in design_info(a).memories]
    assert design_info(a, one_port=True) is not design_info(a)
