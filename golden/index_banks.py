"""Index memory banked by block parity: the paper's even/odd index banks, generalised for a texture
filter that fetches the four texels of a 2x2 footprint in one cycle.

The four texels of a bilinear footprint lie in at most four blocks, one per combination of block
column and block row parity ``(bx & 1, by & 1)``: two neighbouring texel columns are in the same
block or in neighbouring block columns (levels and blocks are powers of two, so a wrap from the last
block column to the first also changes parity when there are two or more; clamp and mirror repeat
the edge texel, the same block). So an index memory split into four banks by ``bank = (bx & 1) |
(by & 1) << 1`` serves a footprint in one cycle: each bank is read once, by the texels of one block
(texels in the same block share the read). Two banks by column parity serve the horizontal pairs of a
two-lane filter. Total index storage is one copy, where one reader per lane needs a copy per lane.

Bank ``p`` holds, for every level group (one index map, shared by the group's levels), the indices
of the blocks of parity ``p``, numbered ``k'`` densely (:func:`bank_address`: the map of the half or
quarter grid, in the map's own order, row-major or PowerVR2 twiddled), packed as
:func:`golden.format.pack_indices` packs a map. Every bank gives a group the same base word ``base'``
(the regions are as long as the largest bank's), so one descriptor column serves the four banks.

Twin of :mod:`hw.filter.index_banks` (the banks' block RAMs and the lanes' crossbar). The mapping is
computed from the block number ``k`` the block address shifter already produces and the level's
grid, so the hardware needs no second address computation.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .fetch import block_address, lookup_descriptor, read_index
from .format import FormatError, LAYOUT_CODES, TextureSet, pack_indices, unpack_indices

__all__ = ["BANK_COUNTS", "bank_address", "BankedIndex", "banked_index", "read_banked_index", "lane_banks",
           "conflicts"]

#: Bank counts: 1 (one map, the paper's unit), 2 (by block column parity), 4 (column and row parity).
BANK_COUNTS = (1, 2, 4)


def bank_address(k, gw, gh, twiddled, banks: int):
    """(bank, k') of block number ``k`` of a map of ``2**gw x 2**gh`` blocks (``gw = log2w - log2bw``,
    ``gh = log2h - log2bh``; ``twiddled`` true for a PowerVR2 map), vectorised.

    Row-major map: ``bx = k mod 2**gw``, ``by = k >> gw``; 4 banks: ``bank = (bx & 1) | (by & 1) << 1``,
    ``k' = (by >> 1) << max(gw - 1, 0) | (bx >> 1)``; 2 banks: ``bank = bx & 1``,
    ``k' = by << max(gw - 1, 0) | (bx >> 1)``. Twiddled map (bits of ``by`` and ``bx`` interleaved,
    ``by`` bit 0 at bit 0): with both sides at least two blocks, ``bank`` from bits 1 and 0 of ``k`` and
    ``k'`` the remaining bits in order (``k >> 2``; 2 banks: ``(k >> 2) << 1 | (k & 1)``); a grid one
    block wide or high is a strip along one axis, numbered by that axis. The row-major map of a linear
    level only needs ``gw`` (``gh`` is ignored there). ``banks`` 1: ``(0, k)``.
    """
    if banks not in BANK_COUNTS:
        raise ValueError(f"banks must be one of {BANK_COUNTS}, not {banks!r}")
    k = np.asarray(k, np.int64)
    gw = np.asarray(gw, np.int64)
    gh = np.asarray(gh, np.int64)
    tw = np.asarray(twiddled, bool)
    if banks == 1:
        return np.zeros_like(k), k.copy()
    bx = k & ((np.int64(1) << gw) - 1)
    by = k >> gw
    hx = np.maximum(gw - 1, 0)
    if banks == 4:
        bank = (bx & 1) | ((by & 1) << 1)
        kq = ((by >> 1) << hx) | (bx >> 1)
    else:
        bank = bx & 1
        kq = (by << hx) | (bx >> 1)
    # PowerVR2 twiddled maps: squares interleave by (bit 0) and bx (bit 1); strips count one axis
    square = (gw >= 1) & (gh >= 1)
    x_strip = ~square & (gh == 0)               # 2**gw x 1 (and 1 x 1): k counts bx
    if banks == 4:
        t_bank = np.where(square, ((k >> 1) & 1) | ((k & 1) << 1), np.where(x_strip, k & 1, (k & 1) << 1))
        t_kq = np.where(square, k >> 2, k >> 1)
    else:
        t_bank = np.where(square, (k >> 1) & 1, np.where(x_strip, k & 1, 0))
        t_kq = np.where(square, ((k >> 2) << 1) | (k & 1), np.where(x_strip, k >> 1, k))
    return np.where(tw, t_bank, bank), np.where(tw, t_kq, kq)


@dataclass(frozen=True)
class BankedIndex:
    """An index memory in ``banks`` banks.

    Members
    -------
    banks : int
    words : list of ndarray
        Each bank's memory image (``<u{W/8}`` words, the same length, a zero word at the end).
    base : ndarray (n_textures, MAX_LEVELS) int64
        ``base'``: the word of each compressed level's group in every bank (raw levels keep their raw
        memory base, other rows 0).
    word_bits : int
    """
    banks: int
    words: list
    base: np.ndarray
    word_bits: int

    def view(self, ts: TextureSet) -> TextureSet:
        """``ts`` with the banked bases in its descriptor table: what the lanes of a banked filter
        hold (their block address and descriptor fields are the set's; the index memory is the
        banks'). Its ``index_words`` are zeros as long as ``ts``'s or the banks' (whichever is
        longer), so that the set still validates and the base column keeps its width."""
        d = ts.descriptors.copy()
        d["base"] = self.base.astype(d["base"].dtype)
        length = max(len(ts.index_words), len(self.words[0]))
        return replace(ts, descriptors=d, index_words=np.zeros(length, ts.index_words.dtype))


def _groups(ts: TextureSet):
    """(base, gw, gh, twiddled, b) of every level group (the distinct bases of the compressed levels),
    checked to agree across the group's levels."""
    d = ts.descriptors
    rows = d[(d["valid"] != 0) & (d["compressed"] != 0)]
    gw = rows["log2w"].astype(np.int64) - rows["log2bw"]
    gh = rows["log2h"].astype(np.int64) - rows["log2bh"]
    tw = rows["layout"].astype(np.int64) == LAYOUT_CODES["pvr2"]
    key = np.stack([rows["base"].astype(np.int64), gw, gh, tw, rows["index_bits"].astype(np.int64)], 1)
    groups = np.unique(key, axis=0)
    if len(np.unique(groups[:, 0])) != len(groups):
        raise FormatError("levels sharing an index map disagree on its grid, layout or index width")
    return groups


