"""``python -m vqtex.sim.bench.simulators.cached [--caches I:R ...] [--backends B ...] [--json]``: the
cached unit (textures in external memory, docs/memory.md) on the compiled backends.

For each cache configuration (index cache and raw cache bytes; 32-byte lines, 4 ways, a 16-entry
FIFO, 16-byte bus; the memory: 100 cycles of latency, 16 bytes per clock) and each backend, in a
fresh temporary build cache: the first build's time (and its steps: Yosys, the C++ compiler, or
Verilator and the link), the size of the generated C++ (CXXRTL's ``design.cc``; Verilator's
``obj/*.cpp``), then topspin's frame 0 (trilinear, the sparse stream ``vqtex render`` issues: about
9e5 requests) through the library, best of two: seconds and simulated cycles per second. The
golden cycle model runs the same frame once per configuration; every backend's cycles must equal
its cycles (the run stops with an error otherwise) and its responses ``golden.fetch``'s.
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import tempfile
import time

import numpy as np

__all__ = ["run"]

#: Default configurations: the command line's default caches (16 KB index, 4 KB raw) and 4 + 1 KB.
CACHES = ((16384, 4096), (4096, 1024))


def _cpp_bytes(build, backend: str) -> int:
    folder = os.path.dirname(build.library)
    files = ([os.path.join(folder, "design.cc")] if backend == "cxxrtl"
             else glob.glob(os.path.join(folder, "obj", "*.cpp")))
    return sum(os.path.getsize(f) for f in files if os.path.exists(f))


def run(caches=CACHES, backends=("cxxrtl", "verilator"), json_out: bool = False) -> dict:
    from vqtex.golden.fetch import fetch
    from vqtex.golden.memory.cache import CacheShape
    from vqtex.golden.memory.system import MemoryConfig
    from vqtex.golden.render.frame import frame_requests
    from vqtex.golden.render.scene import build_texture_set, load_scene
    from vqtex.sim.backends.cycle_model import run_cached
    from vqtex.sim.backends.memory import build_cached, run_compiled
    from vqtex.sim.backends.toolchain import using_cache
    scene = load_scene("topspin")
    ts = build_texture_set(scene)
    req, _ = frame_requests(scene, 0, ts, "trilinear")
    want = fetch(ts, *req.T)
    rows = []
    for index_bytes, raw_bytes in caches:
        cfg = MemoryConfig(index_cache=CacheShape(index_bytes, 32, 4), raw_cache=CacheShape(raw_bytes, 32, 4))
        t = time.perf_counter()
        model = run_cached(ts, req, cfg, zero_latency=False)
        golden_s = time.perf_counter() - t
        rows.append({"caches": [index_bytes, raw_bytes], "backend": "golden cycle model",
                     "cycles": int(model["cycles"]), "run_s": round(golden_s, 2),
                     "requests_per_s": round(len(req) / golden_s)})
        for backend in backends:
            with tempfile.TemporaryDirectory(prefix="vqtex-bench-cached-") as folder, using_cache(folder):
                t = time.perf_counter()
                build = build_cached(ts, cfg, backend)
                build_s = time.perf_counter() - t
                cpp = _cpp_bytes(build, backend)
                best = float("inf")
                for _ in range(2):
                    t = time.perf_counter()
                    got = run_compiled(ts, req, cfg, backend, 0.0, 0)
                    best = min(best, time.perf_counter() - t)
                if got["cycles"] != model["cycles"] or not np.array_equal(got["responses"], want):
                    raise RuntimeError(f"{backend} at caches {index_bytes}+{raw_bytes}: {got['cycles']} cycles, "
                                       f"golden {model['cycles']} (or the responses differ)")
                steps = {k: round(v, 1) for k, v in build.steps.items() if v >= 0.05}
                rows.append({"caches": [index_bytes, raw_bytes], "backend": backend, "cycles": int(got["cycles"]),
                             "build_s": round(build_s, 1), "build_steps_s": steps, "cpp_bytes": cpp,
                             "run_s": round(best, 2), "cycles_per_s": round(got["cycles"] / best)})
    out = {"frame": "topspin 0, trilinear, sparse stream", "requests": int(len(req)), "rows": rows}
    if json_out:
        print(json.dumps(out))
    else:
        print(f"{out['frame']}: {out['requests']:,} requests; memory 100 cycles, 16 B/clock; 32-byte lines, 4 ways, "
              f"{MemoryConfig().prefetch}-entry FIFO")
        print(f"{'caches (index+raw)':>19} {'backend':>19} {'cycles':>9} {'build s':>8} {'C++ bytes':>10} "
              f"{'run s':>6} {'rate':>12}")
        for r in rows:
            rate = (f"{r['cycles_per_s']:.2e} cyc/s" if "cycles_per_s" in r else f"{r['requests_per_s']:.2e} req/s")
            print(f"{r['caches'][0] // 1024:>8} KB + {r['caches'][1] // 1024:>2} KB {r['backend']:>19} {r['cycles']:>9} "
                  f"{r.get('build_s', ''):>8} {r.get('cpp_bytes', ''):>10} {r['run_s']:>6} {rate:>12}")
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m vqtex.sim.bench.simulators.cached", description=__doc__.split("\n\n")[0])
    p.add_argument("--caches", nargs="+", default=[f"{i}:{r}" for i, r in CACHES], metavar="INDEX:RAW",
                   help="cache configurations, bytes (default: %(default)s)")
    p.add_argument("--backends", nargs="+", default=["cxxrtl", "verilator"], choices=["cxxrtl", "verilator"])
    p.add_argument("--json", action="store_true")
    a = p.parse_args(argv)
    try:
        caches = [tuple(int(v) for v in c.split(":")) for c in a.caches]
        if any(len(c) != 2 for c in caches):
            raise ValueError
    except ValueError:
        p.error(f"--caches takes INDEX:RAW byte counts, not {' '.join(a.caches)}")
    run(caches, a.backends, a.json)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
