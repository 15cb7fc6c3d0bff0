"""golden.codebook: nearest, TSVQ, GLA, design -- contracts and degenerate inputs."""
import numpy as np
import pytest

from vqtex.golden import codebook as cb
from vqtex.golden.codebook import cells, inputs


def _brute(x, c):
    d = ((x[:, None, :].astype(np.float64) - c[None, :, :]) ** 2).sum(-1)
    return d.argmin(1), d.min(1)  # argmin: first (lowest) index among ties


def _clusters(seed=0, n=3000, d=12, centres=40, spread=6.0):
    rng = np.random.default_rng(seed)
    cen = rng.uniform(0, 255, (centres, d))
    lab = rng.integers(0, centres, n)
    return np.clip(np.rint(cen[lab] + rng.normal(0, spread, (n, d))), 0, 255)


# ------------------------------------------------------------------------------------ nearest
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_nearest_matches_brute_force(seed):
    rng = np.random.default_rng(seed)
    x = rng.normal(0, 50, (700, 7))
    c = rng.normal(0, 50, (37, 7))
    idx, d2 = cb.nearest(x, c, chunk=64)
    ref_i, ref_d = _brute(x, c)
    assert idx.dtype == np.int64 and d2.dtype == np.float64
    assert idx.shape == (700,) and d2.shape == (700,)
    np.testing.assert_array_equal(idx, ref_i)
    np.testing.assert_allclose(d2, ref_d, rtol=1e-12, atol=1e-9)


def test_nearest_ties_go_to_lowest_index():
    rng = np.random.default_rng(5)
    # integer data: every float64 distance is exact, so ties are real ties
    c = rng.integers(0, 256, (50, 12)).astype(np.float64)
    c = np.concatenate([c, c[::-1]])  # every codeword twice
    x = np.concatenate([c, rng.integers(0, 256, (500, 12)).astype(np.float64)])
    # vectors exactly halfway between two codewords (even coordinate differences)
    a = np.arange(12.0) * 2
    b = a + 2 * np.eye(12)[3] * 5
    c2 = np.concatenate([c, b[None], a[None]])
    x2 = np.concatenate([x, ((a + b) / 2)[None]])
    for xs, cs in ((x, c), (x2, c2)):
        idx, d2 = cb.nearest(xs, cs)
        ref_i, ref_d = _brute(xs, cs)
        np.testing.assert_array_equal(idx, ref_i)
        np.testing.assert_array_equal(d2, ref_d)
    assert cb.nearest(x2[-1:], c2)[0][0] == 100  # b (index 100) before a (101), same distance


def test_nearest_large_offsets_and_near_ties():
    # far from the origin with tiny gaps: float32 screening alone would get these wrong
    rng = np.random.default_rng(3)
    base = rng.uniform(0, 255, (1, 16)) + 1e4
    c = base + rng.normal(0, 1e-2, (64, 16))
    x = base + rng.normal(0, 1e-2, (400, 16))
    idx, _ = cb.nearest(x, c)
    np.testing.assert_array_equal(idx, _brute(x, c)[0])


# ------------------------------------------------------------------------------- determinism
def test_deterministic_for_a_seed():
    x = _clusters(1, n=4000)
    r1 = cb.gla(x, 32, seed=7)
    r2 = cb.gla(x.copy(), 32, seed=7)
    assert r1.codebook.tobytes() == r2.codebook.tobytes()
    np.testing.assert_array_equal(r1.indices, r2.indices)
    assert r1.distortion == r2.distortion and r1.history == r2.history
    t1 = cb.tsvq(x, 32, seed=3)
    assert t1.tobytes() == cb.tsvq(x, 32, seed=3).tobytes()
    c1, i1 = cb.design(x, 16, method="tsvq", seed=2)
    c2, i2 = cb.design(x, 16, method="tsvq", seed=2)
    assert c1.tobytes() == c2.tobytes() and np.array_equal(i1, i2)


def test_subsampled_path_is_deterministic_and_sane():
    x = _clusters(2, n=40000, d=6, centres=16, spread=10.0)
    r1 = cb.gla(x, 16, seed=1, subsample=1024)  # > 1.5 * 16384 distinct: coarse phase
    r2 = cb.gla(x, 16, seed=1, subsample=1024)
    assert r1.codebook.tobytes() == r2.codebook.tobytes()
    full = cb.gla(x, 16, seed=1, subsample=0)
    assert r1.distortion <= 1.05 * full.distortion


