"""Every simulation backend (golden cycle model, pysim, cxxrtl, verilator) returns the same responses,
cycle counts, stall counts, straddle counts and occupancy on the same request streams."""


import numpy as np
import pytest

from tests.support import (assert_same, back_to_back_requests, need, random_requests, shared_cache, shared_cache_dir,
                           texture_sets)
from vqtex.sim.backends import cxxrtl as cb
from vqtex.sim.backends import design
from vqtex.sim.backends.interface import simulate


@pytest.fixture(scope="module", autouse=True)
def cache():
    with shared_cache():
        yield


@pytest.fixture(scope="module")
def sets():
    return texture_sets()


def _streams(ts):
    return {"random": random_requests(ts, 150, seed=1), "adversarial": back_to_back_requests(ts)}


# (texture set, one_port, stall): cxxrtl runs every row, verilator the rows marked True (its builds
# compile the memories in, so each texture set and mode is a build of its own).
CASES = [
    ("rgb12", False, 0.0, False), ("rgb12", True, 0.3, False),
    ("mixed", False, 0.0, True), ("mixed", False, 0.5, True), ("mixed", True, 0.0, True), ("mixed", True, 0.4, True),
    ("w16", False, 0.2, True), ("w16", True, 0.0, False),
]


@pytest.mark.parametrize("name,one_port,stall,with_verilator", CASES)
def test_backends_agree(sets, name, one_port, stall, with_verilator):
    need("g++")
    if with_verilator:
        need("verilator")
    ts = sets[name]
    for kind, req in _streams(ts).items():
        what = f"{name} one_port={one_port} stall={stall} {kind}"
        gold = simulate(ts, req, backend="golden", stall=stall, seed=5, one_port=one_port)
        pys = simulate(ts, req, backend="pysim", stall=stall, seed=5, one_port=one_port)
        assert_same(pys, gold, what + " pysim")
        cxx = simulate(ts, req, backend="cxxrtl", stall=stall, seed=5, one_port=one_port)
        assert_same(cxx, gold, what + " cxxrtl")
        if with_verilator:
            ver = simulate(ts, req, backend="verilator", stall=stall, seed=5, one_port=one_port)
            assert_same(ver, gold, what + " verilator")


@pytest.mark.parametrize("threads", [1, 2])
def test_long_stream_compiled_only(sets, threads, monkeypatch):
    """A longer stream with heavy backpressure (pattern regrown by the driver) on the compiled
    backend, its halves on one thread and on two (the back end then runs behind the front end
    through the ring of link records: 20000 requests are many turns of it)."""
    need("g++")
    monkeypatch.setenv("VQTEX_SIM_THREADS", str(threads))
    ts = sets["mixed"]
    req = random_requests(ts, 20000, seed=3)
    gold = simulate(ts, req, backend="golden", stall=0.7, seed=11)
    assert_same(simulate(ts, req, backend="cxxrtl", stall=0.7, seed=11), gold, "cxxrtl long")
    assert gold.stall_cycles["output_backpressure"] > 20000


@pytest.mark.parametrize("threads", [1, 2])
def test_long_one_port_stream_threads(sets, threads, monkeypatch):
    """One-port (the front end holds its first stages on a straddle), light backpressure, no
    backpressure: both thread counts equal golden, cycle for cycle."""
    need("g++")
    monkeypatch.setenv("VQTEX_SIM_THREADS", str(threads))
    ts = sets["w16"]
    req = random_requests(ts, 12000, seed=8)
    for stall in (0.0, 0.2):
        gold = simulate(ts, req, backend="golden", stall=stall, seed=3, one_port=True)
        assert gold.straddles > 0
        got = simulate(ts, req, backend="cxxrtl", stall=stall, seed=3, one_port=True)
        assert_same(got, gold, f"one-port stall {stall} threads {threads}")


def test_empty_and_single_request(sets):
    need("g++")
    ts = sets["rgb12"]
    for req in (np.zeros((0, 4), np.int64), np.array([[0, 0, 63, 63]])):
        assert_same(simulate(ts, req, backend="cxxrtl"), simulate(ts, req, backend="golden"), f"{len(req)} requests")


def test_cxxrtl_one_build_serves_same_shaped_sets(sets):
    """Memories are loaded at run time: a texture set with other contents but the same memory shapes
    reuses the library (and gives its own, right, texels)."""
    need("g++")
    from tests.support import image
    from vqtex.golden.encode import encode
    from vqtex.sim.backends.cxxrtl import build_cxxrtl
    a = sets["rgb12"]
    b = encode([image((64, 64), 42, 3)], codebook_size=16, mipmaps=True, index_bits=12)
    assert not np.array_equal(a.index_words, b.index_words) or not np.array_equal(a.codebook, b.codebook)
    la, lb = build_cxxrtl(a), build_cxxrtl(b)
    assert la.library == lb.library
    req = random_requests(b, 300, seed=9)
    assert_same(simulate(b, req, backend="cxxrtl"), simulate(b, req, backend="golden"), "same shape, other texels")


