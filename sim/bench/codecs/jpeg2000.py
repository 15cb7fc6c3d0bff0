"""JPEG 2000 through glymur and OpenJPEG (libopenjp2: the Debian package ``libopenjp2-7``, which
``scripts/install-sim-tools`` installs): the 9/7 irreversible wavelet and the irreversible colour
transform, one quality layer whose size OpenJPEG's rate control sets from a compression ratio.

OpenImageIO (this project's image library) reads and writes JPEG 2000 too, but its writer is
lossless only (it sets no rate), so it cannot hit a bit rate; glymur passes ``cratios`` through.

The ratio asked for is 24 / target bits per texel; ``bits_per_texel`` is what came out, the whole
``.j2k`` codestream (main header, tile headers, packets) over the texels. Two layouts:

* **untiled**: one tile; a random texel costs OpenJPEG's decode of the area of that one texel
  (``opj_set_decode_area``: it decodes the code-blocks of every resolution the texel depends on).
* **tiled** (``tile`` x ``tile`` tiles, each coded on its own): a random texel costs the decode of
  the area of one texel, inside its tile.

Each random texel is one library call (one decode per request, the work the format asks for), timed
over a sample of requests and divided by their number: a Python loop over the sample, because each
request is a separate decode; the loop's own cost is below a microsecond against milliseconds.
OpenJPEG runs on one thread (glymur's default ``lib.num_threads``).
"""

from __future__ import annotations

import os
import tempfile
import time

import numpy as np

from .measure import best_time, copy_floor, gather_floor, psnr
from .schema import row

__all__ = ["encode", "decode", "decode_texel", "rows", "openjpeg", "TILES", "RANDOM_SAMPLE"]

#: Layouts: None (untiled) and the tile side.
TILES = (None, 64)
#: Random texels decoded one by one per row.
RANDOM_SAMPLE = 32


def openjpeg():
    """The glymur module, once it has found OpenJPEG; ImportError (naming ``libopenjp2``) if not."""
    import glymur as g
    if g.version.openjpeg_version_tuple[0] < 2:
        raise ImportError("glymur found no OpenJPEG library", name="libopenjp2")
    return g


def encode(image: np.ndarray, path: str, bits_per_texel: float, tile: int | None = None):
    """Write ``image`` (H, W, 3) uint8 to the codestream ``path`` (``.j2k``) at about
    ``bits_per_texel``; returns the glymur object."""
    h, w = image.shape[:2]
    side = min(h, w) if tile is None else tile
    levels = max(1, min(5, int(np.log2(side)) - 2))         # down to a 4-texel band, at most 5
    kw = {"tilesize": (tile, tile)} if tile is not None else {}
    return openjpeg().Jp2k(path, data=np.ascontiguousarray(image[..., :3]), cratios=[24.0 / bits_per_texel],
                       irreversible=True, numres=levels + 1, **kw)


def decode(path: str) -> np.ndarray:
    """The whole image, (H, W, 3) uint8."""
    return openjpeg().Jp2k(path)[:]


def decode_texel(jp2, y: int, x: int) -> np.ndarray:
    """One texel (3,) uint8: OpenJPEG decodes the area (y, x, y+1, x+1)."""
    return jp2[y:y + 1, x:x + 1][0, 0]


def _random_texel_s(path: str, y, x, sample: int) -> float:
    jp2 = openjpeg().Jp2k(path)                                 # headers parsed once, as a renderer would
    n = min(sample, len(y))
    t0 = time.perf_counter()
    for k in range(n):                                       # one library decode per request
        decode_texel(jp2, int(y[k]), int(x[k]))
    return (time.perf_counter() - t0) / n


def rows(name: str, image: np.ndarray, *, targets: dict, y, x, repeats: int = 3, tiles=TILES,
         sample: int = RANDOM_SAMPLE) -> list[dict]:
    """One row per (target rate, layout). ``targets``: {VQ config: its bits per texel}."""
    g = openjpeg()
    h, w = image.shape[:2]
    out = []
    with tempfile.TemporaryDirectory(prefix="vqtex-j2k-") as tmp:
        for cfg, bpt in targets.items():
            for tile in tiles:
                if tile is not None and (tile > min(h, w)):
                    continue
                path = os.path.join(tmp, "image.j2k")
                _, enc_s = best_time(lambda: encode(image, path, bpt, tile), repeats)
                dec, dec_s = best_time(lambda: decode(path), repeats)
                rnd_s = min(_random_texel_s(path, y, x, sample) for _ in range(max(1, repeats)))
                layout = "untiled" if tile is None else f"tiles {tile}x{tile}"
                out.append(row(method="jpeg2000", config=f"{layout} @{cfg}", image=name,
                               bits_per_texel=os.path.getsize(path) * 8 / (w * h), psnr_db=psnr(image, dec),
                               encode_s=enc_s, decode_s=dec_s, random_texel_s=rnd_s,
                               floor_s=copy_floor(dec, repeats), random_floor_s=gather_floor(dec, y, x, repeats),
                               random_texel=("OpenJPEG decode of a 1x1 area "
                                             + ("of the image" if tile is None else "in its tile")
                                             + f", one call per texel, {min(sample, len(y))} texels"),
                               library=f"glymur {g.__version__}, OpenJPEG {g.version.openjpeg_version}, 9/7",
                               target_bits_per_texel=bpt, width=w, height=h))
    return out
