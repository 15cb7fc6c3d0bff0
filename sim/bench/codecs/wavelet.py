"""A wavelet texture coder in the spirit of the wavelet-compressed-texture work: a colour transform,
a 2-D wavelet transform (PyWavelets), dead-zone uniform quantisation, and bits counted from the
measured entropy of the quantised coefficients.

The coder, step by step:

1. **Colour**: RGB - 128 -> Y Cb Cr with the JFIF (BT.601 full-range) float matrix, as JPEG 2000's
   irreversible colour transform.
2. **Tiles**: the image whole (``tile=None``) or cut into ``tile`` x ``tile`` tiles, each transformed
   on its own (so one tile can be decoded alone). All tiles go through PyWavelets in one call.
3. **Transform**: ``pywt.wavedec2`` with periodic extension (``mode='periodization'``: textures
   wrap, and the coefficients are exactly as many as the texels), ``levels`` = at most 5, down to a
   4-coefficient band. Wavelets: ``haar`` (orthonormal) and ``bior2.2``, which is LeGall 5/3 (CDF
   5/3), JPEG 2000's reversible wavelet: its analysis low-pass is sqrt(2) (-1, 2, 6, 2, -1) / 8, used
   here in floating point.
4. **Quantisation**: dead-zone uniform, ``q = sign(c) floor(|c| / step)`` (the zero bin is twice as
   wide as the others), reconstruction at the middle of the bin, ``(|q| + 1/2) step sign(q)``. The
   step of each band (subband x colour channel) is ``step / sqrt(G)``, where G is the energy that a
   unit coefficient of that band puts into the RGB image (the subband's synthesis gain, from an
   impulse through ``waverec2``, times the colour matrix's column energy), so that every band costs
   the same RGB error per unit of step: one number, ``step``, sets the rate.
5. **Bits (the model)**: a zeroth-order (memoryless) entropy coder per band: bits = sum over bands of
   N_b H_0(q_b), with H_0 the entropy of the band's measured histogram of q, pooled over the tiles
   (one code per band, shared by every tile). It is the rate of an ideal static arithmetic coder that
   knows each band's histogram; the histograms (side information) and the step are not counted, and
   no context modelling is done (which would lower the rate). ``step`` is searched by bisection on
   log2(step) for the largest rate not above the target.

Times: ``encode_s`` is colour, transform, rate search and quantisation (no entropy coder runs);
``decode_s`` is dequantisation, inverse transform, inverse colour, rounding: both leave out the
entropy coding the counted bits assume, so they are lower bounds for a real coder. One random texel
costs the inverse transform of the whole image (untiled) or of its tile (tiled: a batch of tiles, one
per requested texel, inverse-transformed in one call).
"""

from __future__ import annotations

import warnings

import numpy as np

from .measure import best_time, copy_floor, gather_floor, psnr
from .schema import row

__all__ = ["WaveletCoder", "rows", "WAVELETS", "TILES", "YCBCR", "RANDOM_TILES"]

WAVELETS = {"haar": "Haar", "bior2.2": "LeGall 5/3"}
TILES = (None, 64)
#: Tiles inverse-transformed per random-texel batch (tiled layout).
RANDOM_TILES = 256

#: JFIF full-range RGB -> Y Cb Cr (rows), applied to RGB - 128.
YCBCR = np.array([[0.299, 0.587, 0.114],
                  [-0.168735892, -0.331264108, 0.5],
                  [0.5, -0.418687589, -0.081312411]])
_RGB = np.linalg.inv(YCBCR)


