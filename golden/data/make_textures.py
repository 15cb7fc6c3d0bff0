"""Development-time tool: regenerate the bundled texture PNGs of golden/data/ from scikit-image's
sample images (public-domain / CC0 photographs, see LICENSE-textures.md).

    python golden/data/make_textures.py

Needs scikit-image (the ``bench`` extra); nothing at run time uses this script or scikit-image:
the renderer only reads the PNGs it wrote. Output is deterministic.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from vqtex.golden.render.imageio import write_image

HERE = Path(__file__).resolve().parent


def fit(img: np.ndarray, width: int, height: int) -> np.ndarray:
    """Centre-crop to the target aspect ratio, then resize with anti-aliasing (uint8 out)."""
    from skimage.transform import resize

    h, w = img.shape[:2]
    target = width / height
    if w / h > target:
        cw = int(round(h * target))
        x0 = (w - cw) // 2
        img = img[:, x0:x0 + cw]
    else:
        ch = int(round(w / target))
        y0 = (h - ch) // 2
        img = img[y0:y0 + ch]
    out = resize(img, (height, width) + img.shape[2:], anti_aliasing=True, preserve_range=True, order=1)
    return np.clip(np.rint(out), 0, 255).astype(np.uint8)


def tint(grey: np.ndarray, rgb, lo=0.0, hi=1.0) -> np.ndarray:
    """A grey image coloured towards ``rgb`` with its contrast mapped to [lo, hi]."""
    g = grey.astype(np.float64) / 255.0
    g = lo + (hi - lo) * g
    return np.clip(np.rint(g[..., None] * np.asarray(rgb, np.float64)[None, None]), 0, 255).astype(np.uint8)


def road(gravel: np.ndarray, crossing: bool = False) -> np.ndarray:
    """Asphalt from the gravel photo; lane markings along t (rows), or zebra stripes across."""
    img = tint(gravel, (150, 150, 155), 0.25, 0.7).astype(np.float64)
    h, w = img.shape[:2]
    x = np.arange(w)[None, :] + 0.5
    y = np.arange(h)[:, None] + 0.5
    if not crossing:
        center = (np.abs(x - w / 2) < w / 64 + 0.5) & ((y % (h / 2)) < h / 4)
        edges = (np.abs(x - w * 0.06) < w / 90 + 0.5) | (np.abs(x - w * 0.94) < w / 90 + 0.5)
        img[np.broadcast_to(center, img.shape[:2])] = (230, 190, 40)
        img[np.broadcast_to(edges, img.shape[:2])] = (225, 225, 225)
    else:
        stripes = ((x // (w / 8)) % 2 == 0) & (y > h * 0.15) & (y < h * 0.85)
        img[np.broadcast_to(stripes, img.shape[:2])] = img[np.broadcast_to(stripes, img.shape[:2])] * 0.2 + 200
    return np.clip(np.rint(img), 0, 255).astype(np.uint8)


def sidewalk(gravel: np.ndarray) -> np.ndarray:
    img = tint(gravel, (200, 196, 188), 0.6, 0.95).astype(np.float64)
    h, w = img.shape[:2]
    x = np.arange(w)[None, :]
    y = np.arange(h)[:, None]
    joints = (x % (w // 2) < 2) | (y % (h // 2) < 2)
    img[np.broadcast_to(joints, img.shape[:2])] *= 0.55
    return np.clip(np.rint(img), 0, 255).astype(np.uint8)


def with_round_alpha(img: np.ndarray) -> np.ndarray:
    """RGBA: opaque inside a centred disc with a soft 2-texel edge, transparent outside."""
    h, w = img.shape[:2]
    y, x = np.mgrid[0:h, 0:w] + 0.5
    r = np.hypot((x - w / 2) / (w / 2), (y - h / 2) / (h / 2))
    a = np.clip((1.0 - r) * (w / 4), 0, 1)
    return np.concatenate([img, np.rint(a * 255).astype(np.uint8)[..., None]], 2)


def arrow_sign(size: int = 64) -> np.ndarray:
    """A white arrow on a blue rounded plate, transparent around it (RGBA)."""
    y, x = (np.mgrid[0:size, 0:size] + 0.5) / size
    plate = (np.maximum(np.abs(x - 0.5), np.abs(y - 0.5)) < 0.46)
    rgb = np.zeros((size, size, 3))
    rgb[:] = (30, 80, 180)
    shaft = (np.abs(y - 0.5) < 0.09) & (x > 0.18) & (x < 0.62)
    head = (x >= 0.55) & (x < 0.84) & (np.abs(y - 0.5) < (0.84 - x) * 0.9)
    rgb[shaft | head] = (245, 245, 245)
    alpha = np.where(plate, 255, 0)
    return np.concatenate([rgb, alpha[..., None]], 2).astype(np.uint8)


def main() -> None:
    import skimage.data as d

    out = {
        # signs and billboards (RGB)
        "astronaut.png": fit(d.astronaut(), 256, 256),
        "coffee.png": fit(d.coffee(), 256, 128),
        "chelsea.png": fit(d.chelsea(), 128, 128),
        "rocket.png": fit(d.rocket(), 64, 128),
        "ihc.png": fit(d.immunohistochemistry(), 128, 128),
        "hubble.png": fit(d.hubble_deep_field(), 128, 128),
        "coins.png": fit(d.coins(), 128, 64),
        # roads
        "road.png": road(fit(d.gravel(), 128, 128)),
        "crossing.png": road(fit(d.gravel()[::-1], 128, 128), crossing=True),
        "sidewalk.png": sidewalk(fit(d.gravel().T, 128, 128)),
        # everything else (RGB)
        "brick_red.png": tint(fit(d.brick(), 128, 128), (255, 140, 110), 0.25, 0.95),
        "stone.png": tint(fit(d.gravel(), 64, 64), (230, 215, 190), 0.5, 1.0),
        "lawn.png": tint(fit(d.grass(), 128, 128), (120, 200, 90), 0.3, 1.0),
        # intensity (one channel)
        "brick.png": fit(d.brick(), 128, 128),
        "gravel.png": fit(d.gravel(), 128, 128),
        "grass.png": fit(d.grass(), 128, 128),
        "camera.png": fit(d.camera(), 128, 128),
        # RGBA
        "cat_badge.png": with_round_alpha(fit(d.chelsea(), 128, 128)),
        "arrow.png": arrow_sign(64),
    }
    for name, img in out.items():
        write_image(HERE / name, img)
        print(f"{name}: {img.shape[1]}x{img.shape[0]}x{img.shape[2] if img.ndim == 3 else 1}")


if __name__ == "__main__":
    main()