# ---------------------------------------------------------------------------------------- GLA
def test_gla_contract_and_monotone():
    x = _clusters(4, n=3000, d=12, centres=60)
    r = cb.gla(x, 24, seed=0)
    assert r.codebook.shape == (24, 12) and r.codebook.dtype == np.float64
    assert r.indices.shape == (3000,) and r.indices.dtype == np.int64
    h = np.array(r.history)
    assert np.all(np.diff(h) <= 0), "distortion increased"
    idx, d2 = cb.nearest(x, r.codebook)
    np.testing.assert_array_equal(r.indices, idx)  # exact full-search nearest
    assert r.distortion == pytest.approx(d2.mean(), rel=1e-12)
    assert r.distortion <= h[-1] * (1 + 1e-12)
    assert r.converged and r.iterations >= 1


@pytest.mark.parametrize("migrate", [0, 8])
def test_gla_beats_its_tsvq_init(migrate):
    x = _clusters(5, n=2500, d=12, centres=80, spread=12.0)
    init = cb.tsvq(x, 32, seed=0)
    d_init = cb.nearest(x, init)[1].mean()
    r = cb.gla(x, 32, seed=0, migrate=migrate)
    assert r.history[0] == pytest.approx(d_init, rel=1e-12)
    assert r.distortion <= d_init
    r2 = cb.gla(x, 32, seed=0, init=init, migrate=migrate)
    assert r2.distortion <= d_init


def test_gla_weights_equal_duplicates():
    rng = np.random.default_rng(8)
    u = rng.integers(0, 256, (300, 6)).astype(np.float64)
    cnt = rng.integers(1, 4, 300)
    dup = np.repeat(u, cnt, axis=0)
    a = cb.gla(dup, 12, seed=1)
    b = cb.gla(u, 12, seed=1, weights=cnt)
    np.testing.assert_array_equal(a.codebook, b.codebook)
    assert a.distortion == pytest.approx(b.distortion, rel=1e-12)


def test_gla_iteration_cap():
    x = _clusters(6, n=3000, d=8, centres=100, spread=15.0)
    r = cb.gla(x, 40, max_iter=2, migrate=0, tol=0.0)
    assert r.iterations == 2 and not r.converged


# ----------------------------------------------------------------------- empty cells, outliers
def _green_brown(seed=0):
    rng = np.random.default_rng(seed)
    green = np.array([60, 160, 50.0]) + rng.normal(0, 4, (1000, 3))
    brown = np.array([120, 80, 40.0]) + rng.normal(0, 2, (5, 3))
    return np.clip(np.rint(np.concatenate([green, brown])), 0, 255), np.array([120, 80, 40.0])


@pytest.mark.parametrize("k", [2, 3, 4])
def test_rare_outlier_cluster_survives(k):
    x, brown = _green_brown()
    for r in (cb.gla(x, k), cb.gla(x, k, migrate=0)):
        assert np.min(np.linalg.norm(r.codebook - brown, axis=1)) < 10
    assert np.min(np.linalg.norm(cb.tsvq(x, k) - brown, axis=1)) < 10


@pytest.mark.parametrize("k", [2, 3, 4])
def test_empty_cell_repair_keeps_outlier(k):
    # every initial codeword on green: all but one cell start empty; repair must split the cell of
    # largest error (the one holding the brown vectors) at its farthest member
    x, brown = _green_brown(1)
    init = np.tile(x[:1000].mean(0), (k, 1))
    r = cb.gla(x, k, init=init, migrate=0)
    assert np.min(np.linalg.norm(r.codebook - brown, axis=1)) < 10
    assert np.all(np.diff(r.history) <= 0)
    assert len(np.unique(r.indices)) == k


def test_repair_prefers_largest_error_over_most_populated():
    # cell A: 2000 tight vectors (small total error); cell B: 40 spread vectors (large error).
    rng = np.random.default_rng(2)
    a = 100 + rng.normal(0, 0.5, (2000, 3))
    b = np.concatenate([200 + rng.normal(0, 1, (20, 3)), 20 + rng.normal(0, 1, (20, 3))])
    x = np.concatenate([a, b])
    u, wu, _ = cb.unique_weighted(x + 0.0, np.ones(len(x)))
    lab = (np.abs(u - 100).max(1) > 10).astype(np.int64)  # 0: cell A, 1: cell B, 2: empty
    cnt, sums = cells.centroids(u, wu, lab, 3)
    c = np.zeros((3, 3))
    cells.repair_empty(u, wu, lab, c, cnt, sums, 3)
    far_b = np.min(np.linalg.norm(c[2] - np.array([[200.0] * 3, [20.0] * 3]), axis=1))
    assert far_b < 10  # new codeword taken from the spread cell B, not the populous A


