"""The TSVQ's batched splits (golden.codebook.split.split_padded, the tree's speculative
batches) give the splits and the tree of the plain one-leaf-at-a-time greedy rule."""
import heapq

import numpy as np
import pytest

from vqtex.golden.codebook import inputs, split, tree


def _data(seed, n=1500, d=12, centres=60):
    rng = np.random.default_rng(seed)
    cen = rng.uniform(0, 255, (centres, d))
    return np.clip(np.rint(cen[rng.integers(0, centres, n)] + rng.normal(0, 8, (n, d))), 0, 255)


@pytest.mark.parametrize("seed", [0, 1])
def test_split_padded_equals_split_cell(seed):
    """Cells of 2..300 rows, padded into one group, split as split_cell splits each alone."""
    rng = np.random.default_rng(seed)
    u, w = _data(seed), rng.integers(1, 4, 1500).astype(np.float64)
    sizes = np.concatenate([[2, 3], rng.integers(2, 300, 30)])
    cells = [rng.choice(u.shape[0], s, replace=False) for s in sizes]
    idx = np.zeros((sizes.size, sizes.max()), dtype=np.int64)
    for q, r in enumerate(cells):
        idx[q, :r.size], idx[q, r.size:] = r, r[0]
    cents = np.array([inputs.wmean(u[r], w[r]) for r in cells])
    v0 = rng.standard_normal(cents.shape)
    got = split.split_padded(u, w, idx, sizes, cents, v0)
    for q, r in enumerate(cells):
        ref = split.split_cell(u[r], w[r], cents[q], v0[q], None, sample=10**9)
        assert got[q] is not None and ref is not None
        np.testing.assert_array_equal(got[q][0], ref[0])
        for a, b in zip(got[q][1:], ref[1:]):
            np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-6)


def _greedy(u, w, k, seed):
    """The paper's greedy rule, one leaf at a time (split_cell on every leaf, no sampling)."""
    v0 = np.random.default_rng(seed).standard_normal((2 * k + 1, u.shape[1]))
    rows, left, heap = [np.arange(u.shape[0])], [-1], []
    cent = [inputs.wmean(u, w)]
    heapq.heappush(heap, (-float(w @ ((u - cent[0]) ** 2).sum(1)), 0))
    leaves = 1
    while leaves < k and heap:
        _, nid = heapq.heappop(heap)
        r = split.split_cell(u[rows[nid]], w[rows[nid]], cent[nid], v0[nid], None, sample=10**9)
        if r is None:
            continue
        mask, c0, c1, e0, e1 = r
        left[nid] = len(cent)
        for part, c, e in ((rows[nid][~mask], c0, e0), (rows[nid][mask], c1, e1)):
            if part.size > 1:
                heapq.heappush(heap, (-e, len(cent)))
            rows.append(part)
            cent.append(c)
            left.append(-1)
        leaves += 1
    return np.array(left), np.array(cent)


@pytest.mark.parametrize("k", [7, 64, 300])
def test_batched_tree_is_the_greedy_tree(k):
    """The speculative batches (every leaf above the (k-1)-th largest error split at once, in
    padded groups, on two threads) build the tree of the one-at-a-time greedy rule."""
    from vqtex.golden.codebook.workers import using_threads
    _, _, u, w, _ = inputs.prepare(_data(3), None)
    left, cent = _greedy(u, w, k, seed=5)
    with using_threads(2):
        t, labels = tree.tsvq_build(u, w, k, 5, sample=10**9, dtype=np.float64)
    np.testing.assert_array_equal(t.left, left)
    np.testing.assert_allclose(t.centroids, cent, rtol=1e-9, atol=1e-6)
    assert (t.leaf >= 0).sum() == k and np.bincount(labels, minlength=k).min() >= 1


def test_float32_groups_split_like_float64():
    """The TSVQ's float32 groups cut the cells as float64 does, up to rows at the cut."""
    rng = np.random.default_rng(4)
    u, w = _data(4), np.ones(1500)
    sizes = rng.integers(2, 300, 40)
    idx = np.array([np.resize(rng.choice(1500, s, replace=False), sizes.max()) for s in sizes])
    cents = np.array([u[r[:s]].mean(0) for r, s in zip(idx, sizes)])
    v0 = rng.standard_normal(cents.shape)
    a = split.split_padded(u, w, idx, sizes, cents, v0)
    b = split.split_padded(u.astype(np.float32), w, idx, sizes, cents, v0)
    same = sum(int((ra[0] == rb[0]).sum()) for ra, rb in zip(a, b))
    assert same >= 0.99 * sizes.sum()
    for ra, rb in zip(a, b):
        assert rb[1].dtype == np.float64 and rb[2].dtype == np.float64
        if np.array_equal(ra[0], rb[0]):
            for xa, xb in zip(ra[1:], rb[1:]):
                np.testing.assert_allclose(xb, xa, rtol=1e-4, atol=1e-2)


def test_float32_tree_codes_as_well_and_centroids_are_means():
    """The default (float32) tree: leaves' centroids are the float64 means of their vectors, a
    one-row leaf's is that row, and it codes within 1% of the float64 tree."""
    _, _, u, w, _ = inputs.prepare(_data(6, n=3000), None)
    t32, lab = tree.tsvq_build(u, w, 256, 0)
    t64, _ = tree.tsvq_build(u, w, 256, 0, dtype=np.float64)
    means = np.array([np.average(u[lab == j], axis=0, weights=w[lab == j]) for j in range(256)])
    np.testing.assert_allclose(t32.codebook, means, rtol=0, atol=1e-9)
    one = np.bincount(lab, minlength=256) == 1
    assert one.any()
    np.testing.assert_array_equal(t32.codebook[one], u[np.isin(lab, np.flatnonzero(one))][
        np.argsort(lab[np.isin(lab, np.flatnonzero(one))], kind="stable")])
    err = [float(w @ ((u - t.codebook[t.encode(u)]) ** 2).sum(1)) for t in (t32, t64)]
    assert err[0] <= 1.01 * err[1]


def test_rows_equal_in_float32_still_split():
    """Distinct float64 vectors that float32 cannot tell apart (offsets of 1e-6 on 1000s) still
    give k distinct TSVQ codewords: such cells are split in float64."""
    rng = np.random.default_rng(0)
    base = rng.integers(0, 4, (50, 3)).astype(np.float64) * 1000.0 + 1000.0
    tiny = np.array([[0, 0, 0], [1e-6, 0, 0], [0, 1e-6, 0], [0, 0, 1e-6]])
    x = np.repeat(base, 4, axis=0) + np.tile(tiny, (50, 1))
    assert len(np.unique(x.astype(np.float32), axis=0)) < 64 <= len(np.unique(x, axis=0))
    c = tree.tsvq(x, 64, seed=0)
    assert len(np.unique(c, axis=0)) == 64
