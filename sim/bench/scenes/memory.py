"""The cached unit on a built-in scene's frame: the same frame from the VQ texture set and from the
same textures uncompressed (every level raw RGBA8888, the raw path), through the same caches and
memory: hit rates, memory bytes per textured pixel and per texel, cycles per pixel against the
zero-latency figure, over cache sizes; blocking and prefetching, a fixed-latency memory and the DDR3
part (docs/memory.md). Also how fast the golden cycle model runs.

``python -m vqtex.sim.bench.scenes.memory [--scene topspin] [--frame 0] [--latency 100]
[--sizes 1,4,16,64] [--prefetch 16] [--no-uncompressed] [--no-dram] [--json]``.

Golden only (the cycle model of golden.memory.timing with this pipeline's LATENCY); no RTL runs.
Both caches have the size in the row; 32-byte lines, 4 ways, 16-byte bus.
"""

from __future__ import annotations

import argparse
import json
import time

__all__ = ["scene_memory", "uncompressed_set", "main"]


def uncompressed_set(scene, images=None):
    """The scene's textures with every level stored raw (RGBA8888 words), texture ids and level
    shapes as :func:`golden.render.scene.build_texture_set` gives them (mipmaps as the scene says)."""
    from vqtex.golden.encode import encode
    from vqtex.golden.format import TextureSet
    if images is None:
        images = [img for img, _ in scene.load_textures()]
    sets = []
    for g in dict.fromkeys(scene.groups):
        members = [k for k, t in enumerate(scene.textures) if t.group == g]
        enc = scene.textures[members[0]].encoding
        sets.append(encode([images[k] for k in members], mipmaps=enc["mipmaps"], raw_below=1 << 13,
                           codebook_size=2, names=[scene.textures[k].name for k in members]))
    return TextureSet.combine(sets)


def scene_memory(scene_name="topspin", frame: int = 0, latency: int = 100, sizes=(1, 4, 16, 64),
                 prefetch: int = 16, line: int = 32, ways: int = 4, uncompressed: bool = True,
                 dram: bool = True) -> dict:
    from vqtex.golden.memory.cache import CacheShape
    from vqtex.golden.memory.system import MemoryConfig
    from vqtex.golden.render.frame import frame_requests
    from vqtex.golden.render.scene import build_texture_set, load_scene
    from vqtex.sim.backends.cycle_model import run_cached

    scene = load_scene(scene_name) if isinstance(scene_name, str) else scene_name     # a name, or a Scene
    scene_name = scene_name if isinstance(scene_name, str) else str(scene.path)
    images = [img for img, _ in scene.load_textures()]
    t0 = time.perf_counter()
    sets = {"vq": build_texture_set(scene, images)}
    encode_s = time.perf_counter() - t0
    if uncompressed:
        sets["uncompressed"] = uncompressed_set(scene, images)
        for t in range(sets["vq"].n_textures):
            assert sets["vq"].level_shapes(t) == sets["uncompressed"].level_shapes(t)
    req, sampler = frame_requests(scene, frame, sets["vq"], "trilinear")
    pixels = len(sampler.fragments)
    runs = [(name, "fixed", 1) for name in sets] + [(name, "fixed", prefetch) for name in sets]
    if dram:
        runs += [(name, "dram", prefetch) for name in sets]
    rows = []
    for kb in sizes:
        shape = CacheShape(kb * 1024, line, ways)
        for name, kind, q in runs:
            cfg = MemoryConfig(index_cache=shape, raw_cache=shape, prefetch=q, kind=kind, latency=latency)
            t0 = time.perf_counter()
            out = run_cached(sets[name], req, cfg)
            dt = time.perf_counter() - t0
            total = sum(out["memory_bytes"].values())
            rows.append({
                "cache_kb": kb, "textures": name, "memory": kind, "prefetch": q, "cycles": out["cycles"],
                "zero_latency_cycles": out["zero_latency_cycles"], "of_zero_latency": out["of_zero_latency"],
                "hit_rate": out["hit_rate"], "bytes_per_texel": out["bytes_per_texel"],
                "bytes_per_pixel": total / pixels, "cycles_per_pixel": out["cycles"] / pixels,
                "stall_cycles": out["stall_cycles"], "model_seconds": dt,
                "requests_per_second": 2 * len(req) / dt,      # the cached run and the zero-latency run
            })
    return {"scene": scene_name, "frame": frame, "requests": int(len(req)), "pixels": int(pixels),
            "latency": latency, "line": line, "ways": ways, "encode_seconds": encode_s, "rows": rows}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default="topspin")
    ap.add_argument("--frame", type=int, default=0)
    ap.add_argument("--latency", type=int, default=100)
    ap.add_argument("--sizes", default="1,4,16,64", help="cache sizes in KB, comma-separated")
    ap.add_argument("--prefetch", type=int, default=16)
    ap.add_argument("--no-uncompressed", action="store_true", help="the VQ set only")
    ap.add_argument("--no-dram", action="store_true", help="the fixed-latency memory only")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    r = scene_memory(a.scene, a.frame, a.latency, tuple(int(s) for s in a.sizes.split(",")), a.prefetch,
                     uncompressed=not a.no_uncompressed, dram=not a.no_dram)
    if a.json:
        print(json.dumps(r, indent=1))
        return
    print(f"{r['scene']} frame {r['frame']}: {r['requests']} requests (trilinear), {r['pixels']} textured pixels; "
          f"memory latency {r['latency']} cycles (fixed) or DDR3-1600 at 200 MHz; {r['line']}-byte lines, "
          f"{r['ways']} ways")
    print(f"{'cache':>6} {'textures':>12} {'memory':>6} {'FIFO':>4} {'index hit':>9} {'raw hit':>7} {'B/texel':>7} "
          f"{'B/pixel':>7} {'cyc/pixel':>9} {'of 0-lat':>8} {'miss':>8} {'bandw':>7} {'model req/s':>11}")
    for x in r["rows"]:
        hr = x["hit_rate"]

        def pct(v):
            return "-" if v is None else f"{100 * v:.1f}%"
        print(f"{x['cache_kb']:>4}KB {x['textures']:>12} {x['memory']:>6} {x['prefetch']:>4} {pct(hr['index']):>9} "
              f"{pct(hr['raw']):>7} {x['bytes_per_texel']:>7.3f} {x['bytes_per_pixel']:>7.3f} "
              f"{x['cycles_per_pixel']:>9.3f} {x['of_zero_latency']:>8.3f} {x['stall_cycles']['miss']:>8} "
              f"{x['stall_cycles']['bandwidth']:>7} {x['requests_per_second']:>11.0f}")


if __name__ == "__main__":
    main()
