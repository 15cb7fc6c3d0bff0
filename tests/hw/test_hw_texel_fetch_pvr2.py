"""The PowerVR2 layout in the RTL: real Dreamcast textures (made by pvrtex, tests/data/pvrtex) through
TexelFetch, bit for bit against golden.fetch and pvrtex's own previews; the twiddling address
shifter and the 16-bit texel expansion stage by stage; the paper's unit unchanged for paper sets."""

from pathlib import Path

import numpy as np
import pytest
from amaranth.sim import Simulator

from tests import support
from tests.support import PVRTEX_DATA
from vqtex.golden.pvr2 import pvr, pvr_set
from vqtex.golden.fetch import block_address, expand_texels, fetch
from vqtex.golden.format import COLOR_CODES, DESCRIPTOR_DTYPE, LAYOUT_CODES, PVR2_COLORS
from vqtex.golden.render.imageio import read_image
from vqtex.hw.address import BlockAddress
from vqtex.hw.codebook_rom import expand_texel
from vqtex.hw.descriptor import descriptor_widths
from vqtex.sim.backends.interface import simulate

DATA = Path(PVRTEX_DATA)
GENERATED = sorted((DATA / "generated").glob("*.dt"))


SMALL = support.pvr2_small_sets()


@pytest.mark.parametrize("name", sorted(SMALL))
def test_pysim_random_and_adversarial_with_backpressure(name):
    ts = SMALL[name]
    req = np.concatenate([support.random_requests(ts, 200, seed=4), support.adversarial_requests(ts, seed=5)])
    support.compare_with_golden(ts, req, "pysim", stall=0.3, seed=6)


def test_pysim_mixed_with_a_paper_set():
    """One unit serving the paper's textures and PowerVR2 ones, requests interleaved."""
    ts = pvr_set.TextureSet.combine([support.texture_sets()["rgb12"], SMALL["rectangles_and_mip8"]])
    req = np.concatenate([support.random_requests(ts, 200, seed=7), support.back_to_back_requests(ts, 120)])
    r = support.compare_with_golden(ts, req, "pysim", stall=0.2, seed=8)
    assert set(req[:, 0].tolist()) == set(range(ts.n_textures)) and r.requests == len(req)


def test_mip8_set_reaches_the_one_by_one_yuv_level():
    ts = SMALL["rectangles_and_mip8"]
    t = ts.n_textures - 1
    assert ts.textures[t].levels == 4 and ts.textures[t].color == "yuv422"
    assert ts.descriptor(t, 3)["color"] == COLOR_CODES["rgb565"]


