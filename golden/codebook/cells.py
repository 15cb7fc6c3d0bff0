"""Cell statistics of the Lloyd iterations: weights and weighted sums per codeword, their
incremental update, and the repair of empty cells.

Contract: ``centroids(u, wu, a, k)`` returns (total weight (k,), weighted sum (k, d)) per cell;
each cell's sums depend only on its members in index order, so ``update_centroids`` and
``repair_empty`` keep untouched cells bit for bit and touched ones equal to a full
recomputation.  Sums are float64 ``np.bincount`` accumulations of weight x component: with
integer components (texels 0..255) and integer weights (counts) they are exact integers while
the total weight times 255 stays below 2^53.  ``repair_empty`` never increases the distortion.
"""
from __future__ import annotations

import numpy as np

from .screen import exact_d2

__all__ = ["centroids", "update_centroids", "repair_empty"]

def centroids(u, wu, a, k):
    """Per cell: total weight (k,) and weighted sum of the vectors (k, d).  Each cell's sum
    depends only on its members in index order, so recomputing a subset of cells gives the same
    bits as a full recomputation."""
    cnt = np.bincount(a, weights=wu, minlength=k)
    sums = np.empty((k, u.shape[1]), dtype=np.float64)
    for j in range(u.shape[1]):  # one bincount per dimension (measured faster than sorting)
        sums[:, j] = np.bincount(a, weights=wu * u[:, j], minlength=k)
    return cnt, sums


def update_centroids(u, wu, a_old, a_new, cnt, sums):
    """Update cnt and sums (in place) for the vectors that changed cell: their weight and
    weighted vector move from the old cell to the new one.  Cells that neither gained nor lost
    vectors keep their sums bit for bit (so their codewords do not "move")."""
    ch = np.flatnonzero(a_old != a_new)
    if ch.size == 0:
        return
    if 4 * ch.size > a_new.size:  # large change: recompute
        cnt[:], sums[:] = centroids(u, wu, a_new, k=cnt.shape[0])
        return
    wv = wu[ch, None] * u[ch]
    np.subtract.at(sums, a_old[ch], wv)
    np.add.at(sums, a_new[ch], wv)
    np.subtract.at(cnt, a_old[ch], wu[ch])
    np.add.at(cnt, a_new[ch], wu[ch])
    # a cell that lost all its vectors is empty: clear the rounding residue exactly (a mask, not
    # np.unique: numpy 2's np.unique imports numpy.ma, 17 ms of the encoder's process)
    lost = np.zeros(cnt.shape[0], dtype=bool)
    lost[a_old[ch]] = True
    gone = np.flatnonzero(lost & (np.bincount(a_new, minlength=cnt.shape[0]) == 0))
    cnt[gone] = 0.0
    sums[gone] = 0.0


def repair_empty(u, wu, a, c, cnt, sums, k):
    """Give every empty cell a codeword: take the cells of largest total squared error (SSE)
    and move each one's member farthest from its centroid (ties: lowest vector index) into an
    empty cell as its codeword.  Repeats while empty cells and splittable cells remain.
    Updates a, c, cnt, sums in place; never increases the distortion."""
    while True:
        empty = np.flatnonzero(cnt == 0)
        if empty.size == 0:
            return
        full = cnt > 0
        c[full] = sums[full] / cnt[full, None]
        d2 = exact_d2(u, c, a)
        sse = np.bincount(a, weights=wu * d2, minlength=k)
        sse[~full] = -1.0
        donors = np.flatnonzero(sse > 0)
        if donors.size == 0:
            return
        # largest SSE first, ties to the lowest cell index
        donors = donors[np.lexsort((donors, -sse[donors]))][: empty.size]
        empty = empty[: donors.size]
        members = np.flatnonzero(np.isin(a, donors))
        order = np.lexsort((members, -d2[members], a[members]))
        members = members[order]
        first = np.ones(members.size, dtype=bool)
        first[1:] = a[members[1:]] != a[members[:-1]]
        pick = members[first]  # farthest member of each donor, sorted by donor cell index
        dcell = a[pick]
        target = np.empty_like(dcell)
        target[np.searchsorted(dcell, donors)] = empty  # donor rank r -> r-th empty cell
        a[pick] = target
        c[target] = u[pick]
        # re-derive the touched cells exactly (bit-identical to a full recomputation)
        touched = np.zeros(k, dtype=bool)
        touched[dcell] = True
        touched[target] = True
        sel = touched[a]
        cnt_t, sums_t = centroids(u[sel], wu[sel], a[sel], k)
        cnt[touched] = cnt_t[touched]
        sums[touched] = sums_t[touched]
