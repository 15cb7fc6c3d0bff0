"""PowerVR2 sets through the specialised and the full unit on the compiled CXXRTL backend, bit-exact
against golden with random backpressure; what Features says each needs (the twiddle, the 16-bit
expansion, yuv422's pairs, the layout multiplexer only with both layouts); the paper's units without
any of it."""


import numpy as np
import pytest
from amaranth.back import rtlil

from tests import support
from tests.support import pvr2_small_sets

SMALL = pvr2_small_sets()
from tests.support import assert_same, back_to_back_requests, need, random_requests, shared_cache
from vqtex.golden.pvr2 import pvr, pvr_set
from vqtex.golden.fetch import fetch
from vqtex.golden.format import COLORS, PVR2_COLORS
from vqtex.hw.features import READ_BY, Features
from vqtex.hw.texel_fetch import TexelFetch
from vqtex.sim.backends.interface import simulate


@pytest.fixture(scope="module", autouse=True)
def cache():
    with shared_cache():
        yield


def _dt(*args, seed):
    return pvr_set.from_dt(pvr.parse_dt(support.random_dt(*args, seed=seed), decode=False))


#: name -> (set, units to run on CXXRTL).
SETS = {
    # the paper's rgb12 and four PowerVR2 textures (yuv422 with an rgb565 1x1 level, argb1555,
    # argb4444): both layouts, seven colour formats, the layout multiplexer
    "mixed": (lambda: pvr_set.TextureSet.combine([support.texture_sets()["rgb12"], SMALL["rectangles_and_mip8"]]),
              (True, False)),
    # one format: constant colour and layout, no multiplexer in the shifter, one expansion
    "rgb565_only": (lambda: _dt(32, 16, 1, 64, seed=3), (True,)),
    # yuv422 alone: the colour matrix and the U, V pairs, no 16-bit expansion
    "yuv422_only": (lambda: _dt(16, 32, 3, 40, seed=4), (True,)),
}


def _requests(ts, seed):
    return np.concatenate([back_to_back_requests(ts, limit=150), random_requests(ts, 1200, seed=seed),
                           support.adversarial_requests(ts, seed=seed)])


@pytest.mark.parametrize("name", sorted(SETS))
def test_cxxrtl_pvr2_specialised_and_full_bit_exact(name):
    need("g++")
    make, units = SETS[name]
    ts = make()
    req = _requests(ts, seed=29)
    assert np.array_equal(simulate(ts, req, backend="golden").responses, fetch(ts, *req.T))
    gold = simulate(ts, req, backend="golden", stall=0.3, seed=31)
    for specialise in units:
        got = simulate(ts, req, backend="cxxrtl", stall=0.3, seed=31, specialise=specialise)
        assert_same(got, gold, f"{name} cxxrtl specialise={specialise}")


def test_features_of_pvr2_sets():
    mixed, rgb565, yuv422 = (SETS[n][0]() for n in ("mixed", "rgb565_only", "yuv422_only"))
    f = Features.of(mixed)
    assert f.twiddled and f.layouts == {0, 1} and f.matrix
    assert {"yuv422", "argb1555", "argb4444", "rgb565"} <= f.colors
    assert "layout" in f.stored_fields and "log2h" in READ_BY
    f = Features.of(rgb565)
    assert f.twiddled and f.layouts == {1} and f.colors == {"rgb565"} and not f.matrix
    assert f.constants["layout"] == 1 and f.constants["color"] == COLORS.index("rgb565")
    assert f.output_codes == {COLORS.index("rgba")}
    f = Features.of(yuv422)
    assert f.colors == {"yuv422"} and f.matrix and f.output_codes == {COLORS.index("yuv411")}
    assert not f.expand16
    # the full unit serves every layout and format of a PowerVR2 set, only the paper's of a paper set
    assert Features.full(rgb565).colors == set(COLORS) and Features.full(rgb565).layouts == {0, 1}
    paper = support.texture_sets()["rgb12"]
    assert not set(PVR2_COLORS) & Features.full(paper).colors and not Features.full(paper).twiddled
    assert not Features.of(paper).twiddled


def _rtlil(ts, specialise):
    return rtlil.convert(TexelFetch(ts, specialise=specialise), emit_src=False)


def test_pvr2_logic_only_where_needed():
    """The specialised rgb565 unit: the twiddle without the layout multiplexer, no U, V pair select,
    no colour matrix products; the yuv422 unit: the pair select, no 16-bit expansion; the paper set's
    specialised unit: none of the PowerVR2 signals, no layout field."""
    rgb565 = _rtlil(SETS["rgb565_only"][0](), True)
    yuv422 = _rtlil(SETS["yuv422_only"][0](), True)
    paper = _rtlil(support.texture_sets()["rgb12"], True)
    assert "\\k_tw" in rgb565 and "\\ct_pair" not in rgb565 and "cell $mul " not in rgb565
    assert "\\ct_pair" in yuv422 and "\\k_tw" in yuv422
    for name in ("k_tw", "ct_pair", "square", "layout"):
        assert name not in paper, name
    # the full unit of the one-format set keeps every PowerVR2 path (and the paper's)
    full = _rtlil(SETS["rgb565_only"][0](), False)
    assert "\\ct_pair" in full and "\\k_tw" in full and "cell $mul " in full
