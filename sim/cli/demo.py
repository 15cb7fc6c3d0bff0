"""``vqtex demo``: the main job on embedded defaults, offline.

Encodes the bundled textures of the built-in ``topspin`` scene, renders a few frames with the golden
model and with the compiled RTL, checks they are identical, writes the frames, the texture set and a
report, and prints a summary.
"""

from __future__ import annotations

import os
import time

import numpy as np

from .common import CliError, emit, write_json
from .render import encode_scene, parse_frames, render_to_files

__all__ = ["add_parser", "cmd_demo"]


def cmd_demo(args) -> int:
    """Encode the bundled textures, render a few topspin frames with golden and compiled RTL,
    check they are identical, write the frames and a report, print a summary."""
    from vqtex.golden.render.scene import load_scene
    t_start = time.perf_counter()
    os.makedirs(args.out_dir, exist_ok=True)
    scene = load_scene("topspin")
    frames = parse_frames(args.frames, scene.frames)
    images = [img for img, _ in scene.load_textures()]
    t0 = time.perf_counter()
    ts = encode_scene(scene, images)
    encode_s = time.perf_counter() - t0
    ts.save(os.path.join(args.out_dir, "topspin.vqt"))
    per_frame, mismatches = render_to_files(
        scene, ts, frames, lambda f: os.path.join(args.out_dir, f"topspin_{f:04d}.png"), images,
        mode="trilinear", backend=args.backend)
    rates = {t.name: round(ts.rates(k)["overall"], 3) for k, t in enumerate(ts.textures)}
    report = {
        "scene": "topspin", "frames": per_frame, "backend": args.backend,
        "identical_to_golden": not mismatches,
        "texture_rates": rates, "overall_rate": round(ts.rates()["overall"], 4),
        "mean_mse": round(float(np.mean([f["mse"] for f in per_frame])), 4),
        "cycles_per_frame": round(float(np.mean([f.get("cycles", 0) for f in per_frame])), 1),
        "encode_seconds": round(encode_s, 2), "total_seconds": round(time.perf_counter() - t_start, 2),
    }
    write_json(os.path.join(args.out_dir, "report.json"), report)
    lines = [
        f"vqtex demo: topspin, {len(frames)} frames {scene.width}x{scene.height}, trilinear mipmapping",
        "  textures: " + ", ".join(f"{n} {r:.1f}:1" for n, r in rates.items())
        + f"  (overall {report['overall_rate']:.2f}:1)",
        f"  frame MSE vs uncompressed: {report['mean_mse']:.3f} (mean over frames)",
        f"  RTL ({args.backend}) frames identical to golden: {'yes' if not mismatches else 'NO ' + str(mismatches)}",
        f"  cycles per frame: {report['cycles_per_frame']:.0f} for "
        f"{np.mean([f['requests'] for f in per_frame]):.0f} texel requests (latency {per_frame[0].get('latency', 0)})",
        f"  wrote {args.out_dir}/topspin_*.png and {args.out_dir}/report.json in {report['total_seconds']:.1f} s",
    ]
    emit(report, args.json, "\n".join(lines))
    if mismatches:
        raise CliError(f"RTL frames {mismatches} differ from the golden frames")
    return 0


def add_parser(sub) -> None:
    d = sub.add_parser("demo", help="the main job on embedded defaults (offline)")
    d.add_argument("--out-dir", default="vqtex-demo")
    d.add_argument("--frames", default="0:3")
    d.add_argument("--backend", choices=["cxxrtl", "verilator", "pysim", "golden"], default="cxxrtl")
    d.add_argument("--json", action="store_true")
    d.set_defaults(func=cmd_demo)
