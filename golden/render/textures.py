"""Procedural textures: wood, marble, checker, stripes; bricks, facade, noise and cutout (the many
textures of the paper-sized town scene, ``town-paper``).

Every generator is vectorised, deterministic for a given (size, seed, parameters) and *tileable*
(the noise is periodic over the image), so the textures can be used with wrap addressing without
seams. Each returns a uint8 RGB image (height, width, 3), except ``cutout``, which returns RGBA
(height, width, 4) with a transparent surround. ``size`` is (width, height).

    generate(name, size, seed, **params)   dispatches by name; ``GENERATORS`` lists the names.
"""

from __future__ import annotations

import inspect

import numpy as np

__all__ = ["GENERATORS", "generate", "periodic_noise", "fbm", "wood", "marble", "checker", "stripes",
           "bricks", "facade", "noise", "cutout"]


def periodic_noise(width: int, height: int, cells: int, rng: np.random.Generator) -> np.ndarray:
    """Smooth value noise in [0, 1), (height, width) float64, periodic with the image size.

    A lattice of ``cells`` x ``cells`` random values is interpolated with a smoothstep; the lattice
    wraps around, so the result tiles.
    """
    cells = max(1, int(cells))
    lattice = rng.random((cells, cells))
    x = (np.arange(width) + 0.5) * (cells / width)
    y = (np.arange(height) + 0.5) * (cells / height)
    x0 = np.floor(x).astype(np.int64)
    y0 = np.floor(y).astype(np.int64)
    fx = x - x0
    fy = y - y0
    fx = fx * fx * (3 - 2 * fx)
    fy = fy * fy * (3 - 2 * fy)
    x0 %= cells
    y0 %= cells
    x1 = (x0 + 1) % cells
    y1 = (y0 + 1) % cells
    top = lattice[y0][:, x0] * (1 - fx) + lattice[y0][:, x1] * fx
    bot = lattice[y1][:, x0] * (1 - fx) + lattice[y1][:, x1] * fx
    return top * (1 - fy)[:, None] + bot * fy[:, None]


def fbm(width: int, height: int, rng: np.random.Generator, base_cells: int = 4, octaves: int = 5) -> np.ndarray:
    """Fractal sum of periodic value noise, normalised to [0, 1]."""
    total = np.zeros((height, width))
    amp, norm = 1.0, 0.0
    for k in range(octaves):
        total += amp * periodic_noise(width, height, base_cells << k, rng)
        norm += amp
        amp *= 0.5
    return total / norm


