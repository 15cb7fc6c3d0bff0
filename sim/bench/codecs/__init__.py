"""Against the codecs a user would pick instead: VQ beside BC1, ASTC, JPEG 2000 and a wavelet coder,
on the same images: bits per texel, PSNR, encode time, whole-image decode time and the cost of one
random texel, each against its physical floor (docs/codecs.md).

One module per codec, each with ``rows(name, image, ...)`` giving rows of the shared schema
(:mod:`.schema`); :mod:`.measure` says how everything is timed. :func:`codec_rows` runs them all:

* :mod:`.vq` -- the project's encoder and golden fetch at a few configurations; their bits per texel
  are the **target rates** of the rate-controlled codecs (JPEG 2000 and the wavelet coder), so each
  of those rows sits at the rate of a VQ row of the same image (its ``config`` names it: ``@2x2/256 rgb``);
* :mod:`.bc1` -- BC1/DXT1 at 4 bits per texel (etcpak and quicktex; texture2ddecoder and a numpy
  decoder);
* :mod:`.astc` -- ASTC 8x8 (2 bits per texel) and 12x12 (0.89) through astcenc;
* :mod:`.jpeg2000` -- JPEG 2000 (OpenJPEG through glymur), untiled and in 64x64 tiles;
* :mod:`.wavelet` -- Haar and LeGall 5/3 with dead-zone quantisation and entropy-counted bits,
  untiled and in 64x64 tiles.

``vqtex bench codecs [--json] [--quick]`` prints the table (needs the ``codecs`` extra, and the
``bench`` extra's scikit-image for the full run's photographs).
"""

from __future__ import annotations

import json
import sys

import numpy as np

from . import astc, bc1, jpeg2000, vq, wavelet
from .measure import RANDOM_TEXELS, random_texels
from .schema import FIELDS

__all__ = ["codec_rows", "summary", "run", "print_table", "default_images", "FIELDS", "METHODS"]

METHODS = ("vq", "bc1", "astc", "jpeg2000", "wavelet")

#: Photographs (scikit-image, CC0 / public domain; 512x512 centre crops) and textures of the full run.
PHOTOS = ("astronaut", "immunohistochemistry", "hubble_deep_field", "retina")
BUNDLED = ("lawn.png", "brick_red.png", "road.png")            # golden/data, 128x128
PROCEDURAL = ("wood", "marble")                                 # golden.render.textures, 256x256 (topspin's)
#: The quick run: two bundled textures, no scikit-image needed.
QUICK_BUNDLED = ("astronaut.png", "lawn.png")


def _check_images(images) -> None:
    if not isinstance(images, dict) or not images:
        raise ValueError("images must be a non-empty dict of name -> (H, W, 3) uint8 array")
    for name, img in images.items():
        a = np.asarray(img)
        if a.dtype != np.uint8 or a.ndim != 3 or a.shape[2] != 3:
            raise ValueError(f"image {name!r} is {a.dtype} {a.shape}, not (H, W, 3) uint8")
        h, w = a.shape[:2]
        if min(h, w) < 16 or h & (h - 1) or w & (w - 1):
            raise ValueError(f"image {name!r} is {w}x{h}: sides must be powers of two from 16")


