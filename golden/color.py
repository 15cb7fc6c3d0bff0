"""Fixed-point colour matrices (YUV -> RGB) and their float64 references.

One unit serves every colour conversion (docs/format.md, "Colour"; docs/hardware.md, the colour matrix)::

    out_c = clamp(((sum_k M[c][k] * (in_k - off_k)) + bias) >> F, 0, 255)

with signed integer coefficients ``M``, input offsets ``off`` (128 for U and V), ``F`` fractional bits
and ``bias`` either ``2**(F-1)`` (round to nearest) or 0 (floor; ``>>`` is an arithmetic shift, so
negative sums floor towards minus infinity exactly as the hardware's signed shift does).

The golden model here and the hardware in ``hw/color_matrix.py`` are the same integer arithmetic.
The float64 reference (:meth:`ColorMatrix.reference`) is what the fixed-point matrix approximates;
:meth:`ColorMatrix.error_bound` states how far apart they can be.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "ColorMatrix", "JFIF_BT601", "DREAMCAST_YUV422",
    "JFIF_YUV_TO_RGB", "JFIF_RGB_TO_YUV", "rgb_to_yuv", "yuv_to_rgb_float",
]

#: Full-range BT.601 (JFIF) YUV -> RGB, real coefficients; rows R, G, B; columns Y, U, V.
JFIF_YUV_TO_RGB = np.array([
    [1.0, 0.0, 1.402],
    [1.0, -0.344136286, -0.714136286],
    [1.0, 1.772, 0.0],
])
#: Full-range BT.601 (JFIF) RGB -> YUV; U and V then get +128.
JFIF_RGB_TO_YUV = np.array([
    [0.299, 0.587, 0.114],
    [-0.168735892, -0.331264108, 0.5],
    [0.5, -0.418687589, -0.081312411],
])


@dataclass(frozen=True)
class ColorMatrix:
    """A parameterised fixed-point 3x3 colour matrix.

    Arguments
    ---------
    coeffs : 3x3 tuple of int
        Signed integer coefficients ``M[c][k]``; rows are outputs (R, G, B), columns inputs
        (Y, U, V). Each must fit in 18 signed bits, -2^17 .. 2^17 - 1 (one ECP5 multiplier operand).
    offsets : 3-tuple of int
        Subtracted from each 8-bit input before multiplying (0..255).
    frac_bits : int
        ``F``, 0..16.
    rounding : bool
        ``True``: bias ``2**(F-1)`` (round half up). ``False``: bias 0 (floor).
    reference_coeffs : 3x3 tuple of float, optional
        The real matrix this one approximates (defaults to ``coeffs / 2**F``).

    Raises
    ------
    ValueError
        If a coefficient, offset or ``frac_bits`` is out of range.
    """

    coeffs: tuple
    offsets: tuple = (0, 128, 128)
    frac_bits: int = 12
    rounding: bool = True
    reference_coeffs: tuple | None = None

    def __post_init__(self):
        m = np.asarray(self.coeffs)
        if m.shape != (3, 3) or not np.issubdtype(m.dtype, np.integer):
            raise ValueError("colour matrix coefficients must be a 3x3 array of integers")
        if m.min() < -(1 << 17) or m.max() >= 1 << 17:
            raise ValueError("colour matrix coefficients must fit in 18 signed bits (-131072..131071)")
        if len(self.offsets) != 3 or not all(0 <= int(o) <= 255 for o in self.offsets):
            raise ValueError("colour matrix offsets must be three integers in 0..255")
        if not 0 <= int(self.frac_bits) <= 16:
            raise ValueError("colour matrix frac_bits must be in 0..16")
        object.__setattr__(self, "coeffs", tuple(tuple(int(v) for v in row) for row in m))
        object.__setattr__(self, "offsets", tuple(int(o) for o in self.offsets))
        object.__setattr__(self, "frac_bits", int(self.frac_bits))
        object.__setattr__(self, "rounding", bool(self.rounding))
        if self.reference_coeffs is not None:
            r = np.asarray(self.reference_coeffs, dtype=np.float64)
            object.__setattr__(self, "reference_coeffs", tuple(tuple(float(v) for v in row) for row in r))

    @classmethod
    def from_float(cls, matrix, *, frac_bits: int = 12, offsets=(0, 128, 128), rounding=True):
        """Quantise a real matrix to ``frac_bits`` fractional bits (round to nearest)."""
        real = np.asarray(matrix, dtype=np.float64)
        coeffs = np.rint(real * (1 << frac_bits)).astype(np.int64)
        return cls(coeffs=coeffs, offsets=offsets, frac_bits=frac_bits, rounding=rounding,
                   reference_coeffs=real)

    @property
    def bias(self) -> int:
        return (1 << (self.frac_bits - 1)) if (self.rounding and self.frac_bits > 0) else 0

    def apply(self, yuv: np.ndarray) -> np.ndarray:
        """Bit-exact conversion of ``(..., 3)`` uint8 inputs to ``(..., 3)`` uint8 outputs."""
        x = np.asarray(yuv, dtype=np.int64) - np.asarray(self.offsets, dtype=np.int64)
        acc = x @ np.asarray(self.coeffs, dtype=np.int64).T + self.bias
        return np.clip(acc >> self.frac_bits, 0, 255).astype(np.uint8)

    def reference(self) -> np.ndarray:
        """The real 3x3 matrix this fixed-point matrix stands for (float64)."""
        if self.reference_coeffs is not None:
            return np.asarray(self.reference_coeffs, dtype=np.float64)
        return np.asarray(self.coeffs, dtype=np.float64) / (1 << self.frac_bits)

    def apply_float(self, yuv: np.ndarray) -> np.ndarray:
        """The float64 reference, unrounded and unclamped: ``(..., 3)`` float64."""
        x = np.asarray(yuv, dtype=np.float64) - np.asarray(self.offsets, dtype=np.float64)
        return x @ self.reference().T

    def error_bound(self) -> float:
        """Largest possible ``|apply(x) - clamp(apply_float(x))|`` over all 8-bit inputs.

        Coefficient quantisation contributes ``sum_k |M[c][k]/2^F - R[c][k]| * max|x_k - off_k|``;
        the final shift contributes 0.5 (rounding) or 1 (floor).
        """
        quant = np.abs(np.asarray(self.coeffs) / (1 << self.frac_bits) - self.reference())
        span = np.array([max(o, 255 - o) for o in self.offsets], dtype=np.float64)
        return float((quant @ span).max() + (0.5 if self.rounding else 1.0))

    def to_dict(self) -> dict:
        d = {"coeffs": [list(r) for r in self.coeffs], "offsets": list(self.offsets),
             "frac_bits": self.frac_bits, "rounding": self.rounding}
        if self.reference_coeffs is not None:
            d["reference_coeffs"] = [list(r) for r in self.reference_coeffs]
        return d

    @classmethod
    def from_dict(cls, d: dict) -> "ColorMatrix":
        return cls(coeffs=d["coeffs"], offsets=tuple(d["offsets"]), frac_bits=d["frac_bits"],
                   rounding=d["rounding"], reference_coeffs=d.get("reference_coeffs"))

    @property
    def product_bits(self) -> int:
        """Signed width of one product ``M * (in - off)`` (for the hardware)."""
        cmax = max(max(abs(v) for v in row) for row in self.coeffs)
        xmax = max(max(o, 255 - o) for o in self.offsets)
        return (cmax * xmax).bit_length() + 1

    @property
    def sum_bits(self) -> int:
        """Signed width of the accumulated sum plus bias (for the hardware)."""
        total = max(sum(abs(v) for v in row) for row in self.coeffs)
        xmax = max(max(o, 255 - o) for o in self.offsets)
        return (total * xmax + self.bias).bit_length() + 1


#: The paper's YUV: full-range BT.601 (JFIF), 12 fractional bits, round to nearest.
JFIF_BT601 = ColorMatrix.from_float(JFIF_YUV_TO_RGB, frac_bits=12)

#: Dreamcast (PowerVR2) YUV422 decode: R = Y + 11V/8, G = Y - (11U + 22V)/32, B = Y + 110U/64,
#: U and V less 128, floored (F = 6, bias 0).
DREAMCAST_YUV422 = ColorMatrix(
    coeffs=((64, 0, 88), (64, -22, -44), (64, 110, 0)),
    offsets=(0, 128, 128), frac_bits=6, rounding=False,
    reference_coeffs=((1.0, 0.0, 1.375), (1.0, -0.34375, -0.6875), (1.0, 1.71875, 0.0)),
)


def rgb_to_yuv(rgb: np.ndarray) -> np.ndarray:
    """Forward full-range BT.601 (JFIF) transform for the encoder: ``(..., 3)`` -> float64 Y, U, V
    with U and V offset by 128 (unrounded, unclamped)."""
    yuv = np.asarray(rgb, dtype=np.float64) @ JFIF_RGB_TO_YUV.T
    yuv[..., 1:] += 128.0
    return yuv


def yuv_to_rgb_float(yuv: np.ndarray) -> np.ndarray:
    """Inverse of :func:`rgb_to_yuv` in float64 (the reference of :data:`JFIF_BT601`)."""
    x = np.asarray(yuv, dtype=np.float64).copy()
    x[..., 1:] -= 128.0
    return x @ JFIF_YUV_TO_RGB.T
