"""``vqtex need SCENE [--frames A:B] [--json] [--heatmap DIR]``: what a scene's frames touch in its
texture set (``golden.need.analysis``): textures, levels, level groups, blocks, codewords, formats, distinct
memory words per frame, block-buffer and block-cache hits, and heat maps of the blocks touched."""

from __future__ import annotations

import os

import numpy as np

from . import limits
from .common import CliError, Outputs, add_json, emit, load_set, number_help, with_default

__all__ = ["add_parser", "cmd_need", "need_text", "scene_need", "write_heatmaps", "add_need_source"]


def add_need_source(p) -> None:
    """The options that say which frames of which scene, and which texture set (need, prune)."""
    p.add_argument("--frames", help=with_default("frames to analyse: a Python slice A:B[:STEP] or one frame number",
                                                 "all"))
    p.add_argument("--mode", choices=["point", "bilinear", "trilinear"], default="trilinear",
                   help=with_default("the sampling mode whose requests are analysed", "trilinear"))
    p.add_argument("--requests", choices=["sparse", "fixed"], default="sparse",
                   help=with_default("the request stream analysed: sparse (no zero-weight texels or repeats in a "
                                     "footprint) or fixed (every pixel's whole footprint), as vqtex render issues "
                                     "them", "sparse"))


def scene_need(scene, ts, frames, mode="trilinear", cache=None, progress=True, per_frame=True, stream="sparse"):
    """The :class:`~vqtex.golden.need.analysis.Need` of ``frames`` of ``scene`` in ``ts`` (a progress bar)."""
    from vqtex.golden.fetch import check_requests
    from vqtex.golden.need.analysis import CacheSpec, NeedCounter, scene_streams

    from .render import Progress
    counter = NeedCounter(ts, cache or CacheSpec(), per_frame)
    prog = Progress(len(frames), "analysing frames") if progress else None
    for f, reqs in scene_streams(scene, ts, frames, mode, stream=stream):
        check_requests(ts, reqs[:, 0], reqs[:, 1], reqs[:, 2], reqs[:, 3])
        counter.add(f, reqs)
        if prog:
            prog.step()
    if prog:
        prog.done()
    return counter.result()


def need_text(name: str, summary: dict) -> str:
    """The need report as a few lines of text."""
    s = summary
    fr = s.get("per_frame", [])
    tot = s["totals"]
    req = max(1, tot["requests"])

    def pair(key, a="touched"):
        return f"{s[key][a]}/{s[key]['stored']}"

    mem_t, mem_s = s["memory_touched"], s["memory_stored"]
    lines = [
        f"{name}: {tot['frames']} frame(s), {tot['requests']} requests",
        f"  touched/stored: textures {pair('textures')}, levels {pair('levels')}, level groups "
        f"{pair('level_groups')}, compressed blocks {pair('compressed_blocks')}, codewords "
        f"{s['codewords']['used']}/{s['codewords']['stored']}",
        f"  formats: colours {', '.join(s['formats']['colors'])}; index widths "
        f"{', '.join(map(str, s['formats']['index_bits'])) or '-'}; sub-levels "
        f"{', '.join(map(str, s['formats']['sublevels'])) or '-'}",
        f"  memory words touched/stored (all frames): index {mem_t['index_words']}/{mem_s['index_words']}, "
        f"codebook entries {mem_t['codebook_entries']}/{mem_s['codebook_entries']}, raw "
        f"{mem_t['raw_words']}/{mem_s['raw_words']}",
    ]
    if fr:
        mean = {k: float(np.mean([f[k] for f in fr])) for k in ("index_words", "codebook_entries", "raw_words",
                                                                 "blocks", "requests")}
        lines.append(f"  per frame (mean): {mean['requests']:.0f} requests, {mean['blocks']:.0f} distinct blocks, "
                     f"{mean['index_words']:.0f} index words, {mean['codebook_entries']:.0f} codebook entries, "
                     f"{mean['raw_words']:.0f} raw words")
    lines.append(f"  reads repeating the previous request's block: {tot['buffer_hits']} ({100 * tot['buffer_hits'] / req:.1f}%); "
                 f"hits in a {s['cache']['policy']}: {tot['cache_hits']} ({100 * tot['cache_hits'] / req:.1f}%)")
    for t in s["texture_detail"]:
        lv = t["levels_touched"]
        blocks = sum(r["blocks_touched"] for r in t["level_rows"])
        stored = sum(r["blocks"] for r in t["level_rows"])
        lines.append(f"  texture {t['texture']} {t['name']}: " + (
            f"levels {', '.join(map(str, lv))} of {t['levels']}, {blocks}/{stored} blocks or raw texels"
            if lv else "not touched"))
    return "\n".join(lines)


