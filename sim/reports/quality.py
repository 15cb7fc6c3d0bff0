"""Seeing the compression error: PSNR per texture and mip level, difference heat maps and the
side-by-side picture (uncompressed | compressed | difference). numpy only (no plotting library).

The difference of two RGBA images is, per pixel, the largest absolute difference over R, G and B
(0..255). A heat map shows it on a fixed scale, 0 (black) through red and yellow to ``vmax`` and
above (white), so pictures of different frames compare; the scale is drawn as a strip under the
map with a tick every quarter of ``vmax``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["texture_psnr", "difference", "heat", "heat_with_scale", "side_by_side", "HEAT_STOPS", "DEFAULT_VMAX"]

#: The heat map's colours at 0, 1/3, 2/3 and 1 of its scale.
HEAT_STOPS = np.array([[0, 0, 0], [200, 0, 0], [255, 210, 0], [255, 255, 255]], np.float64)
#: The default top of the scale: a difference of 32 levels or more is white.
DEFAULT_VMAX = 32


def _psnr(mse: float) -> float | None:
    return None if mse == 0 else round(float(10 * np.log10(255.0**2 / mse)), 3)


def texture_psnr(ts, images) -> list[dict]:
    """Per texture ``k`` of ``ts`` (encoded from ``images[k]``): its PSNR in dB against the
    uncompressed image, per stored level, over the channels its colour format holds (R, G, B; alpha
    too for rgba; the one intensity channel). ``None`` (JSON null) when a level is exact (raw levels are).

    Returns ``[{"texture", "name", "psnr_db": [per level], "raw_levels": [...]}]``.
    """
    from vqtex.golden.encode import reference_pyramid
    from vqtex.golden.fetch import decode
    out = []
    for k, (info, img) in enumerate(zip(ts.textures, images)):
        pyramid = reference_pyramid(img, info.color, info.mipmapped)
        channels = {"rgba": slice(0, 4), "intensity": slice(0, 1)}.get(info.color, slice(0, 3))
        levels = []
        for level in range(min(info.levels, len(pyramid))):
            d = decode(ts, k, level)[..., channels].astype(np.int64) - pyramid[level][..., channels]
            levels.append(_psnr(float((d * d).mean())))
        out.append({"texture": k, "name": info.name, "psnr_db": levels,
                    "raw_levels": [L for L in range(len(levels)) if not ts.descriptors[k, L]["compressed"]]})
    return out


def difference(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Per pixel the largest absolute difference over R, G, B of two (H, W, >=3) uint8 images; (H, W) uint8."""
    a, b = np.asarray(a), np.asarray(b)
    if a.shape[:2] != b.shape[:2] or a.ndim != 3 or b.ndim != 3 or min(a.shape[2], b.shape[2]) < 3:
        raise ValueError(f"images must be (H, W, 3|4) of the same size, got {a.shape} and {b.shape}")
    return np.abs(a[..., :3].astype(np.int16) - b[..., :3]).max(axis=2).astype(np.uint8)


def heat(diff: np.ndarray, vmax: int = DEFAULT_VMAX) -> np.ndarray:
    """The heat-map colours (H, W, 3) uint8 of a difference map on the scale 0..``vmax``."""
    t = np.clip(np.asarray(diff, np.float64) / vmax, 0, 1) * (len(HEAT_STOPS) - 1)
    i = np.minimum(t.astype(np.int64), len(HEAT_STOPS) - 2)
    f = (t - i)[..., None]
    return np.rint(HEAT_STOPS[i] * (1 - f) + HEAT_STOPS[i + 1] * f).astype(np.uint8)


def heat_with_scale(diff: np.ndarray, vmax: int = DEFAULT_VMAX) -> np.ndarray:
    """:func:`heat` with its scale under it: a gap, a strip running 0..``vmax`` left to right, and a
    white tick every quarter of the scale. (H + 16, W, 3) uint8."""
    h, w = diff.shape
    strip = np.repeat(heat(np.linspace(0, vmax, w))[None], 10, axis=0)
    for q in range(5):
        x = min(w - 1, round(q * (w - 1) / 4))
        strip[:3, max(0, x - 1): x + 1] = (0, 160, 255)
    gap = np.full((6, w, 3), 255, np.uint8)
    return np.concatenate([heat(diff, vmax), gap, strip])


def side_by_side(reference: np.ndarray, image: np.ndarray, vmax: int = DEFAULT_VMAX) -> np.ndarray:
    """One RGB picture: the uncompressed ``reference``, the compressed ``image`` and their difference
    as a heat map with its scale, left to right, 8 white pixels apart."""
    h, w = image.shape[:2]
    pad = lambda a: np.concatenate([a, np.full((16, w, 3), 255, np.uint8)])           # noqa: E731
    gap = np.full((h + 16, 8, 3), 255, np.uint8)
    return np.concatenate([pad(reference[..., :3]), gap, pad(image[..., :3]), gap,
                           heat_with_scale(difference(image, reference), vmax)], axis=1)
