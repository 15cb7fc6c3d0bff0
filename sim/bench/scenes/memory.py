"""The cached unit on a built-in scene's frame: the same frame from the VQ texture set and from the
same textures uncompressed (every level raw RGBA8888, the raw path), through the same caches and
memory: hit rates, memory bytes per textured pixel and per texel, cycles per pixel against the
zero-latency figure, over cache sizes; blocking and prefetching, a fixed-latency memory and the DDR3
part (docs/memory.md). Also how fast the golden cycle model runs.

``python -m vqtex.sim.bench.scenes.memory [--scene topspin] [--frame 0] [--latency 100]
[--sizes 1,4,16,64] [--prefetch 16] [--no-uncompressed] [--no-dram] [--json]``.

``--claim`` prints the paper's claim instead (issue 25, item 7; docs/memory.md): for each scene of
``--scenes`` (default topspin,town) and each cache size of ``--sizes`` (default 1 to 64 KB in powers
of two), the VQ set against the same textures uncompressed through the same caches and memory
(prefetching, ``--prefetch`` entries; the fixed memory of ``--latency`` cycles, or ``--memory-model
dram``): memory bytes per textured pixel, cycles per textured pixel, hit rates, texels per clock
against zero latency, over ``--frame`` or the sum of ``--frames 0,10,20`` (each frame its own stream);
``--plot PATH`` draws them.
The hit rates and bytes are the caches' classification (numpy, :func:`golden.memory.timing.plan`);
the cycles are the golden cycle model's loop over requests, the slow part (about 1e5 requests per
second on a free core, a few times less on a shared one), run once per row; the zero-latency
cycles do not depend on the cache, so they are run once per set. ``--no-cycles`` skips the loop.

Golden only (the cycle model of golden.memory.timing with this pipeline's LATENCY); no RTL runs.
Both caches have the size in the row; 32-byte lines, 4 ways, 16-byte bus.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

__all__ = ["scene_memory", "uncompressed_set", "claim", "plot_claim", "main"]


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
                 prefetch: int = 128, line: int = 32, ways: int = 4, uncompressed: bool = True,
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


def claim(scene_name="topspin", frame=0, sizes=(1, 2, 4, 8, 16, 32, 64), latency: int = 100,
          prefetch: int = 128, line: int = 32, ways: int = 4, cycles: bool = True, progress=None,
          kind: str = "fixed") -> dict:
    """The paper's claim on one scene's frames (see the module docstring): rows of (cache_kb,
    textures "vq" or "uncompressed", hit_rate per cache, bytes_per_pixel, bytes_per_texel and, with
    ``cycles``, cycles_per_pixel and of_zero_latency).

    ``frame`` is one frame number or a sequence of them: each frame is its own stream (the caches
    empty at its start, as a frame of :func:`scene_memory`), and a row sums the frames' references,
    hits, bytes, pixels and cycles. ``kind`` is the memory model (``"fixed"``: ``latency`` cycles and
    the bus's bandwidth; ``"dram"``: the DDR3-1600 part of :class:`golden.memory.system.MemoryConfig`,
    where ``latency`` is not used)."""
    from vqtex.golden.memory.cache import CacheShape
    from vqtex.golden.memory.system import MemoryConfig
    from vqtex.golden.memory.timing import plan, run, run_requests
    from vqtex.golden.render.frame import frame_requests
    from vqtex.golden.render.scene import build_texture_set, load_scene
    from vqtex.hw.texel_fetch import LATENCY
    from vqtex.sim.streams import ready_pattern

    frames = (frame,) if isinstance(frame, (int, np.integer)) else tuple(frame)
    scene = load_scene(scene_name) if isinstance(scene_name, str) else scene_name     # a name, or a Scene
    scene_name = scene_name if isinstance(scene_name, str) else str(scene.path)
    images = [img for img, _ in scene.load_textures()]
    sets = {"vq": build_texture_set(scene, images), "uncompressed": uncompressed_set(scene, images)}
    streams = [frame_requests(scene, f, sets["vq"], "trilinear") for f in frames]
    reqs = [req for req, _ in streams]
    pixels = sum(len(sampler.fragments) for _, sampler in streams)
    n = sum(len(req) for req in reqs)

    def always(m):
        return ready_pattern(0, 0.0, m)
    zero, seconds = {}, 0.0
    rows = []
    for name, ts in sets.items():
        for kb in sizes:
            shape = CacheShape(kb * 1024, line, ways)
            cfg = MemoryConfig(index_cache=shape, raw_cache=shape, prefetch=prefetch, latency=latency, kind=kind)
            plans = [plan(ts, req, cfg) for req in reqs]
            misses = sum(np.bincount(p.cache, minlength=2) for p in plans)
            refs = [sum(p.references[c] for p in plans) for c in range(2)]
            hits = [sum(p.hits[c] for p in plans) for c in range(2)]
            total = int(misses[0]) * line + int(misses[1]) * line
            row = {"cache_kb": kb, "textures": name, "references": {"index": refs[0], "raw": refs[1]},
                   "hit_rate": {k: (hits[c] / refs[c] if refs[c] else None) for c, k in enumerate(("index", "raw"))},
                   "bytes_per_pixel": total / pixels, "bytes_per_texel": total / n}
            if cycles:
                if name not in zero:
                    zero[name] = sum(run_requests(ts, req, cfg, LATENCY, always, ideal=True)["cycles"] for req in reqs)
                t0 = time.perf_counter()
                outs = [run(p, cfg, LATENCY, always) for p in plans]       # the plans above, not made again
                seconds += time.perf_counter() - t0
                assert sum(sum(out["memory_bytes"].values()) for out in outs) == total
                c = sum(out["cycles"] for out in outs)
                row.update(cycles=c, cycles_per_pixel=c / pixels, zero_latency_cycles=zero[name],
                           of_zero_latency=zero[name] / c)
            rows.append(row)
            if progress:
                progress(row)
    return {"scene": scene_name, "frame": frames[0] if len(frames) == 1 else list(frames), "requests": int(n),
            "pixels": int(pixels), "latency": latency if kind == "fixed" else None, "memory": kind,
            "prefetch": prefetch, "line": line, "ways": ways, "rows": rows,
            "model_requests_per_second": (len(rows) * n / seconds) if seconds else None}


def _memory_words(r: dict) -> str:
    """The memory of a claim result in words."""
    if r.get("memory", "fixed") == "fixed":
        return f"fixed memory, latency {r['latency']} cycles"
    return "DDR3-1600 (MT41K256M16-125) at 200 MHz"


def _frames_words(r: dict) -> str:
    f = r["frame"]
    return f"frame {f}" if isinstance(f, int) else f"frames {','.join(map(str, f))}"


def plot_claim(results: list, path: str) -> None:
    """Bytes per pixel, cycles per pixel and hit rate against cache size, VQ and uncompressed, one
    line per scene and set (matplotlib; ``path`` PNG)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    with_cycles = all("cycles_per_pixel" in row for r in results for row in r["rows"])
    panels = [("bytes_per_pixel", "memory bytes per textured pixel", True)]
    if with_cycles:
        panels.append(("cycles_per_pixel", "cycles per textured pixel", False))
    panels.append(("hit", "hit rate (index cache for VQ, raw for uncompressed)", False))
    fig, axes = plt.subplots(1, len(panels), figsize=(5 * len(panels), 4))
    for ax, (key, label, log) in zip(axes, panels):
        for r in results:
            for name, style in (("vq", "-o"), ("uncompressed", "--s")):
                rows = [x for x in r["rows"] if x["textures"] == name]
                kb = [x["cache_kb"] for x in rows]
                if key == "hit":
                    y = [x["hit_rate"]["index" if name == "vq" else "raw"] for x in rows]
                else:
                    y = [x[key] for x in rows]
                ax.plot(kb, y, style, label=f"{r['scene']} {'VQ' if name == 'vq' else 'uncompressed'}")
        ax.set_xscale("log", base=2)
        if log:
            ax.set_yscale("log")
        ax.set_xlabel("cache size per cache (KB)")
        ax.set_title(label, fontsize=10)
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=8)
    r0 = results[0]
    fig.suptitle(f"{_frames_words(r0)}, trilinear; {r0['line']}-byte lines, {r0['ways']} ways; {_memory_words(r0)}, "
                 f"{r0['prefetch']}-entry prefetch FIFO", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _print_claim(r: dict) -> None:
    print(f"{r['scene']} {_frames_words(r)}: {r['requests']} requests (trilinear), {r['pixels']} textured pixels; "
          f"{_memory_words(r)}, {r['prefetch']}-entry FIFO, {r['line']}-byte lines, "
          f"{r['ways']} ways")
    print(f"{'cache':>6} {'textures':>12} {'index hit':>9} {'raw hit':>7} {'B/pixel':>8} {'VQ gain':>7} "
          f"{'cyc/pixel':>9} {'of 0-lat':>8}")
    vq = {x["cache_kb"]: x["bytes_per_pixel"] for x in r["rows"] if x["textures"] == "vq"}
    for x in r["rows"]:
        hr = x["hit_rate"]

        def pct(v):
            return "-" if v is None else f"{100 * v:.2f}%"
        gain = f"{x['bytes_per_pixel'] / vq[x['cache_kb']]:.1f}x" if x["textures"] == "uncompressed" and vq[x["cache_kb"]] else ""
        cyc = f"{x['cycles_per_pixel']:>9.3f} {x['of_zero_latency']:>8.3f}" if "cycles_per_pixel" in x else ""
        print(f"{x['cache_kb']:>4}KB {x['textures']:>12} {pct(hr['index']):>9} {pct(hr['raw']):>7} "
              f"{x['bytes_per_pixel']:>8.3f} {gain:>7} {cyc}")
    if r["model_requests_per_second"]:
        print(f"golden cycle model: {r['model_requests_per_second']:.0f} requests per second")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default="topspin")
    ap.add_argument("--frame", type=int, default=0)
    ap.add_argument("--frames", default=None, help="--claim: frames, comma-separated (each its own stream, summed)")
    ap.add_argument("--memory-model", default="fixed", choices=("fixed", "dram"),
                    help="--claim: the fixed-latency memory or the DDR3-1600 part")
    ap.add_argument("--latency", type=int, default=100)
    ap.add_argument("--sizes", default="1,4,16,64", help="cache sizes in KB, comma-separated")
    ap.add_argument("--prefetch", type=int, default=128)
    ap.add_argument("--no-uncompressed", action="store_true", help="the VQ set only")
    ap.add_argument("--no-dram", action="store_true", help="the fixed-latency memory only")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--claim", action="store_true", help="the paper's claim table (VQ against uncompressed)")
    ap.add_argument("--scenes", default="topspin,town", help="--claim: scenes, comma-separated")
    ap.add_argument("--no-cycles", action="store_true", help="--claim: bytes and hit rates only (no cycle loop)")
    ap.add_argument("--plot", default=None, help="--claim: draw the table into this PNG")
    a = ap.parse_args(argv)
    if a.claim:
        sizes = (1, 2, 4, 8, 16, 32, 64) if a.sizes == "1,4,16,64" else tuple(int(s) for s in a.sizes.split(","))
        frames = a.frame if a.frames is None else tuple(int(f) for f in a.frames.split(","))
        results = [claim(name, frames, sizes, a.latency, a.prefetch, cycles=not a.no_cycles, kind=a.memory_model)
                   for name in a.scenes.split(",")]
        if a.plot:
            plot_claim(results, a.plot)
        if a.json:
            print(json.dumps(results, indent=1))
            return
        for r in results:
            _print_claim(r)
        return
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