def heatmap_names(ts, need) -> dict:
    """File name (in the heat map folder) of each stored (texture, level): ``tTT_NAME_LL.png``."""
    names = {}
    valid = ts.descriptors["valid"].astype(bool)
    for t, info in enumerate(ts.textures):
        safe = "".join(c if c.isalnum() or c in "-_" else "_" for c in info.name)[:64] or "texture"
        for L in range(info.levels):
            if valid[t, L]:
                names[(t, L)] = f"t{t:02d}_{safe}_L{L:02d}.png"
    return names


def write_heatmaps(outs, folder: str, ts, need) -> list[str]:
    """One PNG per stored (texture, level) of the blocks touched, into the registered ``folder``."""
    from vqtex.golden.need.analysis import heat_image
    from vqtex.golden.render.imageio import write_image
    written = []
    for (t, L), name in heatmap_names(ts, need).items():
        path = outs.add(os.path.join(folder, name))
        write_image(outs.path(path), heat_image(need, t, L))
        written.append(name)
    return written


def cmd_need(args) -> int:
    from vqtex.golden.need.analysis import CacheSpec
    from vqtex.golden.render.scene import load_scene

    from .render import encode_scene, parse_frames
    try:
        cache = CacheSpec(tile=args.cache_tile, ways=args.cache_ways)
    except ValueError as e:
        raise CliError(f"--cache-tile/--cache-ways: {e}") from None
    with Outputs() as outs:
        folder = outs.folder(args.heatmap) if args.heatmap else None
        scene = load_scene(args.scene)
        frames = parse_frames(args.frames, scene.frames)
        ts = load_set(args.texture_set) if args.texture_set else encode_scene(scene, None)
        if ts.n_textures != len(scene.textures):
            raise CliError(f"{args.texture_set} holds {ts.n_textures} textures, the scene uses {len(scene.textures)}")
        need = scene_need(scene, ts, frames, args.mode, cache, stream=args.requests)
        report = {"scene": scene.name, "mode": args.mode, "requests": args.requests, "frames": frames,
                  **need.summary()}
        if folder:
            report["heatmaps"] = {"folder": args.heatmap, "files": write_heatmaps(outs, folder, ts, need)}
    text = need_text(scene.name, report)
    if folder:
        text += f"\nwrote {len(report['heatmaps']['files'])} heat maps into {args.heatmap}"
    emit(report, args.json, text)
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("need", help="what a scene's frames touch in its texture set: textures, levels, blocks, "
                                    "codewords, memory words, block buffer and cache hits")
    p.add_argument("scene", help="scene file (docs/rendering.md) or built-in scene name (topspin, town)")
    add_need_source(p)
    p.add_argument("--texture-set", metavar="FILE.vqt",
                   help=with_default("analyse this texture set instead of encoding the scene's textures",
                                     "encode them with the scene's settings"))
    p.add_argument("--cache-tile", type=limits.CACHE_TILE, default=(8, 8),
                   help=number_help("the block cache's sets as a WxH tile of block coordinates (8x8 is 64 sets)",
                                    limits.CACHE_TILE, "8x8"))
    p.add_argument("--cache-ways", type=int, choices=[1, 2, 4, 8, 16], default=2,
                   help=with_default("blocks per cache set: 1 direct-mapped, more LRU (the memory system's "
                                     "cache model, docs/memory.md)", 2))
    p.add_argument("--heatmap", metavar="DIR",
                   help=with_default("write a PNG per stored texture level of the blocks touched into this folder "
                                     "(created; its parent must exist)", "none"))
    add_json(p)
    p.set_defaults(func=cmd_need)