def test_every_texel_of_every_pvrtex_file_through_cxxrtl():
    """All twenty pvrtex files in one set, every texel of every level, random backpressure: the
    responses assembled into pvrtex's preview layout equal its preview images."""
    support.need("g++")
    with support.shared_cache():
        ts = pvr_set.import_dt(GENERATED)
        rows = []
        for t in range(ts.n_textures):
            for L, (w, h) in enumerate(ts.level_shapes(t)):
                jj, ii = np.mgrid[0:h, 0:w]
                rows.append(np.stack([np.full(w * h, t), np.full(w * h, L), ii.ravel(), jj.ravel()], 1))
        req = np.concatenate(rows)
        r = simulate(ts, req, backend="cxxrtl", stall=0.1, seed=11)
        g = simulate(ts, req, backend="golden", stall=0.1, seed=11)
        support.assert_same(r, g, "cxxrtl")
        at = 0
        for t, path in enumerate(GENERATED):
            levels = []
            for w, h in ts.level_shapes(t):
                levels.append(r.responses[at: at + w * h].reshape(h, w, 4))
                at += w * h
            theirs = read_image(path.with_name(path.name[:-3] + ".preview.png"))
            assert np.array_equal(pvr.preview(levels), theirs), path.name
        assert at == len(req) == 12 * ((128 * 128 * 4 - 1) // 3) + 8 * 128 * 128   # 12 mip chains, 8 single levels


def test_paper_sets_elaborate_the_paper_unit():
    """No layout bit, a 2-bit colour, no twiddle in the shifter: the PowerVR2 paths cost a paper set
    nothing."""
    ts = support.texture_sets()["mixed"]
    w = descriptor_widths(ts)
    assert (w["layout"], w["color"]) == (0, 2)
    w2 = descriptor_widths(SMALL["rectangles_and_mip8"])
    assert (w2["layout"], w2["color"]) == (1, 3)
    from amaranth.hdl import Fragment
    for twiddle in (False, True):
        dut = BlockAddress(base_bits=4, k_bits=8, raw_bits=4, twiddle=twiddle)
        assert ("layout" in dut.signature.members) == twiddle == dut.twiddle
        Fragment.get(dut, None)


def _random_descriptors(n, seed):
    rng = np.random.default_rng(seed)
    d = np.zeros(n, DESCRIPTOR_DTYPE)
    lw = rng.integers(1, 11, n)
    lh = np.where(rng.random(n) < 0.5, lw, rng.integers(1, 11, n))
    one = rng.random(n) < 0.1
    d["log2w"], d["log2h"] = np.where(one, 0, lw), np.where(one, 0, lh)
    d["log2bw"] = d["log2bh"] = np.where(one, 0, 1)
    d["layout"] = np.where(rng.random(n) < 0.8, LAYOUT_CODES["pvr2"], 0)
    d["log2bw"] = np.where(d["layout"] == 0, np.minimum(rng.integers(0, 3, n), d["log2w"]), d["log2bw"])
    i = rng.integers(0, 1 << 30, n) % (1 << d["log2w"].astype(np.int64))
    j = rng.integers(0, 1 << 30, n) % (1 << d["log2h"].astype(np.int64))
    return d, i, j


def test_block_address_twiddles_like_golden():
    d, i, j = _random_descriptors(300, seed=3)
    k, x, y = block_address(d, i, j)
    dut = BlockAddress(base_bits=4, k_bits=20, raw_bits=24, twiddle=True)
    out = support.run_lockstep(dut, {
        "i": i.tolist(), "j": j.tolist(), "log2w": d["log2w"].tolist(), "log2h": d["log2h"].tolist(),
        "log2bw": d["log2bw"].tolist(), "log2bh": d["log2bh"].tolist(), "layout": d["layout"].tolist(),
        "base": [0] * len(d)}, ["k", "x", "y"], latency=1, en_pattern=np.random.default_rng(1).random(500) < 0.7)
    assert out["k"] == k.tolist() and out["x"] == x.tolist() and out["y"] == y.tolist()
    assert {int(v) for v in d["layout"]} == {0, 1}


@pytest.mark.parametrize("color", PVR2_COLORS[:3])
def test_texel_expansion_like_golden(color):
    """Every field value of every channel: 600 random texels plus all-zeros, all-ones and each bit."""
    rng = np.random.default_rng(PVR2_COLORS.index(color))
    texels = np.concatenate([[0, 0xFFFF], 1 << np.arange(16), rng.integers(0, 1 << 16, 600)]).astype(np.int64)
    want = expand_texels(texels, color)
    from amaranth import Module, Signal
    m = Module()
    t = Signal(16)
    c = Signal(3)
    out = Signal(32)
    m.d.comb += out.eq(expand_texel(t, c))
    sim = Simulator(m)
    got = []

    async def bench(ctx):
        ctx.set(c, COLOR_CODES[color])
        for v in texels.tolist():
            ctx.set(t, v)
            got.append(ctx.get(out))
    sim.add_testbench(bench)
    sim.run()
    got = np.array(got, dtype="<u4").view(np.uint8).reshape(-1, 4)
    assert np.array_equal(got, want)


def test_golden_fetch_of_small_sets_equals_pvr_decode():
    """The pysim sets above are what pvr.py decodes (so the RTL runs are against the right thing)."""
    ts = SMALL["rectangles_and_mip8"]
    for t in range(ts.n_textures):
        tex = pvr.parse_dt(pvr_set.to_dt(ts, t))
        for L, (w, h) in enumerate(ts.level_shapes(t)):
            jj, ii = np.mgrid[0:h, 0:w]
            assert np.array_equal(fetch(ts, t, L, ii.ravel(), jj.ravel()).reshape(h, w, 4), tex.levels[L])


def test_paper_rtl_holds_no_pvr2_logic():
    """A paper set's full unit's RTLIL has the layout field at width 0 only and none of the PowerVR2
    signals; its specialised unit has no layout field at all; a PowerVR2 set's units, full and
    specialised, have them (main's RTLIL for paper sets differs only by those zero-width wires,
    docs/pvr2.md)."""
    from vqtex.sim.reports.synth import design_rtlil
    paper = design_rtlil(support.texture_sets()["rgb12"], specialise=False)
    layout = [ln.strip() for ln in paper.splitlines() if "layout" in ln]
    assert layout and all(ln.startswith(("wire width 0", "connect")) and ("{  }" in ln or "wire width 0" in ln)
                          for ln in layout), layout[:4]
    paper_specialised = design_rtlil(support.texture_sets()["rgb12"])
    assert "layout" not in paper_specialised
    for specialise in (False, True):
        pvr2 = design_rtlil(SMALL["rectangles_and_mip8"], specialise=specialise)
        for name in ("k_tw", "ct_pair", "square"):
            assert f"\\{name}" not in paper and f"\\{name}" not in paper_specialised, name
            assert f"\\{name}" in pvr2, (name, specialise)
