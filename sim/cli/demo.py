"""``vqtex demo``: the main job on embedded defaults, offline.

Encodes the bundled textures of the built-in ``topspin`` scene, renders a few frames with the golden
model and with the compiled RTL, checks they are identical, writes the frames, the texture set and a
report, and prints a summary. ``--unit``/``--geometry`` choose the RTL unit (the loadable one loads
the set over its bus before each frame); ``--memory external`` puts the index map and raw levels
behind caches (the baked cached unit, or with ``--unit loadable`` the loadable cached unit, whose
load writes the base registers; the report's ``unit`` is ``cached`` or ``loadable cached``). The files appear together when the demo succeeds, or not at all
(:class:`~vqtex.sim.cli.common.Outputs`): a new output folder appears with one rename.
"""

from __future__ import annotations

import os
import time

import numpy as np

from .common import (CliError, Outputs, add_backend, add_json, add_memory_options, add_unit, emit, memory_config,
                     resolve, unit_geometry, with_default, write_bytes, write_json)
from vqtex.sim.reports.quality import DEFAULT_VMAX, side_by_side

from .render import encode_scene, memory_line, memory_summary, parse_frames, render_to_files

__all__ = ["add_parser", "cmd_demo"]

BACKENDS = ["cxxrtl", "verilator", "pysim", "golden"]
#: The side-by-side picture of the first frame.
COMPARE_NAME = "topspin_compare.png"


def cmd_demo(args) -> int:
    """Encode the bundled textures, render a few topspin frames with golden and compiled RTL,
    check they are identical, write the frames and a report, print a summary."""
    from vqtex.golden.render.scene import load_scene
    t_start = time.perf_counter()
    memory = memory_config(args)
    if memory is not None and args.unit not in (None, "loadable"):
        raise CliError(f"--memory external is the cached unit, baked or loadable: no --unit {args.unit}")
    with Outputs() as outs:
        out_dir = outs.folder(args.out_dir)
        scene = load_scene("topspin")
        frames = parse_frames(args.frames, scene.frames)
        vqt, report_path, compare = (outs.add(os.path.join(out_dir, n))
                                     for n in ("topspin.vqt", "report.json", COMPARE_NAME))
        frame_paths = {f: outs.add(os.path.join(out_dir, f"topspin_{f:04d}.png")) for f in frames}
        images = [img for img, _ in scene.load_textures()]
        resolve(args, "unit", "specialised", args.backend != "golden" or (memory is not None and args.unit == "loadable"),
                "chooses the RTL texel-fetch unit: it needs an RTL --backend (pysim, cxxrtl, verilator)")
        t0 = time.perf_counter()
        ts = encode_scene(scene, images)
        encode_s = time.perf_counter() - t0
        geometry = unit_geometry(args, ts, "topspin's texture set")
        write_bytes(outs.path(vqt), ts.to_bytes())
        per_frame, mismatches = render_to_files(
            scene, ts, frames, frame_paths.get, images, outs=outs, mode="trilinear", backend=args.backend,
            cycle_model=True, on_frame=lambda r: _compare(r, outs.path(compare)) if r["frame"] == frames[0] else None,
            unit=args.unit, geometry=geometry, memory=memory)
        report = _report(args, ts, per_frame, mismatches, encode_s)
        report["unit"] = args.unit
        if memory is not None:
            report["unit"] = "loadable cached" if geometry is not None else "cached"
            report["memory"] = memory_summary(memory, per_frame)
        if geometry is not None:
            report["geometry"] = geometry.to_dict()
            report["load_cycles_per_frame"] = per_frame[0].get("load_cycles")
        report["comparison"] = {"file": COMPARE_NAME, "frame": frames[0], "difference_scale": DEFAULT_VMAX,
                                "panels": ["uncompressed", "compressed", "difference"]}
        report["total_seconds"] = round(time.perf_counter() - t_start, 2)
        write_json(outs.path(report_path), report)
    emit(report, args.json, _summary(args, scene, frames, report, per_frame, mismatches))
    if mismatches:
        raise CliError(f"RTL frames {mismatches} differ from the golden frames")
    return 0


def _compare(r, path):
    """The side-by-side picture of frame ``r``: uncompressed | compressed | difference heat map."""
    from vqtex.golden.render.imageio import write_image
    write_image(path, side_by_side(r["reference"], r["image"]))


def _report(args, ts, per_frame, mismatches, encode_s) -> dict:
    rates = {t.name: round(ts.rates(k)["overall"], 3) for k, t in enumerate(ts.textures)}
    return {
        "scene": "topspin", "frames": per_frame, "backend": args.backend,
        "rtl_ran": args.backend != "golden",
        "identical_to_golden": not mismatches if args.backend != "golden" else None,
        "cycles_from": "the exact cycle model (no RTL ran)" if args.backend == "golden" else f"RTL ({args.backend})",
        "texture_rates": rates, "overall_rate": round(ts.rates()["overall"], 4),
        "mean_mse": round(float(np.mean([f["mse"] for f in per_frame])), 4),
        "cycles_per_frame": round(float(np.mean([f["cycles"] for f in per_frame])), 1),
        "encode_seconds": round(encode_s, 2),
    }


def _summary(args, scene, frames, report, per_frame, mismatches) -> str:
    if args.backend == "golden":
        rtl = "  RTL: not run (--backend golden); cycles below are the golden cycle model's"
    else:
        rtl = (f"  RTL ({args.backend}, {report['unit']} unit) frames identical to golden: "
               f"{'yes' if not mismatches else 'NO ' + str(mismatches)}")
    if report.get("load_cycles_per_frame") is not None:
        rtl += f"\n  loaded over the bus port before each frame: {report['load_cycles_per_frame']} cycles"
    return "\n".join([
        f"vqtex demo: topspin, {len(frames)} frames {scene.width}x{scene.height}, trilinear mipmapping",
        "  textures: " + ", ".join(f"{n} {r:.1f}:1" for n, r in report["texture_rates"].items())
        + f"  (overall {report['overall_rate']:.2f}:1)",
        f"  frame MSE vs uncompressed: {report['mean_mse']:.3f} (mean over frames)",
        rtl,
        f"  cycles per frame: {report['cycles_per_frame']:.0f} for "
        f"{np.mean([f['requests'] for f in per_frame]):.0f} texel requests (latency {per_frame[0].get('latency', 0)})",
        *(["  " + memory_line(report)] if "memory" in report else []),
        f"  {args.out_dir}/{COMPARE_NAME}: frame {frames[0]} uncompressed | compressed | difference "
        f"(black 0 to white {DEFAULT_VMAX}+ levels, the scale under it)",
        f"  wrote {args.out_dir}/topspin_*.png, topspin.vqt and report.json in {report['total_seconds']:.1f} s",
    ])


def add_parser(sub) -> None:
    d = sub.add_parser("demo", help="the main job on embedded defaults (offline)")
    d.add_argument("-o", "--out-dir", default="vqtex-demo",
                   help=with_default("folder for the frames, topspin.vqt and report.json (its parent must exist)",
                                     "vqtex-demo"))
    d.add_argument("--frames", default="0:3", help=with_default("frames of topspin to render, a Python slice A:B[:STEP] "
                                                               "or one number", "0:3"))
    add_backend(d, BACKENDS, "cxxrtl")
    add_unit(d)
    add_memory_options(d)
    add_json(d)
    d.set_defaults(func=cmd_demo)
