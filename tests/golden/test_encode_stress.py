"""Encoder arithmetic under adversarial training sets (issue 12): every block's stored index is the
exact nearest stored codeword (ties to the lowest index), nothing non-finite, cell sums exact,
the same bytes on one and two BLAS threads.  The cases and the exact checker live in
:mod:`vqtex.sim.bench.robustness.encoder_stress` (``vqtex bench stability`` prints the same figures)."""

import tracemalloc

import numpy as np
import pytest

from vqtex.golden import codebook as vq
from vqtex.golden.codebook import fullsearch
from vqtex.golden.encode import encode
from vqtex.golden.format import pack_indices, unpack_indices
from vqtex.sim.bench.robustness import encoder_stress as es

ENCODER_CASES = [n for n, (_, opts, _) in es.CASES.items() if opts is not None]


@pytest.mark.parametrize("name", sorted(es.CASES))
def test_case_exact_and_finite(name):
    r = es.run_case(name, threads=False)
    assert r["disagreements"] == 0
    assert r["nan"] == 0 and r["outside_range"] == 0 and r["wrong_sums"] == 0
    if es.CASES[name][1] is None or es.CASES[name][1].get("encoder", "gla") == "gla":
        assert r["blocks"] > 0  # the check ran on every block


def test_the_cases_cover_the_issue():
    """Training sets larger than the codebook where it matters, and the big one is big."""
    big, opts, _ = es.CASES["identical_million"]
    img = big(0)[0]
    assert img.shape[0] * img.shape[1] // (opts["block"][0] * opts["block"][1]) >= 1 << 20
    assert len(np.unique(img.reshape(-1, 3), axis=0)) <= 6 < opts["codebook_size"] + 3
    for name in ("large_norm_close", "noise", "row_1xN", "column_Nx1"):  # training does work
        im, o = es.build(name)[0], es.CASES[name][1]
        assert im.size // (o["block"][0] * o["block"][1] * im.shape[2]) > 2 * o["codebook_size"]
    imgs = es.build("row_1xN") + es.build("column_Nx1")
    assert {im.shape[:2] for im in imgs} == {(1, 1024), (1024, 1)}
    ex = es.build("extremes_0_255")[0]
    assert set(np.unique(ex)) == {0, 255}


@pytest.mark.parametrize("name", [n for n, (_, _, t) in es.CASES.items() if t])
def test_one_and_two_threads_give_the_same_bytes(name):
    assert es.encoded_with_threads(name, 1) == es.encoded_with_threads(name, 2)


def test_one_and_two_threads_through_the_environment(monkeypatch):
    """The fallback without threadpoolctl: a subprocess with the thread variables set."""
    import builtins
    real = builtins.__import__

    def no_threadpoolctl(name, *a, **kw):
        if name == "threadpoolctl":
            raise ImportError(name)
        return real(name, *a, **kw)

    monkeypatch.setattr(builtins, "__import__", no_threadpoolctl)
    one = es.encoded_with_threads("noise_tsvq", 1)
    assert one == es.encoded_with_threads("noise_tsvq", 2)
    monkeypatch.undo()
    assert one == es.encoded_with_threads("noise_tsvq", 1)  # and the same as in this process


# ------------------------------------------------------------------------- the checker can fail
def test_exact_nearest_breaks_ties_to_the_lowest_index():
    c = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 0.0], [1.0, 5.0]])
    x = np.array([[1.0, 0.0], [2.0, 0.0], [1.0, 4.0]])
    idx, settled = es.exact_nearest(x, c)
    np.testing.assert_array_equal(idx, [0, 1, 3])
    assert settled == 2  # the two tied rows went through the integer settling


def test_exact_nearest_sees_what_float64_cannot():
    """|x - c0|^2 = 2^54 + 2^28 + 1 and |x - c1|^2 = 2^54 + 2^28: equal in float64 (its ulp there
    is 4), so a float64 argmin says 0; in exact arithmetic c1 is nearer."""
    x = np.array([[2.0 ** 27 + 1, 0.0]])
    c = np.array([[0.0, 0.0], [1.0, 2.0 ** 14]])
    d64 = ((x - c) ** 2).sum(axis=1)
    assert d64[0] == d64[1]
    assert es.exact_nearest(x, c)[0][0] == 1
    # a true tie below float64's resolution: 1 + 2^-80 both, the lowest index
    x = np.array([[1.0, 2.0 ** -40]])
    c = np.array([[0.0, 0.0], [2.0, 2.0 ** -39]])
    assert es.exact_nearest(x, c)[0][0] == 0