# -------------------------------------------------------------------------- degenerate inputs
@pytest.mark.parametrize("method", ["gla", "tsvq"])
def test_constant_input_is_exact(method):
    x = np.full((500, 12), 37.0)
    c, idx = cb.design(x, 8, method=method)
    assert c.shape == (8, 12)
    np.testing.assert_array_equal(c, 37.0)
    np.testing.assert_array_equal(idx, 0)


@pytest.mark.parametrize("method", ["gla", "tsvq"])
def test_fewer_distinct_than_k_is_exact(method):
    rng = np.random.default_rng(9)
    distinct = rng.uniform(0, 255, (5, 4))
    x = distinct[rng.integers(0, 5, 800)]
    c, idx = cb.design(x, 16, method=method, seed=3)
    assert c.shape == (16, 4)
    assert len(np.unique(c, axis=0)) == 5
    for v in distinct:  # every distinct vector is a codeword, bit for bit
        assert np.any(np.all(c == v, axis=1))
    np.testing.assert_array_equal(c[idx], x)
    r = cb.gla(x, 16)
    assert r.distortion == 0.0


@pytest.mark.parametrize("method", ["gla", "tsvq"])
def test_two_colours(method):
    x = np.array([[0.0, 0, 0], [255.0, 255, 255]])[np.arange(301) % 2]
    c, idx = cb.design(x, 2, method=method)
    np.testing.assert_array_equal(c[idx], x)
    c4, idx4 = cb.design(x, 4, method=method)
    np.testing.assert_array_equal(c4[idx4], x)
    assert c4.shape == (4, 3)


@pytest.mark.parametrize("method", ["gla", "tsvq"])
def test_n_smaller_than_k(method):
    rng = np.random.default_rng(4)
    x = rng.integers(0, 256, (7, 12)).astype(np.float64)
    c, idx = cb.design(x, 64, method=method)
    assert c.shape == (64, 12)
    np.testing.assert_array_equal(c[idx], x)


def test_extreme_values_0_and_255():
    rng = np.random.default_rng(11)
    x = rng.choice([0.0, 255.0], size=(3000, 12))
    r = cb.gla(x, 64, seed=0)
    assert np.all(r.codebook >= 0) and np.all(r.codebook <= 255)
    np.testing.assert_array_equal(r.indices, cb.nearest(x, r.codebook)[0])
    few = x[:20].copy()
    few[:10] = 0.0
    few[10:] = 255.0
    for method in ("gla", "tsvq"):
        c, idx = cb.design(few, 4, method=method)  # 2 distinct vectors: exact
        np.testing.assert_array_equal(c[idx], few)


def test_k_one_and_bad_input():
    x = _clusters(7, n=200, d=3)
    r = cb.gla(x, 1)
    np.testing.assert_allclose(r.codebook[0], x.mean(0), rtol=1e-12)
    with pytest.raises(ValueError):
        cb.gla(x, 0)
    with pytest.raises(ValueError):
        cb.nearest(x, np.zeros((3, 4)))
    with pytest.raises(ValueError):
        cb.gla(np.array([[np.nan, 1.0]]), 2)
    with pytest.raises(ValueError):
        cb.design(x, 4, method="kmeans")


# ---------------------------------------------------------------------------------------- TSVQ
@pytest.mark.parametrize("k", [2, 17, 64, 200])
def test_tsvq_distinct_codewords(k):
    x = _clusters(8, n=2000, d=6, centres=30)
    c = cb.tsvq(x, k, seed=1)
    assert c.shape == (k, 6) and c.dtype == np.float64
    assert len(np.unique(c, axis=0)) == k


def test_tsvq_tree_encode_and_greedy_rule():
    x = _clusters(9, n=3000, d=12, centres=50)
    tree = cb.tsvq_tree(x, 32, seed=0)
    np.testing.assert_array_equal(tree.codebook, cb.tsvq(x, 32, seed=0))
    idx = tree.encode(x)
    assert idx.shape == (3000,) and idx.min() >= 0 and idx.max() < 32
    full = cb.nearest(x, tree.codebook)[1].mean()
    tree_d = ((x - tree.codebook[idx]) ** 2).sum(1).mean()
    assert full <= tree_d <= 2.0 * full  # tree search: never better than full search
    assert tree.depth >= 5
    gain = cb.tsvq_tree(x, 32, seed=0, criterion="gain")
    assert len(np.unique(gain.codebook, axis=0)) == 32


def test_rare_outlier_survives_the_coarse_phase():
    # 2 brown vectors among 40000 green ones: the coarse phase's sample (16384 of them) misses
    # both for about a third of the seeds; the full-data phase (repair, migration) must still
    # give them a codeword
    rng = np.random.default_rng(12)
    green = np.array([60, 160, 50.0]) + rng.normal(0, 1, (40000, 3))
    brown = np.array([120, 80, 40.0]) + rng.normal(0, 2, (2, 3))
    x = np.concatenate([green, brown])
    for seed in range(4):
        r = cb.gla(x, 8, seed=seed, subsample=2048)
        assert np.min(np.linalg.norm(r.codebook - [120, 80, 40.0], axis=1)) < 10


