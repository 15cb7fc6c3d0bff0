"""The texture filter in fixed point: per pixel (texture, s, t, level of detail, mode, addressing) ->
the texel footprint, its integer weights, and the filtered colour. The specification of
:mod:`vqtex.hw.filter` (the RTL sampler) and the arithmetic of :class:`golden.render.sampling.Sampler`.

Inputs per pixel, all integers (numpy arrays of one length M):

- ``s_q``, ``t_q``: the texture coordinates with ``frac`` fractional bits, ``s_q = floor(s 2^frac)``
  of the *folded* coordinate (:func:`golden.render.sampling.fold_coordinate`: wrap in (-1, 1), clamp in
  [-1, 2], mirror in (-2, 2)), so ``|s_q| <= 2^(frac+1)``: ``frac + 3`` signed bits.
  ``frac >= FRAC_BITS + log2`` of the largest level-0 side of the texture (:func:`coordinate_frac_bits`);
  then the nested floors make every footprint below exactly that of the float coordinate
  (``floor(floor(s 2^frac) / 2^k) = floor(s 2^(frac-k))``).
- ``lam``: the level of detail with ``FRAC_BITS`` = 8 fractional bits, clamped to
  ``[0, 256 last]`` (:func:`golden.render.sampling.quantize_lod`); ``L0 = lam >> 8``,
  ``f = lam & 255``, ``L1 = min(L0 + 1, last)``.
- ``mode``: 0 point, 1 bilinear, 2 trilinear (:data:`MODES`); ``address_s``, ``address_t``: 0 wrap,
  1 clamp, 2 mirror (:data:`ADDRESS_MODES`).

The footprint (:func:`footprint`) is eight texel slots (level, i, j) and eight weights per pixel;
the first ``TEXELS[mode]`` slots are used, the rest repeat slot 0 with weight 0:

- point: 1 texel of level 0, ``i = s_q >> (frac - log2 W0)`` (``floor(s W0)``), weight 2^24;
- bilinear: the 2x2 footprint of level ``L0`` in the order (i0, j0), (i1, j0), (i0, j1), (i1, j1),
  ``u = (s_q >> (frac - 8 - log2 W)) - 128`` (``floor(s W 256) - 128``: texel centres at
  half-integers), ``i0 = u >> 8``, ``i1 = i0 + 1``, ``fu = u & 255`` (same for t, j, fv), weights
  ``(256-fu)(256-fv), fu(256-fv), (256-fu)fv, fu fv`` times 256 (sum 2^24);
- trilinear: the footprint of ``L0`` then of ``L1``, the bilinear weights times ``256 - f`` and ``f``
  (eight weights summing to 2^24).

Addressing (:func:`address`) maps an integer index into ``[0, W)``: wrap ``i & (W-1)``, clamp
``min(max(i, 0), W-1)``, mirror ``(i & (W-1)) ^ (W-1 if i & W else 0)`` (period 2W: 0..W-1 then
W-1..0, OpenGL's MIRRORED_REPEAT).

The colour (:func:`blend`): per channel ``(sum_k w_k texel_k + 2^23) >> 24``; the sum is below 2^32.
"""

from __future__ import annotations

import numpy as np

__all__ = ["FRAC_BITS", "WEIGHT_BITS", "WEIGHT_ONE", "MODES", "ADDRESS_MODES", "TEXELS", "SLOTS",
           "coordinate_frac_bits", "coordinate_bits", "quantize_coordinate", "address", "footprint",
           "blend", "LevelTable"]

#: Fractional bits of the level of detail and of the bilinear fractions fu, fv and the blend f.
FRAC_BITS = 8
_ONE = 1 << FRAC_BITS
#: The weights are fractions of 2^WEIGHT_BITS (= 24): a colour is ``(sum w texel + 2^23) >> 24``.
WEIGHT_BITS = 3 * FRAC_BITS
WEIGHT_ONE = 1 << WEIGHT_BITS
#: Filter modes by code.
MODES = ("point", "bilinear", "trilinear")
#: Addressing modes by code.
ADDRESS_MODES = ("wrap", "clamp", "mirror")
#: Texels per pixel, by mode name.
TEXELS = {"point": 1, "bilinear": 4, "trilinear": 8}
#: Texel slots of a footprint.
SLOTS = 8


