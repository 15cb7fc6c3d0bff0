"""``vqtex import FILE.dt... -o SET.vqt``: Dreamcast VQ textures (pvrtex's ``.dt``) as one texture set.

Each file becomes a texture in the PowerVR2 layout (twiddled index maps, one per mip level, its own
codebook of 16-bit texels; see docs/pvr2.md), texture ids in the order given. Every other command
also reads a single ``.dt`` directly; ``import`` is for several textures in one set (one unit, one
scene) and for keeping the set as a ``.vqt``.
"""

from __future__ import annotations

from .common import Outputs, add_json, emit, write_bytes

__all__ = ["add_parser", "cmd_import"]


def cmd_import(args) -> int:
    from vqtex.golden.format import FormatError
    from vqtex.golden.pvr2.pvr import PvrError
    from vqtex.golden.pvr2.pvr_set import import_dt
    with Outputs() as outs:
        out = outs.add(args.output, (".vqt",), "a texture set")
        try:
            ts = import_dt(args.files)
        except PvrError as e:
            raise FormatError(str(e).strip().splitlines()[0]) from None
        write_bytes(outs.path(out), ts.to_bytes())
    textures = [{"id": t, "name": i.name, "width": i.width, "height": i.height, "levels": i.levels, "color": i.color,
                 "codebook_size": ts.codebooks[i.codebook].size} for t, i in enumerate(ts.textures)]
    emit({"output": args.output, "textures": textures}, args.json,
         f"wrote {args.output}: {ts.n_textures} PowerVR2 texture(s) "
         + ", ".join(f"{t['name']} {t['width']}x{t['height']} {t['color']} K={t['codebook_size']}" for t in textures))
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("import", help="Dreamcast VQ textures (.dt, as pvrtex writes them) as one .vqt texture set")
    p.add_argument("files", nargs="+", metavar="FILE.dt",
                   help="VQ .dt textures (ARGB1555, RGB565, ARGB4444 or YUV422, twiddled); texture ids in this order")
    p.add_argument("-o", "--output", required=True, help="texture set to write (.vqt)")
    add_json(p)
    p.set_defaults(func=cmd_import)