def _grid(width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """Texel-centre coordinates u, v in [0, 1), each (height, width)."""
    u = (np.arange(width) + 0.5) / width
    v = (np.arange(height) + 0.5) / height
    return np.broadcast_to(u[None, :], (height, width)), np.broadcast_to(v[:, None], (height, width))


def _ramp(t: np.ndarray, colors: np.ndarray) -> np.ndarray:
    """Piecewise-linear colour ramp of t in [0, 1] through ``colors`` (K, 3)."""
    colors = np.asarray(colors, np.float64)
    k = len(colors) - 1
    x = np.clip(t, 0, 1) * k
    i = np.minimum(np.floor(x).astype(np.int64), k - 1)
    f = (x - i)[..., None]
    return colors[i] * (1 - f) + colors[i + 1] * f


def _to_u8(rgb: np.ndarray) -> np.ndarray:
    return np.clip(np.rint(rgb), 0, 255).astype(np.uint8)


def wood(size=(256, 256), seed=0, planks: int = 4, rings: int = 6) -> np.ndarray:
    """Wooden floor boards: ``planks`` boards across u, growth rings and grain along v."""
    w, h = size
    rng = np.random.default_rng(seed)
    u, v = _grid(w, h)
    board = np.minimum((u * planks).astype(np.int64), planks - 1)
    phase = rng.random(planks)[board]
    tint = (0.85 + 0.3 * rng.random(planks))[board]
    warp = fbm(w, h, rng, base_cells=4, octaves=4)
    across = u * planks - board  # position across the board in [0, 1)
    ring = across * rings + phase * rings + 2.0 * warp + 0.5 * np.sin(2 * np.pi * v * 2 + phase * 6.28)
    ring = ring - np.floor(ring)
    profile = ring**3  # late wood: sharp dark band
    grain = periodic_noise(w, h, 64, rng)
    t = np.clip(0.7 * profile + 0.3 * grain, 0, 1)
    light = np.array([206, 156, 100])
    dark = np.array([120, 72, 36])
    rgb = _ramp(t, np.stack([light, (light + dark) / 2, dark])) * tint[..., None]
    # dark gap between boards
    gap = np.minimum(across, 1 - across) * w / planks < 1.0
    rgb[gap] *= 0.45
    return _to_u8(rgb)


def marble(size=(256, 256), seed=0, veins: int = 3, turbulence: float = 8.0) -> np.ndarray:
    """White marble with dark, turbulent veins (the classic sin(x + turbulence) recipe)."""
    w, h = size
    rng = np.random.default_rng(seed)
    u, v = _grid(w, h)
    turb = fbm(w, h, rng, base_cells=2, octaves=6)
    kx, ky = int(veins), int(max(1, veins // 2))
    m = np.sin(2 * np.pi * (kx * u + ky * v) + turbulence * turb)
    t = np.abs(m) ** 0.35  # veins are where m is near zero
    colors = np.array([[60, 64, 70], [150, 150, 150], [222, 220, 214], [245, 243, 238]])
    speck = periodic_noise(w, h, 32, rng)
    rgb = _ramp(t, colors) * (0.94 + 0.06 * speck)[..., None]
    return _to_u8(rgb)


def checker(size=(64, 64), seed=0, squares: int = 8, colors=None) -> np.ndarray:
    """A checkerboard of ``squares`` x ``squares``; ``colors`` two RGB triples (default from seed)."""
    w, h = size
    if colors is None:
        rng = np.random.default_rng(seed)
        hue = rng.random(3) * 255 if seed else np.array([230.0, 230.0, 230.0])
        colors = [np.clip(hue, 0, 255), [25, 25, 25]]
    colors = np.asarray(colors, np.float64)
    if colors.shape != (2, 3):
        raise ValueError("checker: colors must be two RGB triples")
    i = (np.arange(w) * squares) // w
    j = (np.arange(h) * squares) // h
    parity = (i[None, :] + j[:, None]) & 1
    return _to_u8(colors[parity])


def stripes(size=(256, 256), seed=0, bands: int = 6, sectors: int = 8) -> np.ndarray:
    """A toy top's livery: colour bands along v, every other band split into ``sectors`` along u."""
    w, h = size
    rng = np.random.default_rng(seed)
    palette = rng.integers(40, 256, size=(bands, 3)).astype(np.float64)
    palette[::2] = palette[::2] * 0.5 + 120  # alternate saturated / pastel bands
    u, v = _grid(w, h)
    band = np.minimum((v * bands).astype(np.int64), bands - 1)
    sector = np.minimum((u * sectors).astype(np.int64), sectors - 1)
    rgb = palette[band].copy()
    odd = (band & 1).astype(bool) & (sector & 1).astype(bool)
    rgb[odd] = 255 - rgb[odd]
    edge = np.abs(v * bands - np.rint(v * bands)) * h / bands < 0.75
    rgb[edge] = (30, 30, 30)
    return _to_u8(rgb * (0.9 + 0.1 * periodic_noise(w, h, 16, rng))[..., None])


def _two_colors(rng: np.random.Generator, colors) -> np.ndarray:
    """``colors`` as a (2, 3) float array, or two random related colours (dark, light) from ``rng``."""
    if colors is None:
        base = rng.integers(60, 230, size=3).astype(np.float64)
        return np.stack([base * 0.45, np.minimum(255, base * 1.1 + 20)])
    colors = np.asarray(colors, np.float64)
    if colors.shape != (2, 3):
        raise ValueError("colors must be two RGB triples")
    return colors


def noise(size=(128, 128), seed=0, cells: int = 4, octaves: int = 5, colors=None) -> np.ndarray:
    """Fractal noise ramped between two colours (asphalt, concrete, grass, dirt, plaster)."""
    w, h = size
    rng = np.random.default_rng(seed)
    c = _two_colors(rng, colors)
    t = fbm(w, h, rng, base_cells=int(cells), octaves=int(octaves))
    t = (t - t.min()) / max(1e-9, np.ptp(t))
    return _to_u8(_ramp(t, c))


def bricks(size=(128, 128), seed=0, rows: int = 8, cols: int = 4, mortar: float = 0.08, colors=None) -> np.ndarray:
    """A running-bond brick wall: ``rows`` courses of ``cols`` bricks, each brick its own shade,
    light mortar joints ``mortar`` of a brick's height wide; ``colors`` (brick, mortar)."""
    w, h = size
    rng = np.random.default_rng(seed)
    c = np.asarray(colors, np.float64) if colors is not None else \
        np.stack([rng.integers(90, 200, 3).astype(np.float64) * np.array([1.0, 0.55, 0.45]), [200, 196, 186]])
    if c.shape != (2, 3):
        raise ValueError("bricks: colors must be two RGB triples")
    rows, cols = max(1, int(rows)), max(1, int(cols))
    u, v = _grid(w, h)
    y = v * rows
    course = np.minimum(y.astype(np.int64), rows - 1)
    x = u * cols + 0.5 * (course & 1)
    brick = (np.floor(x).astype(np.int64) % cols) + cols * course
    fx, fy = x - np.floor(x), y - course
    joint = (np.minimum(fy, 1 - fy) < mortar / 2) | (np.minimum(fx, 1 - fx) < mortar * cols / rows / 2)
    shade = 0.8 + 0.4 * rng.random(rows * cols)[brick]
    grain = 0.85 + 0.3 * fbm(w, h, rng, base_cells=8, octaves=3)
    rgb = c[0] * (shade * grain)[..., None]
    rgb[joint] = c[1] * grain[joint][..., None]
    return _to_u8(rgb)


def facade(size=(128, 128), seed=0, floors: int = 4, windows: int = 3, colors=None) -> np.ndarray:
    """A building front: a plastered wall (``colors`` (wall, glass)) with ``floors`` x ``windows``
    framed windows, some lit."""
    w, h = size
    rng = np.random.default_rng(seed)
    c = np.asarray(colors, np.float64) if colors is not None else \
        np.stack([rng.integers(120, 235, 3).astype(np.float64), rng.integers(20, 90, 3).astype(np.float64)])
    if c.shape != (2, 3):
        raise ValueError("facade: colors must be two RGB triples")
    floors, windows = max(1, int(floors)), max(1, int(windows))
    u, v = _grid(w, h)
    fx, fy = u * windows - np.floor(u * windows), v * floors - np.floor(v * floors)
    cell = np.floor(v * floors).astype(np.int64) * windows + np.floor(u * windows).astype(np.int64)
    pane = (np.abs(fx - 0.5) < 0.28) & (np.abs(fy - 0.55) < 0.3)
    frame = (np.abs(fx - 0.5) < 0.33) & (np.abs(fy - 0.55) < 0.35) & ~pane
    lit = rng.random(floors * windows)[cell] < 0.3
    wall = c[0] * (0.85 + 0.25 * fbm(w, h, rng, base_cells=4, octaves=4))[..., None]
    glass = np.where(lit[..., None], np.array([235.0, 215.0, 140.0]), c[1]) * \
        (0.8 + 0.2 * fy[..., None])
    rgb = np.where(pane[..., None], glass, wall)
    rgb[frame] = (235, 235, 230)
    return _to_u8(rgb)


def cutout(size=(128, 128), seed=0, sides: int = 0, rings: int = 2, colors=None) -> np.ndarray:
    """An RGBA sign: a disc (``sides`` = 0) or regular polygon with ``rings`` coloured bands
    (``colors`` (outer, inner)), transparent outside with a one-texel soft edge."""
    w, h = size
    rng = np.random.default_rng(seed)
    c = _two_colors(rng, colors)
    u, v = _grid(w, h)
    x, y = 2 * u - 1, 2 * v - 1
    r = np.hypot(x, y)
    sides = int(sides)
    if sides >= 3:   # distance to a regular polygon's edge, as a radius
        a = np.arctan2(y, x) % (2 * np.pi / sides) - np.pi / sides
        r = r * np.cos(a) / np.cos(np.pi / sides)
    band = np.minimum((r * max(1, int(rings)) * 1.05).astype(np.int64), 64)
    rgb = np.where((band & 1).astype(bool)[..., None], c[1], c[0]) * (0.9 + 0.1 * fbm(w, h, rng, 4, 3))[..., None]
    alpha = np.clip((0.95 - r) * min(w, h) / 2, 0, 1) * 255
    return np.concatenate([_to_u8(rgb), _to_u8(alpha)[..., None]], 2)


GENERATORS = {"wood": wood, "marble": marble, "checker": checker, "stripes": stripes,
              "bricks": bricks, "facade": facade, "noise": noise, "cutout": cutout}


def generator_params(name: str) -> set[str]:
    """The extra keyword parameters a generator accepts (besides size and seed)."""
    sig = inspect.signature(GENERATORS[name])
    return {p for p in sig.parameters if p not in ("size", "seed")}


def generate(name: str, size=(256, 256), seed: int = 0, **params) -> np.ndarray:
    """Run generator ``name`` (one of GENERATORS) for a (width, height) size."""
    if name not in GENERATORS:
        raise ValueError(f"unknown texture generator {name!r} (known: {', '.join(sorted(GENERATORS))})")
    return GENERATORS[name](size=tuple(int(s) for s in size), seed=int(seed), **params)
