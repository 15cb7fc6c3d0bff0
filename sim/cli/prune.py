"""``vqtex prune [SET.vqt] --scene SCENE --frames A:B -o OUT.vqt``: a texture set holding only what
some frames of a scene need (``golden.need.prune``), with its bytes before and after; without ``SET.vqt``,
the scene's textures are encoded for those frames only (``golden.need.prune.encode_needed``)."""

from __future__ import annotations

import time

from .common import CliError, Outputs, add_json, emit, load_set, resolve, with_default, write_bytes
from .need import add_need_source, scene_need

__all__ = ["add_parser", "cmd_prune", "prune_text", "add_train_on"]


def prune_text(r: dict) -> str:
    b, a = r["before"], r["after"]

    def ch(key):
        return f"{b[key]} -> {a[key]}"
    lines = [
        f"stored: textures {ch('textures')}, levels {ch('levels')} (compressed {ch('compressed_levels')}), "
        f"blocks of compressed levels {ch('compressed_level_blocks')}, codewords {ch('codewords')}",
        f"memory bytes (index + codebook + raw): {b['memory_bytes']} -> {a['memory_bytes']} "
        f"({100 * (1 - a['memory_bytes'] / max(1, b['memory_bytes'])):.1f}% less); file {b['bytes']['file']} -> "
        f"{a['bytes']['file']} bytes (with {a['bytes']['present_blocks']} bytes of block presence bits)",
        "index widths: " + ", ".join(f"{x}->{y}" for x, y in zip(b["index_bits"], a["index_bits"]) if x is not None),
    ]
    if "encode_seconds" in r:
        line = f"encoded for the frames in {r['encode_seconds']:.2f} s"
        if "full_encode_seconds" in r:
            line += f", the full encode took {r['full_encode_seconds']:.2f} s"
        lines.append(line)
    return "\n".join(lines)


def cmd_prune(args) -> int:
    from vqtex.golden.need.prune import encode_needed, prune, prune_report
    from vqtex.golden.render.scene import build_texture_set, load_scene

    from .render import Progress, parse_frames
    with Outputs() as outs:
        out = outs.add(args.output, (".vqt",), "a texture set")
        scene = load_scene(args.scene)
        frames = parse_frames(args.frames, scene.frames)
        extra = {"scene": scene.name, "frames": frames, "mode": args.mode, "requests": args.requests}
        resolve(args, "train_on", "levels", not args.file,
                "is for encoding (no SET.vqt): a set's codebooks are already trained")
        if args.file:
            if args.compare:
                raise CliError("--compare times a full encode against encoding for the frames: give no SET.vqt")
            ts = load_set(args.file)
            if ts.n_textures != len(scene.textures):
                raise CliError(f"{args.file} holds {ts.n_textures} textures, the scene uses {len(scene.textures)}")
            t0 = time.perf_counter()
            pruned = prune(ts, scene_need(scene, ts, frames, args.mode, per_frame=False, stream=args.requests))
            extra["prune_seconds"] = round(time.perf_counter() - t0, 3)
            before = ts
        else:
            images = [img for img, _ in scene.load_textures()]
            prog = Progress(1, "encoding for the frames")
            t0 = time.perf_counter()
            pruned, need = encode_needed(scene, frames, args.mode, images, train=args.train_on, stream=args.requests)
            extra["train_on"] = args.train_on
            extra["encode_seconds"] = round(time.perf_counter() - t0, 3)
            prog.step()
            prog.done()
            before = need.ts
            if args.compare:
                prog = Progress(1, "encoding everything")
                t0 = time.perf_counter()
                before = build_texture_set(scene, images)
                extra["full_encode_seconds"] = round(time.perf_counter() - t0, 3)
                prog.step()
                prog.done()
        write_bytes(outs.path(out), pruned.to_bytes())
        report = prune_report(before, pruned, **extra)
    emit(report, args.json, prune_text(report) + f"\nwrote {args.output}")
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("prune", help="a texture set holding only what some frames of a scene need "
                                     "(textures, levels, blocks, codewords), or encode only that")
    p.add_argument("file", metavar="SET.vqt", nargs="?",
                   help=with_default("the texture set to prune (texture k is the scene's texture k)",
                                     "encode the scene's textures for the frames only: the touched levels, "
                                     "codebooks trained on them"))
    p.add_argument("--scene", required=True, help="scene file or built-in scene name whose frames decide what stays")
    add_need_source(p)
    p.add_argument("-o", "--output", required=True, help="the pruned .vqt texture set to write")
    p.add_argument("--compare", action="store_true",
                   help="without SET.vqt: also encode everything, to report the bytes before and the time saved "
                        "(default: no full encode; 'before' is the encode of the touched levels)")
    add_train_on(p)
    add_json(p)
    p.set_defaults(func=cmd_prune)


def add_train_on(p) -> None:
    """``--train-on``: what encoding for the frames trains the codebooks on."""
    p.add_argument("--train-on", choices=["levels", "blocks"], default=None,
                   help=with_default("encoding for the frames: train the codebooks on every block of the touched "
                                     "level groups, or on the touched blocks only", "levels"))