def coordinate_frac_bits(max_log2_size: int) -> int:
    """Fractional bits of ``s_q`` that leave every footprint of textures up to ``2^max_log2_size``
    texels a side unchanged: ``FRAC_BITS + max_log2_size``."""
    return FRAC_BITS + int(max_log2_size)


def coordinate_bits(frac: int) -> int:
    """Signed width of ``s_q`` with ``frac`` fractional bits over the folded range [-2, 2]:
    ``frac + 3`` (``2^(frac+1)``, the clamped ``s = 2``, needs ``frac + 2`` magnitude bits)."""
    return int(frac) + 3


def quantize_coordinate(s, frac: int) -> np.ndarray:
    """``floor(s 2^frac)`` as int64, for folded coordinates (finite, |s| <= 2): exact in float64."""
    return np.floor(np.asarray(s, np.float64) * float(1 << frac)).astype(np.int64)


def address(i, log2size, mode) -> np.ndarray:
    """Integer texel index into ``[0, 2^log2size)`` by addressing mode code (0 wrap, 1 clamp, 2 mirror)."""
    i = np.asarray(i, np.int64)
    size = np.left_shift(np.int64(1), np.asarray(log2size, np.int64))
    low = i & (size - 1)
    mirrored = low ^ np.where(i & size, size - 1, 0)
    return np.where(mode == 0, low, np.where(mode == 1, np.clip(i, 0, size - 1), mirrored))


class LevelTable:
    """log2 of every level's width and height per texture, and the last level, as the filter reads them.

    Arguments:
        level_shapes: per texture id, [(width, height) of level 0, 1, ...], powers of two.

    Members: ``log2w``, ``log2h`` (T, L) int64 (missing levels repeat the last), ``last`` (T,) int64,
    ``max_log2`` (the largest log2 side of any level 0).
    """

    def __init__(self, level_shapes):
        t = max(len(level_shapes), 1)
        nlev = max((len(s) for s in level_shapes), default=1)
        self.log2w = np.zeros((t, nlev), np.int64)
        self.log2h = np.zeros((t, nlev), np.int64)
        self.last = np.zeros(t, np.int64)
        for k, shapes in enumerate(level_shapes):
            if not shapes:
                raise ValueError(f"texture {k} has no levels")
            for n, (w, h) in enumerate(shapes):
                if w < 1 or h < 1 or (w & (w - 1)) or (h & (h - 1)):
                    raise ValueError(f"texture {k} level {n}: size {w}x{h} is not a power of two")
                self.log2w[k, n], self.log2h[k, n] = int(w).bit_length() - 1, int(h).bit_length() - 1
            self.log2w[k, len(shapes):] = self.log2w[k, len(shapes) - 1]
            self.log2h[k, len(shapes):] = self.log2h[k, len(shapes) - 1]
            self.last[k] = len(shapes) - 1
        self.max_log2 = int(max(self.log2w[:, 0].max(), self.log2h[:, 0].max()))


def _bilinear(s_q, t_q, lw, lh, frac, addr_s, addr_t):
    """(i (M,4), j (M,4), weights (M,4) summing to 2^16) of one level's 2x2 footprint."""
    u = (s_q >> (frac - FRAC_BITS - lw)) - (_ONE >> 1)
    v = (t_q >> (frac - FRAC_BITS - lh)) - (_ONE >> 1)
    i0, j0 = u >> FRAC_BITS, v >> FRAC_BITS
    fu, fv = u & (_ONE - 1), v & (_ONE - 1)
    i0a, i1a = address(i0, lw, addr_s), address(i0 + 1, lw, addr_s)
    j0a, j1a = address(j0, lh, addr_t), address(j0 + 1, lh, addr_t)
    gu, gv = _ONE - fu, _ONE - fv
    return (np.stack([i0a, i1a, i0a, i1a], 1), np.stack([j0a, j0a, j1a, j1a], 1),
            np.stack([gu * gv, fu * gv, gu * fv, fu * fv], 1))