class WaveletCoder:
    """The coder for one image, wavelet and tiling: ``analyse`` once, then ``quantise`` at any step,
    ``bits`` of a quantisation, ``synthesise`` tiles back to texels."""

    def __init__(self, image: np.ndarray, wavelet: str = "haar", tile: int | None = None, levels: int = 5):
        import pywt
        h, w = image.shape[:2]
        self.height, self.width = h, w
        self.tile = tile
        th, tw = (h, w) if tile is None else (tile, tile)
        if h % th or w % tw:
            raise ValueError(f"a {w}x{h} image is not made of {tw}x{th} tiles")
        self.th, self.tw = th, tw
        self.wavelet = pywt.Wavelet(wavelet)
        self.levels = max(1, min(levels, int(np.log2(min(th, tw))) - 2))
        if min(th, tw) >> self.levels < 1:
            raise ValueError(f"{tw}x{th} tiles are too small for a {self.levels}-level transform")
        self.gains = self._gains()

    # -- transform -----------------------------------------------------------------------------
    def _tiles(self, image: np.ndarray) -> np.ndarray:
        """(H, W, 3) uint8 -> (tiles, th, tw, 3) float64 Y Cb Cr, tiles row-major."""
        ycc = (image[..., :3].astype(np.float64) - 128.0) @ YCBCR.T
        ny, nx = self.height // self.th, self.width // self.tw
        return ycc.reshape(ny, self.th, nx, self.tw, 3).transpose(0, 2, 1, 3, 4).reshape(-1, self.th, self.tw, 3)

    def _untile(self, tiles: np.ndarray) -> np.ndarray:
        ny, nx = self.height // self.th, self.width // self.tw
        ycc = tiles.reshape(ny, nx, self.th, self.tw, 3).transpose(0, 2, 1, 3, 4).reshape(self.height, self.width, 3)
        return np.clip(np.rint(ycc @ _RGB.T + 128.0), 0, 255).astype(np.uint8)

    def analyse(self, image: np.ndarray) -> list[np.ndarray]:
        """The subbands, coarsest first: [LL, (H, V, D) of level L, ..., (H, V, D) of level 1], each
        (tiles, h, w, 3) float64."""
        import pywt
        with warnings.catch_warnings():                       # deeper than pywt's "no boundary effects" level:
            warnings.simplefilter("ignore", UserWarning)      # periodic extension wraps, as a texture does
            c = pywt.wavedec2(self._tiles(image), self.wavelet, mode="periodization", level=self.levels,
                              axes=(1, 2))
        return [c[0]] + [a for lvl in c[1:] for a in lvl]

    def synthesise(self, bands: list[np.ndarray]) -> np.ndarray:
        """Subbands (tiles, ...) -> (tiles, th, tw, 3) float64 Y Cb Cr."""
        import pywt
        c = [bands[0]] + [tuple(bands[1 + 3 * k: 4 + 3 * k]) for k in range(self.levels)]
        return pywt.waverec2(c, self.wavelet, mode="periodization", axes=(1, 2))

    def _gains(self) -> np.ndarray:
        """(subbands, 3): RGB energy of a unit coefficient in each subband and channel."""
        import pywt
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            zero = pywt.wavedec2(np.zeros((self.th, self.tw)), self.wavelet, mode="periodization", level=self.levels)
        flat = [zero[0]] + [a for lvl in zero[1:] for a in lvl]
        g = np.empty(len(flat))
        for s in range(len(flat)):                            # one impulse per subband (16 at most)
            bands = [np.zeros_like(a) for a in flat]
            bands[s][bands[s].shape[0] // 2, bands[s].shape[1] // 2] = 1.0
            c = [bands[0]] + [tuple(bands[1 + 3 * k: 4 + 3 * k]) for k in range(self.levels)]
            g[s] = float(np.sum(pywt.waverec2(c, self.wavelet, mode="periodization") ** 2))
        return g[:, None] * np.sum(_RGB ** 2, axis=0)[None, :]

    # -- quantisation and bits -----------------------------------------------------------------
    def steps(self, step: float) -> np.ndarray:
        """(subbands, 3) quantiser steps for the global ``step``."""
        return step / np.sqrt(self.gains)

    def quantise(self, bands: list[np.ndarray], step: float) -> list[np.ndarray]:
        """Dead-zone uniform quantisation: int32 subbands."""
        st = self.steps(step)
        return [(np.sign(a) * np.floor(np.abs(a) / st[s])).astype(np.int32) for s, a in enumerate(bands)]

    def dequantise(self, q: list[np.ndarray], step: float) -> list[np.ndarray]:
        """Middle of each bin (zero stays zero)."""
        st = self.steps(step)
        return [np.sign(a) * (np.abs(a) + 0.5) * st[s] * (a != 0) for s, a in enumerate(q)]

    @staticmethod
    def bits(q: list[np.ndarray]) -> float:
        """Sum over bands (subband x channel) of N_b H_0(q_b), bits (the zeroth-order entropy model)."""
        total = 0.0
        for a in q:                                           # subbands (16 at most); channels vectorised
            v = a.reshape(-1, 3)
            lo = int(v.min())
            span = int(v.max()) - lo + 1
            keys = (v - lo).astype(np.int64) + np.arange(3, dtype=np.int64) * span
            counts = np.bincount(keys.ravel(), minlength=3 * span).reshape(3, span).astype(np.float64)
            n = counts.sum(axis=1)
            nz = counts > 0
            clog = np.where(nz, counts * np.log2(np.where(nz, counts, 1.0)), 0.0).sum(axis=1)
            total += float(np.sum(n * np.log2(n) - clog))
        return total

    def search(self, bands: list[np.ndarray], bits_per_texel: float, iterations: int = 24):
        """The finest step whose rate is at most ``bits_per_texel``: (step, quantised bands, bits)."""
        budget = bits_per_texel * self.width * self.height
        lo, hi = -4.0, 14.0                                   # log2(step): 1/16 .. 16384
        best = None
        for _ in range(iterations):
            mid = 0.5 * (lo + hi)
            q = self.quantise(bands, 2.0 ** mid)
            b = self.bits(q)
            if b <= budget:
                best, hi = (2.0 ** mid, q, b), mid
            else:
                lo = mid
        if best is None:
            q = self.quantise(bands, 2.0 ** hi)
            best = (2.0 ** hi, q, self.bits(q))
        return best

    def decode(self, q: list[np.ndarray], step: float) -> np.ndarray:
        """Quantised subbands -> (H, W, 3) uint8."""
        return self._untile(self.synthesise(self.dequantise(q, step)))

    def decode_tiles(self, q: list[np.ndarray], step: float, tiles: np.ndarray) -> np.ndarray:
        """Only the tiles ``tiles`` -> (n, th, tw, 3) uint8."""
        ycc = self.synthesise(self.dequantise([a[tiles] for a in q], step))
        return np.clip(np.rint(ycc @ _RGB.T + 128.0), 0, 255).astype(np.uint8)

    def tile_of(self, y, x) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(tile number, row, column inside the tile) of texels (y, x)."""
        y = np.asarray(y, dtype=np.int64)
        x = np.asarray(x, dtype=np.int64)
        return (y // self.th) * (self.width // self.tw) + x // self.tw, y % self.th, x % self.tw


def rows(name: str, image: np.ndarray, *, targets: dict, y, x, repeats: int = 3, wavelets=tuple(WAVELETS),
         tiles=TILES, random_tiles: int = RANDOM_TILES) -> list[dict]:
    """One row per (wavelet, layout, target rate). ``targets``: {VQ config: its bits per texel}."""
    import pywt
    h, w = image.shape[:2]
    out = []
    for wav in wavelets:
        for tile in tiles:
            if tile is not None and (h % tile or w % tile or tile > min(h, w)):
                continue
            for cfg, bpt in targets.items():
                def enc():
                    coder = WaveletCoder(image, wav, tile)
                    bands = coder.analyse(image)
                    step, q, b = coder.search(bands, bpt)
                    return coder, step, q, b
                (coder, step, q, b), enc_s = best_time(enc, repeats)
                dec, dec_s = best_time(lambda: coder.decode(q, step), repeats)
                if tile is None:
                    rnd_s, how = dec_s, "inverse transform of the whole image (no tiles)"
                else:
                    t, ty, tx = coder.tile_of(y[:random_tiles], x[:random_tiles])
                    picked, s = best_time(lambda: coder.decode_tiles(q, step, t)[np.arange(len(t)), ty, tx],
                                          repeats)
                    rnd_s = s / len(t)
                    how = f"inverse transform of the texel's {tile}x{tile} tile, {len(t)} tiles in one call"
                layout = "untiled" if tile is None else f"tiles {tile}x{tile}"
                out.append(row(method="wavelet", config=f"{WAVELETS.get(wav, wav)} {layout} @{cfg}", image=name,
                               bits_per_texel=b / (w * h), psnr_db=psnr(image, dec), encode_s=enc_s,
                               decode_s=dec_s, random_texel_s=rnd_s, floor_s=copy_floor(dec, repeats),
                               random_floor_s=gather_floor(dec, y, x, repeats), random_texel=how,
                               library=(f"PyWavelets {pywt.__version__} '{wav}', {coder.levels} levels, dead zone, "
                                        "zeroth-order entropy per band (no entropy coder timed)"),
                               target_bits_per_texel=bpt, width=w, height=h))
    return out
