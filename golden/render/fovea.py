"""Foveation: a level-of-detail bias that grows with the distance from a gaze point.

Foveated texture mapping spends texture bandwidth where the viewer looks: around a gaze point the
frame samples the levels the level of detail asks for, farther out it samples coarser ones (fewer
distinct blocks, memory words and, with the sparse stream, requests). The bias is added in the
*quantised* LOD domain, an integer count of 1/256 levels, so it is exact and the fovea is untouched.

For a covered pixel (x, y), its centre at (x + 1/2, y + 1/2) pixels from the frame's top-left corner
(y down), the gaze point (X, Y) in the same units, radius R > 0 and falloff F >= 0::

    d    = sqrt((x + 1/2 - X)^2 + (y + 1/2 - Y)^2)
    bias = 0                                      if d <= R   (the fovea)
         = min(floor(256 F (d - R) / R), BIAS_LIMIT)   otherwise (the periphery)

so the periphery is F levels coarser one radius beyond the fovea's edge, 2F two radii beyond, and
the sampler uses ``lam = clamp(floor(lambda 256 + 1/2) + bias, 0, 256 (levels - 1))`` in place of the
unbiased ``clamp(floor(lambda 256 + 1/2), 0, ...)``. Every operation in ``d`` and ``bias`` is one
IEEE operation (subtract, multiply, add, square root, divide), each correctly rounded, so the bias is
the same on every machine. Pixels with ``d <= R`` get bias 0 and thus exactly the unbiased frame's
levels, blend, requests and colours; elsewhere ``bias >= 0``, so no pixel samples a finer level than
unbiased.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Fovea", "BIAS_LIMIT", "parse_gaze"]

#: Largest bias (1/256 levels): 2^14, 64 levels, more than any texture has.
BIAS_LIMIT = 1 << 14


@dataclass(frozen=True)
class Fovea:
    """A gaze point (x, y) in pixels (top-left corner 0, 0; y down), the fovea's radius in pixels
    and the falloff in levels per radius beyond it.

    Raises:
        ValueError: a coordinate that is not finite, a radius that is not finite and positive, or a
            falloff that is not finite and non-negative.
    """

    x: float
    y: float
    radius: float
    falloff: float = 1.0

    def __post_init__(self):
        for name in ("x", "y", "radius", "falloff"):
            v = getattr(self, name)
            if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v):
                raise ValueError(f"fovea {name} must be a finite number, got {v!r}")
        if self.radius <= 0:
            raise ValueError(f"fovea radius must be positive, got {self.radius}")
        if self.falloff < 0:
            raise ValueError(f"fovea falloff must not be negative, got {self.falloff}")

    def distance(self, pixel: np.ndarray, width: int) -> np.ndarray:
        """(M,) float64 distance in pixels of the centres of pixels ``pixel`` (``y width + x``) from
        the gaze point."""
        pixel = np.asarray(pixel, np.int64)
        dx = (pixel % width).astype(np.float64) + 0.5 - float(self.x)
        dy = (pixel // width).astype(np.float64) + 0.5 - float(self.y)
        return np.sqrt(dx * dx + dy * dy)

    def inside(self, pixel: np.ndarray, width: int) -> np.ndarray:
        """(M,) bool: the pixel's centre is in the fovea (distance <= radius; bias 0)."""
        return self.distance(pixel, width) <= float(self.radius)

    def bias(self, pixel: np.ndarray, width: int) -> np.ndarray:
        """(M,) int64 LOD bias in 1/256 levels (the module's formula): 0 inside, >= 0 everywhere."""
        d = self.distance(pixel, width)
        r = float(self.radius)
        b = np.floor(256.0 * float(self.falloff) * np.maximum(d - r, 0.0) / r)
        return np.minimum(b, BIAS_LIMIT).astype(np.int64)

    def as_dict(self) -> dict:
        return {"x": self.x, "y": self.y, "radius": self.radius, "falloff": self.falloff}


def parse_gaze(text: str) -> tuple[float, float]:
    """``"X,Y"`` -> (X, Y) floats; ValueError with a one-line message otherwise."""
    parts = text.split(",")
    try:
        if len(parts) != 2:
            raise ValueError
        x, y = (float(p) for p in parts)
    except ValueError:
        raise ValueError(f"gaze point {text!r} is not X,Y (two numbers, pixels)") from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise ValueError(f"gaze point {text!r} is not finite")
    return x, y
