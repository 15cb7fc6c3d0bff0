"""Request streams for tests: random (golden's), adversarial (every corner, every straddle
position), back to back (straddling texels in a row, repeats, alternating textures)."""

from __future__ import annotations

import numpy as np

from vqtex.golden.fetch import block_address, lookup_descriptor, random_requests, straddles
from vqtex.golden.format import TextureSet

from .sets import levels

__all__ = ["random_requests", "adversarial_requests", "straddle_offsets", "back_to_back_requests"]


def adversarial_requests(ts: TextureSet, seed: int = 0) -> np.ndarray:
    """Every corner of every level; the first and last block's corners; for every compressed level,
    a texel of blocks whose index starts at every bit offset of a word (every straddle position)."""
    rng = np.random.default_rng(seed)
    out = []
    for t, L, w, h in levels(ts):
        for i, j in ((0, 0), (w - 1, 0), (0, h - 1), (w - 1, h - 1)):
            out.append((t, L, i, j))
        d = ts.descriptor(t, L)
        if not d["compressed"]:
            out.append((t, L, int(rng.integers(0, w)), int(rng.integers(0, h))))
            continue
        bw, bh = 1 << d["log2bw"], 1 << d["log2bh"]
        nbx, nby = w // bw, h // bh
        # first and last block: their far corners too
        out += [(t, L, bw - 1, bh - 1), (t, L, w - bw, h - bh)]
        # blocks 0 .. W-1 cover every offset k*b mod W (one per offset class)
        b, W = d["index_bits"], ts.word_bits
        seen = set()
        for k in range(min(nbx * nby, W)):
            off = (k * b) % W
            if off in seen:
                continue
            seen.add(off)
            bx, by = k % nbx, k // nbx
            out.append((t, L, bx * bw + int(rng.integers(0, bw)), by * bh + int(rng.integers(0, bh))))
    req = np.array(out, dtype=np.int64)
    return req[rng.permutation(len(req))]


def straddle_offsets(ts: TextureSet, req: np.ndarray) -> set:
    """Bit offsets (k*b mod W) at which the compressed requests' indices start."""
    d = lookup_descriptor(ts, req[:, 0], req[:, 1])
    comp = d["compressed"].astype(bool)
    k, _, _ = block_address(d[comp], req[comp, 2], req[comp, 3])
    return set(((k * d[comp]["index_bits"].astype(np.int64)) % ts.word_bits).tolist())


def back_to_back_requests(ts, limit=200):
    """Texels whose index straddles a word boundary (back to back), the corners of every level,
    the same texel repeated, and textures alternating every request."""
    rows = []
    for t, info in enumerate(ts.textures):
        for L in range(info.levels):
            d = ts.descriptors[t, L]
            w, h = 1 << int(d["log2w"]), 1 << int(d["log2h"])
            rows += [[t, L, 0, 0], [t, L, w - 1, h - 1], [t, L, w - 1, 0], [t, L, 0, h - 1]]
            if d["compressed"]:
                jj, ii = np.mgrid[0:h, 0:w]
                req = np.stack([np.full(w * h, t), np.full(w * h, L), ii.ravel(), jj.ravel()], 1)
                dd = lookup_descriptor(ts, req[:, 0], req[:, 1])
                k, _, _ = block_address(dd, req[:, 2], req[:, 3])
                s = req[straddles(dd, k, ts.word_bits)]
                rows += s[:: max(1, len(s) // 12)][:12].tolist()
    rows += [rows[0]] * 5
    alt = random_requests(ts, 20, seed=7)
    rows += alt.tolist()
    return np.array(rows[:limit] if len(rows) > limit else rows, dtype=np.int64)
