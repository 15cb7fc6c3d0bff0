"""``vqtex encode --layout pvr2``: images -> Dreamcast PowerVR2 VQ textures (``.dt`` as pvrtex writes
it, or a ``.vqt`` set in the PowerVR2 layout). The encoder is :func:`vqtex.golden.pvr2.pvr_encode.encode_pvr2`
(docs/pvr2.md); this module checks the options that apply and writes the output."""

from __future__ import annotations

import os

from .common import CliError, warn

__all__ = ["PVR2_COLORS", "encode_pvr2_files", "check_pvr2_options"]

#: --color choices of the PowerVR2 layout (the first is the default).
PVR2_COLORS = ("rgb565", "argb1555", "argb4444", "yuv422")


def encode_pvr2_files(args, images, out_path: str):
    """Encode ``images`` (one texture and codebook each) per ``args``; returns ``(texture_set, data)``:
    the bytes to write to ``out_path`` (a ``.dt`` of one texture, or the ``.vqt`` of them all).

    Raises CliError for an option the PowerVR2 layout does not take (:func:`check_pvr2_options`)."""
    from vqtex.golden.format import TextureSet
    from vqtex.golden.pvr2.pvr_encode import PvrEncodeError, encode_pvr2
    color = check_pvr2_options(args)
    dt = out_path.lower().endswith(".dt")
    if dt and len(images) != 1:
        raise CliError(f"a .dt holds one texture: {len(images)} images need a .vqt output (or one .dt each)")
    if color in ("rgb565", "yuv422"):
        dropped = [p for p, img in zip(args.images, images)
                   if img.ndim == 3 and img.shape[2] in (2, 4) and (img[..., -1] != 255).any()]
        if dropped:
            warn(f"--color {color} drops the alpha channel of {dropped[0]} (argb1555 or argb4444 keep it)")
    sets, data = [], b""
    for path, img in zip(args.images, images):
        try:
            ts, data = encode_pvr2(img, color, codebook_size=args.codebook_size, mipmaps=args.mipmaps, seed=args.seed,
                                   name=os.path.splitext(os.path.basename(path))[0])
        except PvrEncodeError as e:
            raise CliError(f"{path}: {e}") from None
        sets.append(ts)
    ts = sets[0] if len(sets) == 1 else TextureSet.combine(sets)
    return ts, (data if dt else ts.to_bytes())


def check_pvr2_options(args) -> str:
    """The colour format of ``--layout pvr2`` (``--color``, default rgb565); a CliError, before any
    work, for an option this layout does not take: one of its colours only, ``-k`` 1..256, and no
    ``--block``, ``--index-bits``, ``--mip-training``, ``--encoder`` or ``--word-bits`` at all
    (given is refused whatever the value: their argparse defaults are None)."""
    color = args.color or PVR2_COLORS[0]
    if color not in PVR2_COLORS:
        raise CliError(f"--layout pvr2 takes --color {', '.join(PVR2_COLORS)}, not {color}")
    fixed = {"--block": args.block, "--index-bits": args.index_bits, "--mip-training": args.mip_training,
             "--encoder": args.encoder, "--word-bits": args.word_bits}
    for name, value in fixed.items():
        if value is not None:                   # given at all, whatever its value (argparse default None)
            raise CliError(f"{name} does not apply to --layout pvr2 (2x2 blocks, 8-bit indices, 32-bit words, "
                           "its own encoder)")
    if not 1 <= args.codebook_size <= 256:
        raise CliError(f"--layout pvr2 takes a codebook of 1..256 entries, not -k {args.codebook_size}")
    return color
