"""The functional-coverage model of the texel-fetch unit's testbench: which bin a request falls in,
and which bins a texture set can reach at all.

A request's bin is ``(colour, index width, straddle, level group)``; the testbench adds the fifth
dimension, ``stall`` (the response was held at least one cycle by ``o_ready`` low), when the
response leaves. The dimensions are the hardware paths the unit chooses between:

- ``colour``: the descriptor's colour format (``golden.constants.COLORS``: the expansion, or the
  colour matrix for ``yuv411``), or ``"raw"`` for an uncompressed level (an RGBA8888 word of the raw
  memory, whatever the texture's format: no index, no codebook, no conversion);
- ``index width``: the descriptor's ``b`` (1..16), 0 for a raw level;
- ``straddle``: the block's index crosses an index-memory word boundary (``golden.fetch.straddles``:
  both banks read), False for a raw level;
- ``level group``: which part of its level group's extended codeword the level reads, ``"sub0"``
  (the block itself), ``"sub1"``, ``"sub2"`` (its averages), or ``"raw"``.

:func:`reachable` enumerates every stored block of every stored level of a set (one texel per
block: the block's origin), so "100 % coverage" is measured against exactly what the set can
exercise, not against the product of the dimensions. :func:`candidates` gives the texels of each
bin, from which a testbench draws requests that hit a chosen bin. Numpy, vectorised over the blocks
of a level (the only loop is over the set's (texture, level) rows).
"""

from __future__ import annotations

import numpy as np

from vqtex.golden.constants import COLORS
from vqtex.golden.fetch import block_address, lookup_descriptor, straddles
from vqtex.golden.format import TextureSet

__all__ = ["DIMENSIONS", "GROUPS", "request_bins", "candidates", "reachable", "bin_name"]

#: The coverage dimensions in cross order (the testbench's fifth, ``stall``, is a bool).
DIMENSIONS = ("colour", "index_width", "straddle", "level_group", "stall")
#: The level-group bins: a level's sub-level in its group's extended codeword, or raw.
GROUPS = ("sub0", "sub1", "sub2", "raw")


def _bins_of(ts: TextureSet, d: np.ndarray, k) -> list:
    """The four request dimensions for descriptor rows ``d`` and block numbers ``k`` (raw rows:
    ``k`` is ignored)."""
    comp = d["compressed"].astype(bool)
    colour = np.where(comp, np.asarray(COLORS, dtype=object)[d["color"].astype(np.int64)], "raw")
    width = np.where(comp, d["index_bits"].astype(np.int64), 0)
    strad = comp & straddles(d, k, ts.word_bits)
    group = np.where(comp, np.asarray(GROUPS, dtype=object)[np.minimum(d["sublevel"].astype(np.int64), 2)], "raw")
    return [(str(c), int(w), bool(s), str(g)) for c, w, s, g in zip(colour, width, strad, group)]


def request_bins(ts: TextureSet, requests) -> list:
    """The bin ``(colour, index width, straddle, level group)`` of each request (N, 4) of
    (texture, level, i, j)."""
    req = np.asarray(requests, dtype=np.int64).reshape(-1, 4)
    d = lookup_descriptor(ts, req[:, 0], req[:, 1])
    k, _, _ = block_address(d, req[:, 2], req[:, 3])
    return _bins_of(ts, d, k)


def candidates(ts: TextureSet) -> dict:
    """bin -> (M, 4) int64 requests, the origin texel of every stored block of the set in that bin
    (every texel of a raw level); a request anywhere in such a block is in the same bin."""
    out: dict = {}
    for t, tex in enumerate(ts.textures):
        for level in range(tex.levels):
            d = ts.descriptors[t, level]
            if not d["valid"]:
                continue
            w, h = 1 << int(d["log2w"]), 1 << int(d["log2h"])
            bw, bh = (1 << int(d["log2bw"]), 1 << int(d["log2bh"])) if d["compressed"] else (1, 1)
            jj, ii = np.mgrid[0:h:bh, 0:w:bw]
            req = np.stack([np.full(ii.size, t), np.full(ii.size, level), ii.ravel(), jj.ravel()], 1).astype(np.int64)
            rows = lookup_descriptor(ts, req[:, 0], req[:, 1])
            k, _, _ = block_address(rows, req[:, 2], req[:, 3])
            if ts.present_blocks is not None and d["compressed"]:
                keep = ts.block_present(req[:, 0], req[:, 1], k)
                req, rows, k = req[keep], rows[keep], k[keep]
            if not len(req):
                continue
            colour, width, _, group = _bins_of(ts, rows[:1], k[:1])[0]
            strad = rows["compressed"].astype(bool) & straddles(rows, k, ts.word_bits)
            for s in (False, True):
                if (strad == s).any():
                    out.setdefault((colour, width, s, group), []).append(req[strad == s])
    return {key: np.concatenate(parts) for key, parts in out.items()}


def reachable(ts: TextureSet) -> set:
    """Every ``(colour, index width, straddle, level group, stall)`` the set can hit: the request
    bins of its stored blocks, each with ``stall`` False and True."""
    return {(*key, stall) for key in candidates(ts) for stall in (False, True)}


def bin_name(key) -> str:
    """A bin as one short string: ``yuv411/b12/straddle/sub0/stall``."""
    colour, width, strad, group, *stall = key
    parts = [colour, f"b{width}" if width else "-", "straddle" if strad else "aligned", group]
    if stall:
        parts.append("stall" if stall[0] else "flow")
    return "/".join(parts)