def test_dedup_hash_collision_fallback(monkeypatch):
    rng = np.random.default_rng(13)
    x = rng.integers(0, 4, (500, 3)).astype(np.float64)
    ref_u, ref_inv = np.unique(x, axis=0, return_inverse=True)
    monkeypatch.setattr(inputs, "row_hash", lambda v: np.zeros(v.shape[0], dtype=np.uint64))
    u, wu, inv = cb.unique_weighted(x, np.ones(500))
    np.testing.assert_array_equal(u[inv], x)
    assert len(u) == len(ref_u) and wu.sum() == 500


def test_zero_weights_get_an_index_but_do_not_train():
    x = np.concatenate([_clusters(14, n=600, d=4, centres=6), np.full((3, 4), 1000.0)])
    w = np.concatenate([np.ones(600), np.zeros(3)])
    r = cb.gla(x, 6, weights=w)
    assert np.all(r.codebook < 400)  # the far, weight-0 vectors pulled nothing
    np.testing.assert_array_equal(r.indices, cb.nearest(x, r.codebook)[0])
    assert r.distortion == pytest.approx(np.average(cb.nearest(x, r.codebook)[1], weights=w))


def test_nearest_with_many_repeated_codewords():
    rng = np.random.default_rng(15)
    c = np.repeat(rng.uniform(0, 255, (3, 12)), 700, axis=0)  # 2100 rows, 3 distinct
    x = rng.uniform(0, 255, (20000, 12))
    idx, d2 = cb.nearest(x, c)
    ref = cb.nearest(x, c[::700])[0] * 700  # lowest index of each repeated codeword
    np.testing.assert_array_equal(idx, ref)


# ------------------------------------------------------------------------ the stored codebook
def _rounded(c):
    return np.clip(np.rint(c), 0, 255)


@pytest.mark.parametrize("case", ["integers", "fractions", "coarse", "few-distinct", "zero-weights"])
def test_gla_stored_indices_are_the_nearest_stored_codewords(case):
    """gla(..., stored=f): the indices and distortion are those of f(codebook), exactly as
    nearest(vectors, f(codebook)) gives them (ties to the lowest index: rounding makes duplicate
    codewords), and the codebook and history are the design's, as without ``stored``."""
    w = None
    store = _rounded
    if case == "integers":
        x = _clusters(21, n=4000, d=12, centres=80, spread=9.0)
    elif case == "fractions":                      # yuv411-like vectors: quarter values
        x = np.rint(_clusters(22, n=4000, d=6, centres=50, spread=7.0) * 4) / 4
    elif case == "coarse":                         # a coarse phase on a sample, and ties after storing
        x = _clusters(23, n=20000, d=4, centres=300, spread=3.0)
        store = lambda c: np.rint(c / 64) * 64    # noqa: E731  (5 values a component: duplicate codewords)
    elif case == "few-distinct":
        x = np.repeat(np.arange(10.0)[:, None] * 25.3, 3, axis=1)[np.arange(500) % 10]
    else:
        x = np.concatenate([_clusters(24, n=3000, d=12, centres=40), np.full((4, 12), 600.0)])
        w = np.concatenate([np.ones(3000), np.zeros(4)])
    k = {"few-distinct": 16, "coarse": 256}.get(case, 64)
    plain = cb.gla(x, k, seed=3, weights=w)
    r = cb.gla(x, k, seed=3, weights=w, stored=store)
    np.testing.assert_array_equal(r.codebook, plain.codebook)
    assert r.history == plain.history and r.iterations == plain.iterations
    idx, d2 = cb.nearest(x, store(r.codebook))
    np.testing.assert_array_equal(r.indices, idx)
    assert r.distortion == pytest.approx(np.average(d2, weights=w), rel=1e-12)
    code, idx_d = cb.design(x, k, seed=3, weights=w, stored=store)
    np.testing.assert_array_equal(idx_d, idx)
    if case == "coarse":
        assert len(np.unique(store(r.codebook), axis=0)) < k   # the ties were there to settle


def test_gla_stored_must_keep_the_shape():
    x = _clusters(25, n=500, d=4, centres=10)
    with pytest.raises(ValueError, match="stored"):
        cb.gla(x, 8, stored=lambda c: c[:4])
    with pytest.raises(ValueError, match="stored"):
        cb.gla(x, 8, stored=lambda c: np.full_like(c, np.nan))
