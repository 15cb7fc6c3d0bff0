"""``vqtex bench render``: render time and RTL cycles per frame for both built-in scenes.

For each scene (topspin, town) and sampling mode (point, trilinear): the golden renderer's time per
frame from the uncompressed reference textures and from the compressed texture set (golden.fetch),
and the texel-fetch unit's cycles per frame on the compiled RTL (cxxrtl) for the same request stream,
beside the exact cycle model's count (they must agree).
"""

from __future__ import annotations

import json

import numpy as np

__all__ = ["run"]


def run(json_out: bool = False, frames: int = 3, backend: str = "cxxrtl") -> list[dict]:
    from vqtex.golden.render.bench import bench_scene
    from vqtex.golden.render.frame import frame_requests
    from vqtex.golden.render.scene import BUILTIN_SCENES, build_texture_set, load_scene
    from vqtex.sim.backends.interface import simulate
    from vqtex.golden.render.pyramid import VQSource
    rows = []
    for name in BUILTIN_SCENES:
        scene = load_scene(name)
        ref = scene.reference_source()
        src = VQSource(build_texture_set(scene))
        for mode in ("point", "trilinear"):
            plain = bench_scene(name, mode, frames, ref)
            comp = bench_scene(name, mode, frames, src)
            reqs, _ = frame_requests(scene, 0, src, mode)
            rtl = simulate(src.ts, reqs, backend=backend)
            model = simulate(src.ts, reqs, backend="golden")
            rows.append({
                "scene": name, "mode": mode, "size": plain["size"],
                "uncompressed_ms": round(plain["mean_s"] * 1e3, 1),
                "compressed_ms": round(comp["mean_s"] * 1e3, 1),
                "requests_per_frame": int(plain["requests_per_frame"]),
                "frame0_requests": int(len(reqs)), "frame0_cycles": int(rtl.cycles),
                "cycle_model_agrees": bool(model.cycles == rtl.cycles and
                                           np.array_equal(model.responses, rtl.responses)),
                "rtl_backend": backend,
            })
    if json_out:
        print(json.dumps({"render": rows}, sort_keys=True))
    else:
        print(f"{'scene':8} {'mode':9} {'size':8} {'uncompr ms':>10} {'VQ ms':>8} {'requests':>10} "
              f"{'cycles':>10} {'model':>6}   (cycles: frame 0 on {backend})")
        for r in rows:
            print(f"{r['scene']:8} {r['mode']:9} {r['size'][0]}x{r['size'][1]:<4} {r['uncompressed_ms']:10.1f} "
                  f"{r['compressed_ms']:8.1f} {r['frame0_requests']:10,} {r['frame0_cycles']:10,} "
                  f"{'same' if r['cycle_model_agrees'] else 'DIFF':>6}")
    return rows


if __name__ == "__main__":
    run()
