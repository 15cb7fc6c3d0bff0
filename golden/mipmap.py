"""The box-filtered mip pyramid, shared by the encoder and the renderer's reference textures.

Level n+1 texel = ``(a+b+c+d+2) >> 2`` per channel of the 2x2 texels of level n; once one side of a
non-square texture is 1, pairs along the other side are averaged, ``(a+b+1) >> 1``. The same rule
(:func:`box_down`) makes the 2x2 and 1x1 parts of the paper's extended codewords.
"""

from __future__ import annotations

import numpy as np

__all__ = ["to_rgba", "box_down", "downsample", "build_pyramid"]


def to_rgba(image: np.ndarray) -> np.ndarray:
    """Promote a uint8 image (H, W), (H, W, 1), (H, W, 2), (H, W, 3) or (H, W, 4) to RGBA (H, W, 4):
    grey is replicated, a missing alpha is 255.

    Raises
    ------
    ValueError
        If the array is not a uint8 image of that shape.
    """
    img = np.asarray(image)
    if img.dtype != np.uint8:
        raise ValueError(f"expected a uint8 image, got {img.dtype}")
    if img.ndim == 2:
        img = img[:, :, None]
    if img.ndim != 3 or img.shape[2] not in (1, 2, 3, 4):
        raise ValueError(f"expected (H, W) or (H, W, C) with C in 1..4, got shape {img.shape}")
    h, w, c = img.shape
    out = np.empty((h, w, 4), np.uint8)
    out[:, :, :3] = img[:, :, :1] if c <= 2 else img[:, :, :3]
    out[:, :, 3] = img[:, :, c - 1] if c in (2, 4) else 255
    return out


def box_down(a: np.ndarray) -> np.ndarray:
    """Halve each of the two leading axes that is longer than 1 by the rounded mean (int64 result;
    any trailing axes are carried along)."""
    a = np.asarray(a).astype(np.int64)
    h, w = a.shape[:2]
    fy, fx = (2 if h > 1 else 1), (2 if w > 1 else 1)
    n = fy * fx
    s = a.reshape(h // fy, fy, w // fx, fx, *a.shape[2:]).sum(axis=(1, 3))
    return (s + n // 2) // n


def downsample(level: np.ndarray) -> np.ndarray:
    """One pyramid step of a uint8 (H, W, C) level with H or W > 1."""
    if level.shape[0] == 1 and level.shape[1] == 1:
        raise ValueError("a 1x1 level has no smaller level")
    return box_down(level).astype(np.uint8)


def build_pyramid(image: np.ndarray, levels: int | None = None) -> list[np.ndarray]:
    """Levels 0.. down to 1x1 (or ``levels`` of them), RGBA uint8 (H_L, W_L, 4), of a power-of-two
    image (any channel count :func:`to_rgba` accepts)."""
    level = to_rgba(image)
    h, w = level.shape[:2]
    if (w & (w - 1)) or (h & (h - 1)):
        raise ValueError(f"texture size {w}x{h} is not a power of two")
    out = [level]
    while max(out[-1].shape[:2]) > 1 and (levels is None or len(out) < levels):
        out.append(downsample(out[-1]))
    return out
