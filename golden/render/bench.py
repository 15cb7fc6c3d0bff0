"""Renderer benchmark: time per frame and texel requests per frame of the built-in scenes.

    python -m golden.render.bench [--json] [--frames N]

renders N frames (default 5, spread over the animation) of ``topspin`` and ``town`` with the
golden reference source, in point and trilinear mode, and prints for each: the mean and best wall
time per frame (everything from geometry to the resolved frame, texture loading excluded), the time
split into rasterization / requests / fetch / resolve, and the requests per frame.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from .frame import plan_frame
from .scene import BUILTIN_SCENES, load_scene

__all__ = ["run", "bench_scene"]


def bench_scene(name: str, mode: str, frames: int = 5, source=None) -> dict:
    scene = load_scene(name)
    if source is None:
        source = scene.reference_source()
    frame_nos = np.linspace(0, scene.frames - 1, frames).round().astype(int).tolist()
    plan_frame(scene, frame_nos[0], source, mode)  # warm-up: builds the meshes once
    totals, parts, nreq, npix = [], {"raster": 0.0, "requests": 0.0, "fetch": 0.0, "resolve": 0.0}, [], []
    for f in frame_nos:
        t0 = time.perf_counter()
        sampler = plan_frame(scene, f, source, mode)
        t1 = time.perf_counter()
        reqs = sampler.requests(sampler.fragments)
        t2 = time.perf_counter()
        texels = source.fetch(reqs[:, 0], reqs[:, 1], reqs[:, 2], reqs[:, 3])
        t3 = time.perf_counter()
        sampler.resolve(texels)
        t4 = time.perf_counter()
        totals.append(t4 - t0)
        for k, dt in zip(parts, (t1 - t0, t2 - t1, t3 - t2, t4 - t3)):
            parts[k] += dt / len(frame_nos)
        nreq.append(len(reqs))
        npix.append(len(sampler.fragments))
    return {
        "scene": name, "mode": mode, "size": [scene.width, scene.height], "frames": frame_nos,
        "mean_s": float(np.mean(totals)), "best_s": float(np.min(totals)),
        "split_s": {k: float(v) for k, v in parts.items()},
        "requests_per_frame": float(np.mean(nreq)), "covered_pixels_per_frame": float(np.mean(npix)),
    }


def run(json_out: bool = False, frames: int = 5) -> list[dict]:
    """Benchmark both built-in scenes, point and trilinear; print a table (or one JSON object)."""
    results = []
    for name in BUILTIN_SCENES:
        scene = load_scene(name)
        source = scene.reference_source()
        for mode in ("point", "trilinear"):
            results.append(bench_scene(name, mode, frames, source))
    if json_out:
        print(json.dumps({"renderer": results}))
    else:
        print(f"{'scene':8} {'mode':9} {'size':8} {'mean ms':>8} {'best ms':>8} "
              f"{'raster':>7} {'reqs':>6} {'fetch':>6} {'resolve':>7} {'requests/frame':>15}")
        for r in results:
            s = r["split_s"]
            print(f"{r['scene']:8} {r['mode']:9} {r['size'][0]}x{r['size'][1]:<4} {r['mean_s'] * 1e3:8.1f} "
                  f"{r['best_s'] * 1e3:8.1f} {s['raster'] * 1e3:7.1f} {s['requests'] * 1e3:6.1f} "
                  f"{s['fetch'] * 1e3:6.1f} {s['resolve'] * 1e3:7.1f} {r['requests_per_frame']:15,.0f}")
    return results


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m golden.render.bench", description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--frames", type=int, default=5, help="frames per scene and mode (default 5)")
    args = ap.parse_args(argv)
    run(json_out=args.json, frames=max(1, args.frames))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
