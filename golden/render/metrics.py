"""Frame metrics.

``frame_mse(a, b)``: the paper's measure: per channel, the squared differences summed over the
frame's pixels and divided by the pixel count, then averaged over R, G and B (alpha is ignored).
"""

from __future__ import annotations

import numpy as np

__all__ = ["frame_mse", "frame_psnr"]


def frame_mse(a: np.ndarray, b: np.ndarray) -> float:
    """Mean squared error of two frames (H, W, 3 or 4) over R, G, B."""
    a = np.asarray(a)
    b = np.asarray(b)
    if a.shape[:2] != b.shape[:2] or a.ndim != 3 or b.ndim != 3 or min(a.shape[2], b.shape[2]) < 3:
        raise ValueError(f"frames must be (H, W, 3|4) of the same size, got {a.shape} and {b.shape}")
    d = a[:, :, :3].astype(np.int64) - b[:, :, :3].astype(np.int64)
    per_channel = (d * d).sum(axis=(0, 1)) / (a.shape[0] * a.shape[1])
    return float(per_channel.mean())


def frame_psnr(a: np.ndarray, b: np.ndarray) -> float:
    """PSNR in dB from frame_mse (inf for identical frames)."""
    mse = frame_mse(a, b)
    return float("inf") if mse == 0 else float(10 * np.log10(255.0**2 / mse))
