"""How every codec row is measured: wall times, PSNR, random texel coordinates and the physical floor.

* **Times** are wall-clock seconds (``time.perf_counter``), the minimum over ``repeats`` runs of the
  same call (the usual way to time code on a shared machine: noise only ever adds time).
* **PSNR** = 10 log10(255^2 / MSE) over every R, G and B sample of the image, the decoded image
  rounded and clipped to uint8 first (as the encoder benchmark counts it).
* **One random texel** is timed over a batch of ``n`` random texels at once (vectorised numpy, or a
  library decoding the ``n`` blocks that hold them) and divided by ``n``: the amortised cost of one.
  The coordinates come from :func:`random_texels` (seeded, the same for every codec of an image).
* **The physical floor** is what any format costs at least once its texels are in memory, measured
  the same way as the codec: :func:`copy_floor` copies the decoded bytes (the floor of a
  whole-image decode), :func:`gather_floor` reads the same ``n`` random texels from a decoded
  (H, W, 3) uint8 array (the floor of a random texel).
"""

from __future__ import annotations

import time

import numpy as np

__all__ = ["best_time", "psnr", "random_texels", "copy_floor", "gather_floor", "RANDOM_TEXELS"]

#: Random texels per batch for the amortised random-texel cost.
RANDOM_TEXELS = 16384


def best_time(fn, repeats: int):
    """``(result of the last call, minimum wall seconds)`` over ``repeats`` calls of ``fn()``."""
    best = float("inf")
    out = None
    for _ in range(max(1, int(repeats))):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return out, best


def psnr(image: np.ndarray, decoded: np.ndarray) -> float:
    """PSNR in dB of ``decoded`` (H, W, >=3) against ``image`` (H, W, 3) uint8 over R, G and B;
    ``inf`` when they are equal."""
    err = decoded[..., :3].astype(np.float64) - image[..., :3]
    mse = float(np.mean(err * err))
    return float("inf") if mse == 0 else float(10 * np.log10(255.0 ** 2 / mse))


def random_texels(shape, n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """``(y, x)`` int64 arrays of ``n`` uniformly random texel coordinates inside an image of ``shape``."""
    rng = np.random.default_rng(seed)
    h, w = shape[:2]
    return rng.integers(0, h, n), rng.integers(0, w, n)


def copy_floor(decoded: np.ndarray, repeats: int) -> float:
    """Seconds to copy the decoded image's bytes once (the floor of a whole-image decode)."""
    src = np.ascontiguousarray(decoded)
    dst = np.empty_like(src)
    return best_time(lambda: np.copyto(dst, src), repeats)[1]


def gather_floor(decoded: np.ndarray, y: np.ndarray, x: np.ndarray, repeats: int) -> float:
    """Seconds per texel to read the texels (y, x) from a decoded (H, W, C) array, amortised over the
    batch (the floor of a random texel, measured as the codecs' random texels are)."""
    return best_time(lambda: decoded[y, x], repeats)[1] / len(y)