def test_fractional_ties_float64_cannot_order_go_to_the_lowest_index():
    """yuv411-like float32 vectors exactly equidistant from codewords 0 and 1: float64 sums of
    squares (in order, as numpy's sum and einsum both add six terms) put some nearer 0 and some
    nearer 1; ``nearest`` names 0 for every one (it used to follow float64's rounding)."""
    x, c = es.build("nearest_fractional_ties")
    d64 = np.stack([((x - c[j]) ** 2).sum(axis=1) for j in (0, 1)])
    assert np.count_nonzero(d64[1] < d64[0]) > 0 and np.count_nonzero(d64[0] < d64[1]) > 0
    np.testing.assert_array_equal(vq.nearest(x, c)[0], 0)
    np.testing.assert_array_equal(vq.nearest(x, c[[1, 0, 2, 3]])[0], 0)  # codeword 1 first
    ref, settled = es.exact_nearest(x, c)
    assert settled == len(x) and np.all(ref == 0)


def test_integer_settling_in_chunks_is_the_same():
    """The exact settling works in chunks of whole rows: any chunk size, the same winners."""
    x, c = es.build("nearest_fractional_ties")
    r = np.repeat(np.arange(200), 4)
    cc = np.tile(np.array([3, 1, 0, 2]), 200)
    want = fullsearch.settle_in_integers(x, c, r, cc, cc)
    np.testing.assert_array_equal(want[0], np.arange(200))
    np.testing.assert_array_equal(want[1], 0)
    for elements in (1, 7, 24, 100):
        got = fullsearch.settle_in_integers(x, c, r, cc, cc, elements=elements)
        np.testing.assert_array_equal(np.concatenate(got), np.concatenate(want))
    # exact ties (codewords 0, 1 and its repeat 3) go to the least tie key, not the position
    got = fullsearch.settle_in_integers(x, c, r, cc, np.tile([2, 1, 0, 3], 200))
    np.testing.assert_array_equal(got[1], 0)
    got = fullsearch.settle_in_integers(x, c, r, cc, np.tile([0, 2, 1, 3], 200))
    np.testing.assert_array_equal(got[1], 3)


def test_a_wrong_index_is_a_disagreement():
    images = es.build("noise")
    opts = dict(block=(2, 2), codebook_size=16, color="rgb")
    ts = encode(images, **opts)
    assert es.check_encoding(ts, images, opts)["disagreements"] == 0
    n = 64 * 64
    idx = unpack_indices(ts.index_words, 4, n, 0, ts.word_bits)
    idx[[5, 77]] = (idx[[5, 77]] + 1) % 16
    ts.index_words[: -1] = pack_indices(idx, 4, ts.word_bits)
    assert es.check_encoding(ts, images, opts)["disagreements"] == 2


def test_a_tie_resolved_upwards_is_a_disagreement():
    """Two identical codewords: the block must name the lower one."""
    images = es.build("constant")
    opts = dict(block=(4, 4), codebook_size=4, color="rgb")
    ts = encode(images, **opts)
    assert np.all(ts.codebook == ts.codebook[0])  # every codeword the same: all ties
    assert es.check_encoding(ts, images, opts)["disagreements"] == 0
    ts.index_words[:] = 0
    ts.index_words[0] = 1  # the first block names codeword 1
    assert es.check_encoding(ts, images, opts)["disagreements"] == 1


# --------------------------------------------------------------------------- memory and overflow
def test_settling_near_ties_needs_no_pairs_by_dimension_copy():
    """Every codeword a candidate for every vector (d = 256, large norm after centring): the
    exact settling used to copy the vectors once per candidate pair (708 MiB here, now 144)."""
    r = np.random.default_rng(3)
    c = np.concatenate([r.integers(0, 6, (128, 256)), 250 + r.integers(0, 6, (128, 256))])
    c = c.astype(np.float64)
    x = (250 + r.integers(0, 6, (2048, 256))).astype(np.float64)
    tracemalloc.start()
    try:
        idx, _ = vq.nearest(x, c)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 300 << 20, f"peak {peak / 2**20:.0f} MiB"
    np.testing.assert_array_equal(idx, es.exact_nearest(x, c)[0])


def test_cell_sums_of_huge_weights_are_exact():
    """A million copies of one vector and a few outliers, as weights: the cell sums are exact
    integers and the codebook stays in range."""
    x = np.array([[255.0, 255.0, 0.0], [0.0, 1.0, 2.0], [3.0, 250.0, 7.0], [255.0, 254.0, 1.0]])
    w = np.array([1e6, 1.0, 1.0, 3.0])
    r = vq.gla(x, 2, weights=w)
    assert np.all(np.isfinite(r.codebook)) and np.isfinite(r.distortion)
    assert np.all((r.codebook >= x.min(0)) & (r.codebook <= x.max(0)))
    rep = es.check_design(np.repeat(x, [2000, 1, 1, 3], axis=0), 2)
    assert rep == {"nan": 0, "outside_range": 0, "wrong_sums": 0}
