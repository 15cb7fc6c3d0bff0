"""Quality of our PowerVR2 encoder against pvrtex's, on pvrtex's own test image.

For every ``crate_FORMAT_c[_64][_m].dt`` that pvrtex wrote (tests/data/pvrtex/generated), encode
``crate.png`` with :func:`vqtex.golden.pvr2.pvr_encode.encode_pvr2` at the same format, codebook size
and mip setting, and report the PSNR (R, G, B, level 0) of both against the original: pvrtex's
from its own preview image (the top-left ``128x128``: level 0), ours from our ``.dt`` decoded by
:func:`vqtex.golden.pvr2.pvr.parse_dt`; with our encode time (wall clock, one process, default BLAS
threads). pvrtex's encode time is not measured (its binary is not part of this project).

    python -m vqtex.sim.bench.encoding.pvr2_quality [--data tests/data/pvrtex] [--json]
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

__all__ = ["run", "main"]

FORMATS = ("rgb565", "argb1555", "argb4444", "yuv422")
VARIANTS = (("c", 256, False), ("c_64", 64, False), ("c_m", 256, True), ("c_64_m", 64, True))
DEFAULT_DATA = os.path.join(os.path.dirname(__file__), "..", "..", "..", "tests", "data", "pvrtex")


def _psnr(a, b) -> float:
    d = a[..., :3].astype(np.float64) - b[..., :3].astype(np.float64)
    return float(10 * np.log10(255.0 ** 2 / max(float((d * d).mean()), 1e-12)))


def run(data: str = DEFAULT_DATA, seed: int = 0, formats=FORMATS, variants=VARIANTS) -> list:
    """One row per (format, variant): ``{"format", "codebook", "mipmaps", "pvrtex_db", "ours_db",
    "gain_db", "ours_seconds"}``. ``variants``: (pvrtex file tag, codebook size, mipmapped)."""
    from vqtex.golden.pvr2.pvr import parse_dt
    from vqtex.golden.pvr2.pvr_encode import encode_pvr2
    from vqtex.golden.render.imageio import read_image
    src = read_image(os.path.join(data, "crate.png"))
    h, w = src.shape[:2]
    rows = []
    for fmt in formats:
        for tag, k, mip in variants:
            preview = read_image(os.path.join(data, "generated", f"crate_{fmt}_{tag}.preview.png"))
            theirs = _psnr(preview[:h, :w], src)
            t0 = time.perf_counter()
            _, dt = encode_pvr2(src, fmt, codebook_size=k, mipmaps=mip, seed=seed)
            secs = time.perf_counter() - t0
            ours = _psnr(parse_dt(dt).levels[0], src)
            rows.append({"format": fmt, "codebook": k, "mipmaps": mip, "pvrtex_db": round(theirs, 3),
                         "ours_db": round(ours, 3), "gain_db": round(ours - theirs, 3), "ours_seconds": round(secs, 2)})
    return rows


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m vqtex.sim.bench.encoding.pvr2_quality", description=__doc__.splitlines()[0])
    p.add_argument("--data", default=DEFAULT_DATA, help="folder holding crate.png and generated/ (default tests/data/pvrtex)")
    p.add_argument("--seed", type=int, default=0, help="encoder seed (default 0)")
    p.add_argument("--format", dest="formats", action="append", choices=FORMATS,
                   help="only this format (repeat for several; default all four)")
    p.add_argument("--codebook", type=int, choices=[64, 256], default=None,
                   help="only this codebook size (default both, 256 and 64)")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of the table")
    args = p.parse_args(argv)
    variants = [v for v in VARIANTS if args.codebook in (None, v[1])]
    rows = run(args.data, args.seed, tuple(args.formats or FORMATS), tuple(variants))
    if args.json:
        print(json.dumps({"rows": rows}))
        return 0
    print(f"{'format':<9} {'K':>4} {'mip':>4} {'pvrtex dB':>10} {'ours dB':>8} {'gain':>6} {'ours s':>7}")
    for r in rows:
        print(f"{r['format']:<9} {r['codebook']:>4} {'yes' if r['mipmaps'] else 'no':>4} {r['pvrtex_db']:>10.2f} "
              f"{r['ours_db']:>8.2f} {r['gain_db']:>+6.2f} {r['ours_seconds']:>7.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
