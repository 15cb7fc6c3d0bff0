"""``vqtex encode IMAGE... -o OUT.vqt``: compress images into a texture set with one shared codebook."""

from __future__ import annotations

import os

from . import limits
from .common import CliError, Outputs, add_json, emit, number_help, warn, with_default, write_bytes
from .info import add_psnr, info_report, info_text

__all__ = ["add_parser", "cmd_encode"]


def cmd_encode(args) -> int:
    from vqtex.golden.render.imageio import read_image
    with Outputs() as outs:
        if args.layout == "pvr2":           # Dreamcast PowerVR2 VQ (docs/pvr2.md)
            from .encode_pvr2 import check_pvr2_options, encode_pvr2_files
            out = outs.add(args.output, (".dt", ".vqt"), "a Dreamcast texture or a texture set")
            check_pvr2_options(args)
            images = [read_image(p) for p in args.images]
            ts, data = encode_pvr2_files(args, images, out)
            write_bytes(outs.path(out), data)
        else:
            out = outs.add(args.output, (".vqt",), "a texture set")
            _paper_defaults(args)
            images = [read_image(p) for p in args.images]
            ts = _encode(args, images)
            write_bytes(outs.path(out), ts.to_bytes())
    report = info_report(ts)
    add_psnr(report, ts, images)
    emit(report, args.json, info_text(ts, report) + f"\nwrote {args.output}")
    return 0


#: The paper layout's options whose argparse default is None (so that --layout pvr2 can tell whether
#: they were given): their defaults.
PAPER_DEFAULTS = {"color": "rgb", "block": (4, 4), "mip_training": "average", "encoder": "gla", "word_bits": 32}


def _paper_defaults(args) -> None:
    """Fill in the paper layout's defaults; ``--mip-training`` without ``--mipmaps`` is a CliError
    (it trains the extended codewords of a pyramid)."""
    if args.mip_training is not None and not args.mipmaps:
        raise CliError("--mip-training trains the extended codewords of a mip pyramid: it needs --mipmaps")
    for name, default in PAPER_DEFAULTS.items():
        if getattr(args, name) is None:
            setattr(args, name, default)


def _encode(args, images):
    """Encode; a warning for each setting that probably is not what the user meant: alpha that a
    colour format without alpha drops, more codewords than blocks, a result larger than the images."""
    from vqtex.golden.encode import encode
    names = [os.path.splitext(os.path.basename(p))[0] for p in args.images]
    if args.color != "rgba":
        dropped = [p for p, img in zip(args.images, images)
                   if img.ndim == 3 and img.shape[2] in (2, 4) and (img[..., -1] != 255).any()]
        if dropped:
            warn(f"--color {args.color} drops the alpha channel of {dropped[0]}"
                 f"{f' and {len(dropped) - 1} more' if len(dropped) > 1 else ''} (use --color rgba to keep it)")
    ts = encode(images, block=args.block, codebook_size=args.codebook_size, color=args.color,
                index_bits=args.index_bits, mipmaps=args.mipmaps, encoder=args.encoder, seed=args.seed,
                mip_training=args.mip_training, names=names, word_bits=args.word_bits)
    bw, bh = args.block
    blocks = sum((img.shape[1] // bw) * (img.shape[0] // bh) for img in images)
    if args.codebook_size > blocks:
        warn(f"{args.codebook_size} codewords for {blocks} blocks: at least {args.codebook_size - blocks} "
             f"codewords are never used (a smaller -k compresses better)")
    rate = ts.rates()["overall"]
    if rate < 1:
        warn(f"the compression rate is {rate:.2f}:1, below 1:1: the texture set is larger than the images "
             f"(the codebook dominates; use a smaller -k or larger images)")
    return ts


def add_parser(sub) -> None:
    e = sub.add_parser("encode", help="compress images into a .vqt texture set (one shared codebook), "
                                      "or a Dreamcast .dt (--layout pvr2)")
    e.add_argument("images", nargs="+", metavar="IMAGE",
                   help="images (PNG, TIFF, ...), sides powers of two; all share one codebook")
    e.add_argument("-o", "--output", required=True, help="the .vqt texture set to write (--layout pvr2: a .dt too)")
    e.add_argument("--block", type=limits.BLOCK, default=None,
                   help=number_help("block WxH (not with --layout pvr2: 2x2)", limits.BLOCK, "4x4"))
    e.add_argument("--codebook-size", "-k", type=limits.CODEBOOK_SIZE, default=256,
                   help=number_help("codewords K (2..4096 in the paper's layout, 1..256 in pvr2)",
                                    limits.CODEBOOK_SIZE, 256))
    e.add_argument("--layout", choices=["paper", "pvr2"], default="paper",
                   help=with_default("paper: the paper's layout (.vqt); pvr2: Dreamcast PowerVR2 VQ (2x2 blocks, "
                                     "8-bit twiddled indices, 16-bit texels; -o OUT.dt as pvrtex writes it, or .vqt)",
                                     "paper"))
    e.add_argument("--color", choices=["rgb", "rgba", "intensity", "yuv411", "rgb565", "argb1555", "argb4444",
                                       "yuv422"], default=None,
                   help=with_default("colour format of the codewords (yuv411: U, V at half resolution; "
                                     "rgb565, argb1555, argb4444, yuv422 with --layout pvr2)", "rgb; pvr2: rgb565"))
    e.add_argument("--index-bits", type=limits.INDEX_BITS, default=None,
                   help=number_help("index width b (not with --layout pvr2: 8)", limits.INDEX_BITS, "ceil(log2 K)"))
    e.add_argument("--mipmaps", action="store_true",
                   help="mip pyramid with extended codewords (default: level 0 only)")
    e.add_argument("--mip-training", choices=["average", "joint"], default=None,
                   help=with_default("with --mipmaps, extended codewords: averages of the level-0 codeword (the "
                                     "paper) or trained on all sub-levels (not with --layout pvr2)", "average"))
    e.add_argument("--encoder", choices=["gla", "tsvq"], default=None,
                   help=with_default("generalized Lloyd (TSVQ-initialised) or the paper's tree-structured VQ "
                                     "(not with --layout pvr2)", "gla"))
    e.add_argument("--encoder-seed", "--seed", dest="seed", type=limits.SEED, default=0,
                   help=number_help("seed of the codebook design (--seed is the old spelling)", limits.SEED, 0))
    e.add_argument("--word-bits", type=int, choices=[16, 32, 64], default=None,
                   help=with_default("width of the index memory's words (not with --layout pvr2: 32)", 32))
    add_json(e)
    e.set_defaults(func=cmd_encode)