def test_memory_images_are_the_format_images_in_banks(sets):
    """The compiled backends load every memory by its name; the banked memories (512 words per bank)
    hold exactly golden.format's images, in order (banking is the hardware's internal organisation)."""
    from vqtex.sim.backends.cxxrtl import design_info
    ts = sets["mixed"]
    mems = {m.name: m for m in design_info(ts).memories}

    def joined(prefix, image):
        """The banks' contents in order equal ``image``; past it (the last bank is as deep as its read
        address reaches, hw.banked_rom) only zeros."""
        banks = sorted((n for n in mems if n.startswith(prefix + " bank")), key=lambda n: int(n.rsplit("bank", 1)[1]))
        assert all(mems[n].depth <= 512 for n in banks)
        words = [v for n in banks for v in mems[n].init]
        return words[:len(image)] == image and not any(words[len(image):])

    assert len([n for n in mems if n.startswith("back codebook_rom raw bank")]) == 2      # 1023 raw words
    assert joined("back codebook_rom raw", ts.raw_words.astype(int).tolist())
    assert joined("front index_reader even_bank", ts.index_words[0::2].astype(int).tolist())
    assert joined("front index_reader odd_bank", ts.index_words[1::2].astype(int).tolist())
    entries = [int.from_bytes(bytes(row), "little") for row in ts.codebook]
    assert joined("back codebook_rom codebook", entries)


def test_pack_requests_blocks():
    """The payload words hold each field at its offset, tag = request number, whatever the block."""
    ts = texture_sets()["mixed"]
    info = design.design_info(ts)
    req = random_requests(ts, 1001)
    words = design.pack_requests(info, req, block=64)
    assert np.array_equal(words, design.pack_requests(info, req))
    for n in (0, 63, 64, 1000):
        w = int(words[n])
        got = {name: (w >> off) & ((1 << width) - 1) for name, (off, width) in info.request_fields.items()}
        want = dict(zip(("texture", "level", "i", "j"), (int(v) for v in req[n])), tag=n & 0xff)
        assert got == want
    assert w >> info.request_width == 0


def test_batch_api_packs_requests_and_checks_tags(sets, monkeypatch):
    """vq_run packs the (texture, level, i, j) rows itself and returns the RGBA bytes; a response
    whose tag is not its request's is reported (here: the response tag read one bit too high)."""
    need("g++")
    monkeypatch.setenv("VQTEX_CACHE", shared_cache_dir())
    from vqtex.golden.fetch import fetch
    ts = sets["mixed"]
    lib, info, _ = cb.open_cxxrtl(ts)
    req = random_requests(ts, 300, seed=4)
    layout = cb.batch_layout(info)
    rc, rgba, counters = lib.run(req, layout, None, 1000)
    assert rc == 0 and counters[cb.C_RESPONSES] == 300 and counters[cb.C_BAD_TAG] == 0
    assert np.array_equal(rgba, fetch(ts, *req.T))
    wrong = layout.copy()
    wrong[10] += 1                                  # the response tag's offset
    rc, _, counters = lib.run(req, wrong, None, 1000)
    first = next(k for k in range(300) if (k >> 1) & 0x7F != k & 0xFF)   # tag bits 1..7 + a zero
    assert rc == 0 and counters[cb.C_BAD_TAG] == first + 1 and counters[cb.C_BAD_TAG_VALUE] == first >> 1
    monkeypatch.setattr(cb, "batch_layout", lambda info: wrong)
    with pytest.raises(cb.ToolchainError, match=f"response {first} carries tag {first >> 1}, expected {first}"):
        cb.run_batch(lib, info, req)


@pytest.mark.parametrize("tag_width", [0, 3])
def test_other_tag_widths(sets, tag_width):
    """No tag, and a tag that wraps every 8 requests: same responses and cycles as golden (the
    driver checks each response's tag against its request number mod 2^width)."""
    need("g++")
    ts = sets["mixed"]
    req = random_requests(ts, 500, seed=2)
    got = cb.run(ts, req, tag_width=tag_width, stall=0.3, seed=1)
    assert_same(got, simulate(ts, req, backend="golden", stall=0.3, seed=1), f"tag width {tag_width}")