def codec_rows(images: dict, *, methods=METHODS, vq_configs=vq.CONFIGS, bc1_encoders=bc1.ENCODERS,
               astc_blocks=astc.BLOCKS, jpeg2000_tiles=jpeg2000.TILES, wavelets=tuple(wavelet.WAVELETS),
               wavelet_tiles=wavelet.TILES, repeats: int = 3, random_texels_n: int = RANDOM_TEXELS,
               jpeg2000_sample: int = jpeg2000.RANDOM_SAMPLE, targets: dict | None = None, seed: int = 0,
               log=None) -> list[dict]:
    """Rows of the shared schema (:data:`FIELDS`) for every image and codec configuration.

    images: {name: (H, W, 3) uint8}, sides powers of two from 16 (VQ's textures).
    JPEG 2000 and the wavelet coder run at the bits per texel of each VQ row of the same image, and
    at the rates of ``targets`` ({label: bits per texel}, the same for every image; their rows'
    config ends ``@label``): without ``vq`` in ``methods`` and without ``targets`` they have no rate.
    Times are the best of ``repeats``; random texels are batches of ``random_texels_n`` (the same
    coordinates for every codec of an image, seeded by ``seed``).
    """
    _check_images(images)
    unknown = set(methods) - set(METHODS)
    if unknown:
        raise ValueError(f"unknown methods {sorted(unknown)} (known: {', '.join(METHODS)})")
    if "jpeg2000" in methods:
        jpeg2000.openjpeg()                                   # a missing libopenjp2 fails before any work
    log = log or (lambda msg: None)
    out = []
    for n, (name, img) in enumerate(images.items()):
        img = np.ascontiguousarray(img)
        y, x = random_texels(img.shape, random_texels_n, seed + n)
        rates = {}
        if "vq" in methods:
            log(f"{name}: vq {', '.join(vq.applicable(vq_configs, img.shape)) or '(none fits)'}")
            vrows = vq.rows(name, img, y=y, x=x, repeats=repeats, configs=vq_configs, seed=seed)
            rates = {r["config"]: r["bits_per_texel"] for r in vrows}
            out += vrows
        rates.update({str(k): float(v) for k, v in (targets or {}).items()})
        if "bc1" in methods:
            log(f"{name}: bc1 {', '.join(bc1_encoders)}")
            out += bc1.rows(name, img, y=y, x=x, repeats=repeats, encoders=bc1_encoders)
        if "astc" in methods:
            log(f"{name}: astc {', '.join(f'{b}x{b}' for b in astc_blocks)}")
            out += astc.rows(name, img, y=y, x=x, repeats=repeats, blocks=astc_blocks)
        if "jpeg2000" in methods and rates:
            log(f"{name}: jpeg2000 at {len(rates)} rates")
            out += jpeg2000.rows(name, img, targets=rates, y=y, x=x, repeats=repeats, tiles=jpeg2000_tiles,
                                 sample=jpeg2000_sample)
        if "wavelet" in methods and rates:
            log(f"{name}: wavelets at {len(rates)} rates")
            out += wavelet.rows(name, img, targets=rates, y=y, x=x, repeats=repeats, wavelets=wavelets,
                                tiles=wavelet_tiles)
    return out


def summary(rows: list[dict]) -> list[dict]:
    """Per (method, config) over the images: mean bits per texel and PSNR (over the lossy images;
    ``None`` if every one was exact), median times, and the median ratios of the random texel and
    the decode to their floors."""
    groups: dict = {}
    for r in rows:
        groups.setdefault((r["method"], r["config"]), []).append(r)
    out = []
    for (method, config), rs in groups.items():
        med = lambda k: float(np.median([r[k] for r in rs]))                  # noqa: E731
        lossy = [r["psnr_db"] for r in rs if r["psnr_db"] is not None]
        out.append({"method": method, "config": config, "images": len(rs),
                    "bits_per_texel": float(np.mean([r["bits_per_texel"] for r in rs])),
                    "psnr_db": float(np.mean(lossy)) if lossy else None,
                    "encode_s": med("encode_s"), "decode_s": med("decode_s"),
                    "random_texel_s": med("random_texel_s"),
                    "random_over_floor": float(np.median([r["random_texel_s"] / r["random_floor_s"] for r in rs])),
                    "decode_over_floor": float(np.median([r["decode_s"] / r["floor_s"] for r in rs]))})
    return out