def banked_index(ts: TextureSet, banks: int) -> BankedIndex:
    """The index memory of ``ts`` in ``banks`` banks (see the module docstring). Every bank's map of a
    group holds the index of each block of that parity at ``k'`` (:func:`bank_address`); positions
    no block maps to (a grid one block wide has no odd column) hold 0."""
    if banks not in BANK_COUNTS:
        raise ValueError(f"banks must be one of {BANK_COUNTS}, not {banks!r}")
    wb = ts.word_bits
    dtype = ts.index_words.dtype
    parts = [[] for _ in range(banks)]
    new_base = {}
    at = 0
    for base, gw, gh, tw, b in _groups(ts).tolist():     # a loop over level groups, not blocks
        k = np.arange(1 << (gw + gh), dtype=np.int64)
        idx = unpack_indices(ts.index_words, b, len(k), base, wb)
        bank, kq = bank_address(k, gw, gh, tw, banks)
        n = int(kq.max()) + 1
        nwords = -(-(n * b) // wb)
        for p in range(banks):
            sub = np.zeros(n, np.int64)
            sub[kq[bank == p]] = idx[bank == p]
            packed = pack_indices(sub, b, wb)
            parts[p].append(np.concatenate([packed, np.zeros(nwords - len(packed), dtype)]))
        new_base[base] = at
        at += nwords
    zero = np.zeros(1, dtype)
    words = [np.concatenate(p + [zero]).astype(dtype) for p in parts]
    d = ts.descriptors
    comp = (d["valid"] != 0) & (d["compressed"] != 0)
    base = np.where(d["valid"] != 0, d["base"].astype(np.int64), 0)
    if comp.any():
        keys = np.array(sorted(new_base), np.int64)
        vals = np.array([new_base[x] for x in keys.tolist()], np.int64)
        base = np.where(comp, vals[np.minimum(np.searchsorted(keys, base), len(keys) - 1)], base)
    return BankedIndex(banks, words, base, wb)


def read_banked_index(ts: TextureSet, bi: BankedIndex, tex, level, i, j) -> np.ndarray:
    """The index of each request's block read through the banks: bank ``p``'s image read at
    ``base'`` and ``k'`` as :func:`golden.fetch.read_index` reads a map (equals ``read_index`` of
    ``ts``: the test of the layout)."""
    tex = np.asarray(tex, np.int64)
    level = np.asarray(level, np.int64)
    d = lookup_descriptor(ts, tex, level)
    k, _, _ = block_address(d, i, j)
    gw = d["log2w"].astype(np.int64) - d["log2bw"]
    gh = d["log2h"].astype(np.int64) - d["log2bh"]
    bank, kq = bank_address(k, gw, gh, d["layout"] == LAYOUT_CODES["pvr2"], bi.banks)
    banked = d.copy()
    banked["base"] = bi.base[tex, level]
    out = np.zeros(len(k), np.int64)
    for p in range(bi.banks):                   # a loop over the (at most four) banks
        sel = bank == p
        out[sel] = read_index(replace(ts, index_words=bi.words[p]), banked[sel], kq[sel])
    return out


def lane_banks(lanes: int) -> int:
    """Banks a set of lanes reads: 1 lane 1, 2 lanes 2 (a horizontal pair), 4 and 8 lanes 4 per
    set of four (a 2x2 footprint each)."""
    return {1: 1, 2: 2, 4: 4, 8: 4}[lanes]


def conflicts(ts: TextureSet, tex, level, i, j, lanes: int) -> int:
    """Bank conflicts of a filter's groups: ``level``, ``i``, ``j`` are (M, SLOTS) texel slots as
    :func:`golden.filter.footprint` returns them (``tex`` (M,)); the lanes take ``lanes`` slots per
    group, each set of ``lane_banks(lanes)`` lanes reading its own banks. A conflict is a group in
    which two lanes of a set need the same bank for different blocks (0 for every footprint: the
    parity argument of the module docstring; the count is the check)."""
    level = np.asarray(level, np.int64)
    m, slots = level.shape
    tex2 = np.broadcast_to(np.asarray(tex, np.int64)[:, None], level.shape)
    d = lookup_descriptor(ts, tex2.ravel(), level.ravel())
    k, _, _ = block_address(d, np.asarray(i).ravel(), np.asarray(j).ravel())
    gw = d["log2w"].astype(np.int64) - d["log2bw"]
    gh = d["log2h"].astype(np.int64) - d["log2bh"]
    nb = lane_banks(lanes)
    bank, _ = bank_address(k, gw, gh, d["layout"] == LAYOUT_CODES["pvr2"], nb)
    comp = d["compressed"] != 0
    # a block is named by (level, k); sets of nb consecutive slots share banks
    bank = bank.reshape(m, slots // nb, nb)
    block = (level.ravel() * (1 << 25) + k).reshape(m, slots // nb, nb)
    comp = comp.reshape(m, slots // nb, nb)
    same_bank = (bank[..., :, None] == bank[..., None, :]) & comp[..., :, None] & comp[..., None, :]
    clash = same_bank & (block[..., :, None] != block[..., None, :])
    return int(clash.any(axis=(-1, -2)).sum())
