"""Reference mip pyramids and the uncompressed :class:`ReferenceSource`.

The renderer asks texels of a *texture source*, any object with

    level_shapes(tex) -> [(width, height) of level 0, 1, ...]
    fetch(tex, level, i, j) -> (N, 4) uint8 RGBA     (int arrays (N,); i = column, j = row)

This module implements that protocol over uncompressed pyramids: the golden reference against which
compressed textures are measured.

Pyramid rule (the same as the extended codewords of golden.format): level n+1 texel is the rounded
mean ``(a + b + c + d + 2) >> 2`` per channel of the 2x2 texels above it. For a non-square texture,
once one side has reached 1 the other keeps halving with ``(a + b + 1) >> 1``. The pyramid goes down
to 1x1. Images are promoted to RGBA first: RGB gets A = 255, intensity I becomes (I, I, I, 255).
"""

from __future__ import annotations

from typing import Protocol, Sequence

import numpy as np

from ..mipmap import build_pyramid, downsample, to_rgba  # noqa: F401 (re-exported)

__all__ = ["TextureSource", "to_rgba", "downsample", "build_pyramid", "ReferenceSource", "VQSource"]


class TextureSource(Protocol):
    """Where the sampler's texels come from (reference pyramids, compressed TextureSet, RTL...)."""

    def level_shapes(self, tex: int) -> list[tuple[int, int]]: ...

    def fetch(self, tex, level, i, j) -> np.ndarray: ...


def _is_pow2(n: int) -> bool:
    return n >= 1 and (n & (n - 1)) == 0


class ReferenceSource:
    """The TextureSource protocol over uncompressed reference pyramids.

    All levels of all textures live in one flat (texels, 4) array; a fetch is one gather.

    Arguments:
        images: uint8 images (H, W, C), power-of-two sizes, texture id = position in the list.
        levels: optional, per texture, how many levels to keep (None: all, down to 1x1; 1: a
            texture without mipmaps).
    """

    def __init__(self, images: Sequence[np.ndarray], levels: Sequence[int | None] | None = None):
        pyramids = [build_pyramid(img) for img in images]
        if levels is not None:
            if len(levels) != len(pyramids):
                raise ValueError("one level count per texture")
            pyramids = [p if n is None else p[: max(1, int(n))] for p, n in zip(pyramids, levels)]
        self._shapes = [[(lv.shape[1], lv.shape[0]) for lv in p] for p in pyramids]
        nlev = max((len(p) for p in pyramids), default=1)
        t = len(pyramids)
        self._base = np.zeros((max(t, 1), nlev), np.int64)
        self._width = np.ones((max(t, 1), nlev), np.int64)
        self._height = np.zeros((max(t, 1), nlev), np.int64)  # 0 marks a missing level
        chunks, base = [], 0
        for k, p in enumerate(pyramids):
            for n, lv in enumerate(p):
                self._base[k, n] = base
                self._width[k, n] = lv.shape[1]
                self._height[k, n] = lv.shape[0]
                chunks.append(lv.reshape(-1, 4))
                base += lv.shape[0] * lv.shape[1]
        self._texels = np.concatenate(chunks) if chunks else np.zeros((0, 4), np.uint8)
        self.pyramids = pyramids

    @property
    def num_textures(self) -> int:
        return len(self._shapes)

    def level_shapes(self, tex: int) -> list[tuple[int, int]]:
        return list(self._shapes[tex])

    def level(self, tex: int, level: int) -> np.ndarray:
        """The RGBA array (H, W, 4) of one level."""
        return self.pyramids[tex][level]

    def fetch(self, tex, level, i, j) -> np.ndarray:
        """Texels (N, 4) uint8 at (tex, level, i, j); raises ValueError on any out-of-range request."""
        tex = np.asarray(tex, np.int64)
        level = np.asarray(level, np.int64)
        i = np.asarray(i, np.int64)
        j = np.asarray(j, np.int64)
        if tex.size == 0:
            return np.zeros((0, 4), np.uint8)
        t, n = self._base.shape
        if tex.min() < 0 or tex.max() >= self.num_textures or level.min() < 0 or level.max() >= n:
            raise ValueError("fetch: texture id or level out of range")
        w = self._width[tex, level]
        h = self._height[tex, level]
        if (i < 0).any() or (j < 0).any() or (i >= w).any() or (j >= h).any():
            raise ValueError("fetch: (i, j) outside the level (or level missing)")
        return self._texels[self._base[tex, level] + j * w + i]


class VQSource:
    """golden.render's TextureSource over a compressed TextureSet (texels from golden.fetch)."""

    def __init__(self, ts):
        self.ts = ts

    def level_shapes(self, tex: int):
        return self.ts.level_shapes(tex)

    def fetch(self, tex, level, i, j):
        from ..fetch import fetch
        return fetch(self.ts, tex, level, i, j)