def default_images(quick: bool = False) -> dict:
    """The benchmark's images: quick: two bundled textures (astronaut 256x256, lawn 128x128); full:
    scikit-image's photographs (512x512 crops; needs scikit-image), three bundled 128x128 textures
    and topspin's procedural wood and marble (256x256)."""
    from vqtex.golden.render.imageio import read_image
    from vqtex.golden.render.scene import DATA_DIR
    from vqtex.golden.render.textures import generate

    def bundled(f):
        return {f.removesuffix(".png"): np.ascontiguousarray(read_image(DATA_DIR / f)[..., :3])}
    if quick:
        return {k: v for f in QUICK_BUNDLED for k, v in bundled(f).items()}
    from ..encoding.encoder import load_images
    out = dict(zip(PHOTOS, load_images(PHOTOS)))
    for f in BUNDLED:
        out.update(bundled(f))
    for t in PROCEDURAL:
        out[t] = np.ascontiguousarray(generate(t, size=(256, 256))[..., :3])
    return out


QUICK = dict(vq_configs=vq.QUICK_CONFIGS, repeats=2, random_texels_n=4096, jpeg2000_sample=8)


def run(json_out: bool = False, *, quick: bool = False, images: dict | None = None, **options) -> dict:
    """Run the benchmark on :func:`default_images` (or ``images``); print the table (or one JSON
    object) and return the result. ``options`` go to :func:`codec_rows` (``quick`` presets some)."""
    def log(msg):
        print(msg, file=sys.stderr if json_out else sys.stdout, flush=True)
    imgs = default_images(quick) if images is None else images
    opts = {**(QUICK if quick else {}), **options}
    rows = codec_rows(imgs, log=log, **opts)
    out = {"benchmark": "codecs", "quick": bool(quick),
           "images": {k: [int(v.shape[1]), int(v.shape[0])] for k, v in imgs.items()},
           "options": {k: (list(v) if isinstance(v, tuple) else v) for k, v in opts.items()},
           "fields": list(FIELDS), "rows": rows, "summary": summary(rows)}
    if json_out:
        print(json.dumps(out))
    else:
        print_table(out)
    return out


def _db(p) -> str:
    return " exact" if p is None else f"{p:6.2f}"


def _us(s: float) -> str:
    return f"{s * 1e6:10.3f}" if s < 1e-3 else f"{s * 1e6:10.0f}"


def print_table(out: dict) -> None:
    """The readable table: every row by image, then the summary over images."""
    hdr = (f"{'method':<8} {'config':<36} {'bpt':>6} {'PSNR':>6} | {'encode ms':>9} {'decode ms':>9} "
           f"{'x floor':>8} | {'texel us':>10} {'x floor':>8}")
    for name in out["images"]:
        w, h = out["images"][name]
        print(f"\n{name} ({w}x{h})")
        print(hdr)
        print("-" * len(hdr))
        for r in out["rows"]:
            if r["image"] != name:
                continue
            print(f"{r['method']:<8} {r['config']:<36} {r['bits_per_texel']:6.3f} {_db(r['psnr_db'])} | "
                  f"{r['encode_s'] * 1e3:9.2f} {r['decode_s'] * 1e3:9.3f} {r['decode_s'] / r['floor_s']:8.0f} | "
                  f"{_us(r['random_texel_s'])} {r['random_texel_s'] / r['random_floor_s']:8.0f}")
    print(f"\nover {len(out['images'])} images: mean bpt and PSNR, median times and ratios to the floor")
    print(hdr)
    print("-" * len(hdr))
    for s in out["summary"]:
        print(f"{s['method']:<8} {s['config']:<36} {s['bits_per_texel']:6.3f} {_db(s['psnr_db'])} | "
              f"{s['encode_s'] * 1e3:9.2f} {s['decode_s'] * 1e3:9.3f} {s['decode_over_floor']:8.0f} | "
              f"{_us(s['random_texel_s'])} {s['random_over_floor']:8.0f}")
    print("floor: decode = copying the decoded RGB bytes once; texel = reading the same random texels "
          "from a decoded array (numpy), per texel")
