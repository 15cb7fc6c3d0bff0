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
        t, labels = tree.tsvq_build(u, w, k, 5, sample=10**9)
    np.testing.assert_array_equal(t.left, left)
    np.testing.assert_allclose(t.centroids, cent, rtol=1e-9, atol=1e-6)
    assert (t.leaf >= 0).sum() == k and np.bincount(labels, minlength=k).min() >= 1
