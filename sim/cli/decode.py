"""``vqtex decode FILE.vqt -o OUT.png [--texture N] [--level L]``: one level of one texture as an image."""

from __future__ import annotations

import numpy as np

from . import limits
from .common import IMAGE_SUFFIXES, CliError, Outputs, add_json, add_texture_set, emit, load_set, number_help

__all__ = ["add_parser", "cmd_decode"]


def cmd_decode(args) -> int:
    from vqtex.golden.render.imageio import write_image
    with Outputs() as outs:
        out = outs.add(args.output, IMAGE_SUFFIXES, "an image")
        ts = load_set(args.file)
        img = _decoded(ts, args)
        write_image(outs.path(out), img)
    h, w = img.shape[:2]
    emit({"texture": args.texture, "level": args.level, "width": w, "height": h, "output": args.output},
         args.json, f"wrote {args.output} ({w}x{h}, texture {args.texture} level {args.level})")
    return 0


def _decoded(ts, args) -> np.ndarray:
    """The level as the (h, w, channels) image written, filled band by band (golden.fetch.decode_bands):
    the picture and a bounded working set, never the RGBA level beside it."""
    from vqtex.golden.fetch import decode_bands
    if not 0 <= args.texture < ts.n_textures:
        raise CliError(f"texture {args.texture} does not exist (the file has {ts.n_textures})")
    levels = ts.textures[args.texture].levels
    if not 0 <= args.level < levels:
        raise CliError(f"texture {args.texture} has no level {args.level} (it has {levels})")
    channels = {"rgb": 3, "yuv411": 3, "rgba": 4, "intensity": 1, "rgb565": 3, "yuv422": 3, "argb1555": 4,
                "argb4444": 4}[ts.textures[args.texture].color]
    w, h = ts.level_shapes(args.texture)[args.level]
    bands = decode_bands(ts, args.texture, args.level)       # RequestError (a pruned level) before allocating
    img = np.empty((h, w, channels), np.uint8)
    for j0, rows in bands:
        img[j0: j0 + len(rows)] = rows[..., :channels]
    return img


def add_parser(sub) -> None:
    d = sub.add_parser("decode", help="decode one level of one texture to an image")
    add_texture_set(d)
    d.add_argument("-o", "--output", required=True, help="image to write (.png, .tif, .exr, ...)")
    d.add_argument("--texture", type=limits.TEXTURE, default=0,
                   help=number_help("texture number (vqtex info lists them)", limits.TEXTURE, 0))
    d.add_argument("--level", type=limits.LEVEL, default=0,
                   help=number_help("mip level, 0 = full size", limits.LEVEL, 0))
    add_json(d)
    d.set_defaults(func=cmd_decode)
