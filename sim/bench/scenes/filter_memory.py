"""The texture filter through the memory system on a built-in scene's frames (issue 25, item 8;
docs/memory.md): pixels per clock of :class:`hw.memory.filter.CachedTextureFilter` (a cache per
lane, one AXI master) against the on-chip filter's on the same pixels, memory bytes per pixel, hit
rates and where the stall cycles went.

``python -m vqtex.sim.bench.scenes.filter_memory [--scene topspin] [--frames 0] [--modes bilinear]
[--lanes 4] [--sizes 4,16] [--prefetch 16,128] [--latency 100] [--dram] [--json]``

The cycles are the golden cycle model's (:func:`golden.memory.filter.run_pixels`: exact, the RTL
matches it cycle for cycle on pysim and CXXRTL with ``o.ready`` high); no RTL runs here (the
compiled RTL's caches are flip-flops, so caches of several KB per lane are not a build to make per
row). The on-chip filter's cycles are ``groups + 24`` (docs/filter.md): with 4 lanes 1.0 bilinear
pixel per clock, 0.5 trilinear. Each lane's index and raw caches have the size in the row (32-byte
lines, 4 ways; 16-byte bus, a fixed memory of ``--latency`` cycles and 16 bytes per clock, or the
DDR3 part with ``--dram``). "shared B/px" is what one index and one raw cache of the row's size
would read for the same texels in the same order (numpy classification only: what banking by lane
costs in bytes).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

__all__ = ["filter_memory", "main"]


def frame_pixels(scene, ts, frame: int, mode: str):
    """The filter's per-pixel inputs of one frame (what ``vqtex render --filter-in-rtl`` gives the
    filter) and their fractional bits."""
    from vqtex.golden.render import plan_frame
    from vqtex.golden.render.pyramid import VQSource
    sampler = plan_frame(scene, frame, VQSource(ts), mode)
    sampler.requests(sampler.fragments)
    return sampler.filter_inputs(sampler.fragments, sampler.frac), sampler.frac


def shared_bytes(ts, pixels, config, lanes: int, frac: int) -> int:
    """Memory bytes one index and one raw cache (``config``'s) would read for the lanes' texels in
    group order, lane by lane (numpy: the caches' classification)."""
    from vqtex.golden.memory.filter import lane_requests
    from vqtex.golden.memory.timing import plan
    req, _ = lane_requests(ts, pixels, lanes, frac)
    p = plan(ts, req.transpose(1, 0, 2).reshape(-1, 4), config)
    per = np.bincount(p.cache, minlength=2)
    return int(per[0]) * config.index_cache.line + int(per[1]) * config.raw_cache.line


def filter_memory(scene_name="topspin", frames=(0,), modes=("bilinear",), lanes: int = 4, sizes=(4, 16),
                  prefetch=(16,), latency: int = 100, dram: bool = False, line: int = 32, ways: int = 4) -> list:
    from vqtex.golden.memory.cache import CacheShape
    from vqtex.golden.memory.filter import run_pixels
    from vqtex.hw.texel_fetch import LATENCY as FETCH_LATENCY
    from vqtex.golden.memory.system import MemoryConfig
    from vqtex.golden.render.scene import build_texture_set, load_scene
    scene = load_scene(scene_name)
    ts = build_texture_set(scene)
    rows = []
    for frame in frames:
        for mode in modes:
            px, frac = frame_pixels(scene, ts, frame, mode)
            for kb in sizes:
                shape = CacheShape(kb * 1024, line, ways)
                for q in prefetch:
                    cfg = MemoryConfig(index_cache=shape, raw_cache=shape, prefetch=q, latency=latency,
                                       kind="dram" if dram else "fixed")
                    t0 = time.perf_counter()
                    r = run_pixels(ts, px, cfg, lanes, frac, latency=FETCH_LATENCY)
                    seconds = time.perf_counter() - t0
                    on_chip = r["on_chip_cycles"]
                    m = r["pixels"]
                    rows.append({
                        "scene": scene_name, "frame": frame, "mode": mode, "lanes": lanes, "cache_kb": kb,
                        "prefetch": q, "memory": cfg.make_memory().describe(), "pixels": m,
                        "groups": r["groups"], "cycles": r["cycles"], "pixels_per_clock": r["pixels_per_clock"],
                        "on_chip_cycles": on_chip, "on_chip_pixels_per_clock": m / on_chip if on_chip else 0.0,
                        "of_on_chip": on_chip / r["cycles"] if r["cycles"] else 0.0,
                        "bytes_per_pixel": r["bytes_per_pixel"],
                        "shared_bytes_per_pixel": shared_bytes(ts, px, cfg, lanes, frac) / m if m else 0.0,
                        "hit_rate": r["hit_rate"], "bursts": r["bursts"],
                        "stall_cycles": {k: int(v) for k, v in r["stall_cycles"].items()},
                        "model_seconds": seconds})
    return rows


def _pct(v):
    return "-" if v is None else f"{100 * v:.2f}%"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m vqtex.sim.bench.scenes.filter_memory", description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default="topspin")
    ap.add_argument("--frames", default="0")
    ap.add_argument("--modes", default="bilinear")
    ap.add_argument("--lanes", type=int, default=4)
    ap.add_argument("--sizes", default="4,16", help="KB per lane and cache")
    ap.add_argument("--prefetch", default="16")
    ap.add_argument("--latency", type=int, default=100)
    ap.add_argument("--dram", action="store_true")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    try:
        ints = lambda s: tuple(int(x) for x in s.split(","))          # noqa: E731
        rows = filter_memory(a.scene, ints(a.frames), tuple(a.modes.split(",")), a.lanes, ints(a.sizes),
                             ints(a.prefetch), a.latency, a.dram)
    except (ValueError, KeyError, FileNotFoundError) as e:
        print(f"error: {e}")
        return 2
    if a.json:
        print(json.dumps(rows, indent=1))
        return 0
    print("| frame | mode | lanes | cache/lane | FIFO | pixels | cycles | px/clock | on-chip px/clock | of on-chip "
          "| B/px | shared B/px | index hit | raw hit | stalls (miss, bw, join, fifo, victim, arbiter) | model s |")
    print("|" + "---|" * 16)
    for r in rows:
        s = r["stall_cycles"]
        print(f"| {r['frame']} | {r['mode']} | {r['lanes']} | {r['cache_kb']} KB | {r['prefetch']} | {r['pixels']} "
              f"| {r['cycles']} | {r['pixels_per_clock']:.3f} | {r['on_chip_pixels_per_clock']:.3f} "
              f"| {r['of_on_chip']:.3f} | {r['bytes_per_pixel']:.3f} | {r['shared_bytes_per_pixel']:.3f} "
              f"| {_pct(r['hit_rate']['index'])} | {_pct(r['hit_rate']['raw'])} "
              f"| {s['miss']}, {s['bandwidth']}, {s['join']}, {s['fifo_full']}, {s['victim']}, {s['arbiter']} "
              f"| {r['model_seconds']:.1f} |")
    print(f"scene {rows[0]['scene'] if rows else a.scene}; memory: {rows[0]['memory'] if rows else ''}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
