"""Inputs of the sampler and the texture filter for tests (not a test module): fragments at given
texture coordinates (``fragments``) and filter pixels weighted to the hard cases (``edge_pixels``)."""

from __future__ import annotations

import numpy as np

from vqtex.golden import filter as spec
from vqtex.golden.render.raster import Fragments

__all__ = ["fragments", "edge_pixels"]


def fragments(s, t, w=None, tex=None, d=(0.0, 0.0, 0.0, 0.0)):
    """Fragments at texture coordinates ``s``, ``t`` (rows of ``w`` pixels), texture ``tex`` (default 0),
    derivatives ``d`` (ds/dx, dt/dx, ds/dy, dt/dy) in every one."""
    s = np.asarray(s, float)
    t = np.asarray(t, float)
    n = len(s)
    w = w or n
    z = np.zeros(n)
    return Fragments(w, (n + w - 1) // w, np.arange(n), np.zeros(n, np.int64),
                     np.zeros(n, np.int64) if tex is None else np.asarray(tex, np.int64),
                     s, t, z + d[0], z + d[1], z + d[2], z + d[3])


def edge_pixels(table: spec.LevelTable, frac: int, n: int, seed: int) -> dict:
    """Random pixels weighted to the hard cases: s and t on texel edges and centres of every level,
    at 0, +-1, +-2 and just inside; lod at exact level boundaries, at the last level, 0 (magnification)."""
    rng = np.random.default_rng(seed)
    tex = rng.integers(0, len(table.last), n)
    last = table.last[tex]
    one = 1 << frac

    def coord():
        k = rng.integers(0, 4, n)
        lg = rng.integers(0, frac - spec.FRAC_BITS + 1, n)       # a texel (or half-texel) grid of 2^lg
        grid = (rng.integers(-2 << lg, (2 << lg) + 1) << (frac - lg)) >> rng.integers(0, 2, n)
        near = rng.choice([-one, 0, one, 2 * one, -2 * one + 1, 2 * one - 1, one - 1, -1], n)
        return np.clip(np.select([k == 0, k == 1, k == 2],
                                 [grid, grid + rng.choice([-1, 1], n), near],
                                 rng.integers(-2 * one, 2 * one + 1, n)), -2 * one, 2 * one)
    lod = np.select([rng.random(n) < 0.25, rng.random(n) < 0.33, rng.random(n) < 0.5],
                    [last << spec.FRAC_BITS, (rng.integers(0, 16, n) % (last + 1)) << spec.FRAC_BITS, 0],
                    rng.integers(0, 1 << 12, n) % ((last << spec.FRAC_BITS) + 1))
    return {"texture": tex, "s": coord(), "t": coord(), "lod": lod, "mode": rng.integers(0, 3, n),
            "address_s": rng.integers(0, 3, n), "address_t": rng.integers(0, 3, n)}