def footprint(table: LevelTable, tex, s_q, t_q, lam, mode, address_s, address_t, frac: int):
    """The texel slots and weights of M pixels (see the module docstring).

    Returns (level, i, j, weight), each (M, SLOTS) int64; each row of ``weight`` sums to 2^24 and only
    the first ``TEXELS[mode]`` slots may be non-zero.

    Raises:
        ValueError: if ``frac`` is too small for the table's largest level 0.
    """
    if frac < coordinate_frac_bits(table.max_log2):
        raise ValueError(f"{frac} fractional bits are too few for textures of 2^{table.max_log2} texels a side")
    tex, s_q, t_q, lam, mode, addr_s, addr_t = (np.asarray(x, np.int64).reshape(-1) for x in
                                                 (tex, s_q, t_q, lam, mode, address_s, address_t))
    m = len(tex)
    if m and ((lam < 0).any() or (lam > table.last[tex] << FRAC_BITS).any()):
        raise ValueError("level of detail outside [0, 256 last level]")
    if m and ((mode < 0).any() or (mode > 2).any() or (addr_s < 0).any() or (addr_s > 2).any()
              or (addr_t < 0).any() or (addr_t > 2).any()):
        raise ValueError("unknown filter or addressing mode code")
    level = np.zeros((m, SLOTS), np.int64)
    ii = np.zeros((m, SLOTS), np.int64)
    jj = np.zeros((m, SLOTS), np.int64)
    weight = np.zeros((m, SLOTS), np.int64)
    if m == 0:
        return level, ii, jj, weight
    l0 = lam >> FRAC_BITS
    f = np.where(mode == 2, lam & (_ONE - 1), 0)
    l1 = np.minimum(l0 + 1, table.last[tex])
    for k, lv in enumerate((l0, l1)):
        i4, j4, w4 = _bilinear(s_q, t_q, table.log2w[tex, lv], table.log2h[tex, lv], frac, addr_s, addr_t)
        level[:, 4 * k:4 * k + 4] = lv[:, None]
        ii[:, 4 * k:4 * k + 4] = i4
        jj[:, 4 * k:4 * k + 4] = j4
        weight[:, 4 * k:4 * k + 4] = w4 * ((_ONE - f) if k == 0 else f)[:, None]
    # point: one texel of level 0 at (floor(s W0), floor(t H0)), weight one
    pt = mode == 0
    if pt.any():
        lw, lh = table.log2w[tex, 0], table.log2h[tex, 0]
        level[pt, 0] = 0
        ii[pt, 0] = address(s_q >> (frac - lw), lw, addr_s)[pt]
        jj[pt, 0] = address(t_q >> (frac - lh), lh, addr_t)[pt]
        weight[pt, 0] = WEIGHT_ONE
    # unused slots repeat slot 0 with weight 0
    used = np.where(mode == 0, 1, np.where(mode == 1, 4, 8))
    unused = np.arange(SLOTS)[None, :] >= used[:, None]
    for a in (level, ii, jj):
        a[unused] = np.broadcast_to(a[:, :1], a.shape)[unused]
    weight[unused] = 0
    return level, ii, jj, weight


def blend(weight, texels) -> np.ndarray:
    """The filtered colour (M, 4) uint8 from weights (M, n) (rows summing to 2^24) and texels
    (M, n, 4) uint8: ``(sum_k w_k texel_k + 2^23) >> 24`` per channel (exact in uint32)."""
    w = np.asarray(weight).astype(np.uint32)
    tx = np.asarray(texels)
    acc = np.zeros((tx.shape[0], tx.shape[2]), np.uint32)
    for k in range(tx.shape[1]):   # over the (at most 8) slots, each a vectorised pass over pixels
        acc += w[:, k, None] * tx[:, k]
    return ((acc + (1 << (WEIGHT_BITS - 1))) >> WEIGHT_BITS).astype(np.uint8)
