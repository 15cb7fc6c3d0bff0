"""The cached unit on a built-in scene's frames: hit rates, memory bytes per texel, cycles against
the zero-latency figure, for the blocking and the prefetching cache, over cache sizes, with a fixed
latency memory and the DDR3 part; and how fast the golden cycle model runs (docs/memory.md).

``python -m vqtex.sim.bench.scenes.memory [--scene topspin] [--frame 0] [--latency 100]
[--sizes 1,4,16,64] [--prefetch 16] [--json]``.

Golden only (the cycle model of golden.memory.timing with this pipeline's LATENCY); no RTL runs.
"""

from __future__ import annotations

import argparse
import json
import time

__all__ = ["scene_memory", "main"]


def scene_memory(scene_name: str = "topspin", frame: int = 0, latency: int = 100, sizes=(1, 4, 16, 64),
                 prefetch: int = 16, line: int = 32, ways: int = 4) -> dict:
    from vqtex.golden.memory.cache import CacheShape
    from vqtex.golden.memory.system import MemoryConfig
    from vqtex.golden.render.frame import frame_requests
    from vqtex.golden.render.scene import build_texture_set, load_scene
    from vqtex.sim.backends.cycle_model import run_cached

    scene = load_scene(scene_name)
    t0 = time.perf_counter()
    ts = build_texture_set(scene)
    encode_s = time.perf_counter() - t0
    req, _ = frame_requests(scene, frame, ts, "trilinear")
    rows = []
    for kb in sizes:
        shape = CacheShape(kb * 1024, line, ways)
        for kind, q in (("fixed", 1), ("fixed", prefetch), ("dram", prefetch)):
            cfg = MemoryConfig(index_cache=shape, raw_cache=shape, prefetch=q, kind=kind, latency=latency)
            t0 = time.perf_counter()
            out = run_cached(ts, req, cfg)
            dt = time.perf_counter() - t0
            rows.append({
                "cache_kb": kb, "memory": kind, "prefetch": q, "cycles": out["cycles"],
                "zero_latency_cycles": out["zero_latency_cycles"], "of_zero_latency": out["of_zero_latency"],
                "hit_rate": out["hit_rate"], "bytes_per_texel": out["bytes_per_texel"],
                "stall_cycles": out["stall_cycles"], "model_seconds": dt,
                "requests_per_second": 2 * len(req) / dt,      # the cached run and the zero-latency run
            })
    return {"scene": scene_name, "frame": frame, "requests": int(len(req)), "latency": latency,
            "line": line, "ways": ways, "encode_seconds": encode_s, "rows": rows}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default="topspin")
    ap.add_argument("--frame", type=int, default=0)
    ap.add_argument("--latency", type=int, default=100)
    ap.add_argument("--sizes", default="1,4,16,64", help="cache sizes in KB, comma-separated")
    ap.add_argument("--prefetch", type=int, default=16)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    r = scene_memory(a.scene, a.frame, a.latency, tuple(int(s) for s in a.sizes.split(",")), a.prefetch)
    if a.json:
        print(json.dumps(r, indent=1))
        return
    print(f"{r['scene']} frame {r['frame']}: {r['requests']} requests (trilinear), memory latency {r['latency']} "
          f"cycles (fixed) or DDR3-1600 at 200 MHz; {r['line']}-byte lines, {r['ways']} ways")
    print(f"{'cache':>6} {'memory':>6} {'FIFO':>4} {'index hit':>9} {'raw hit':>7} {'B/texel':>7} {'cycles':>9} "
          f"{'of 0-lat':>8} {'miss':>8} {'bandw':>7} {'model req/s':>11}")
    for x in r["rows"]:
        hr = x["hit_rate"]
        fmt = lambda v: "-" if v is None else f"{100 * v:.1f}%"
        print(f"{x['cache_kb']:>4}KB {x['memory']:>6} {x['prefetch']:>4} {fmt(hr['index']):>9} {fmt(hr['raw']):>7} "
              f"{x['bytes_per_texel']:>7.3f} {x['cycles']:>9} {x['of_zero_latency']:>8.3f} "
              f"{x['stall_cycles']['miss']:>8} {x['stall_cycles']['bandwidth']:>7} {x['requests_per_second']:>11.0f}")


if __name__ == "__main__":
    main()
