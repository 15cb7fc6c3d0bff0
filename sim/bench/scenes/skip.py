"""``vqtex bench skip``: the sparse request stream against the fixed one, on the compiled RTL.

For each built-in scene (topspin, 50 frames; town, 60 frames) and every frame: the trilinear request
stream issued both ways (``fixed``: 8 requests per covered pixel; ``sparse``: no zero-weight request,
no repeat of a texel in one pixel's footprint, :mod:`vqtex.golden.render.sparse`), each run through
the texel-fetch unit on the compiled CXXRTL backend (one library, memories loaded once) and resolved
into the frame. The two frames must be identical, pixel for pixel (the benchmark fails otherwise).

Printed per scene: requests and RTL cycles per frame, both ways, and what the sparse stream saves;
the wall time of the simulations (``vq_run`` through ``run_batch``), both streams timed side by side
in one run, alternating which goes first, at the library's default threads and on one thread; and the
golden side's time to issue the requests and resolve the frame.
"""

from __future__ import annotations

import json
import time

import numpy as np

__all__ = ["run", "bench_scene"]


def _timed(fn):
    t = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t


def bench_scene(scene, frames=None, ts=None) -> dict:
    """The fixed and sparse streams of ``frames`` (default all) of ``scene`` (a Scene or a built-in
    name) on the CXXRTL backend; raises AssertionError if a frame differs between the two."""
    from vqtex.golden.render.frame import frame_requests
    from vqtex.golden.render.pyramid import VQSource
    from vqtex.golden.render.scene import build_texture_set, load_scene
    from vqtex.sim.backends.cxxrtl import open_cxxrtl, run_batch
    if isinstance(scene, str):
        scene = load_scene(scene)
    frames = list(range(scene.frames)) if frames is None else list(frames)
    ts = build_texture_set(scene) if ts is None else ts
    src = VQSource(ts)
    lib, info, _ = open_cxxrtl(ts)
    streams = ("fixed", "sparse")
    tot = {s: {"requests": 0, "cycles": 0, "sim_s": 0.0, "sim_1t_s": 0.0, "requests_s": 0.0, "resolve_s": 0.0}
           for s in streams}
    zero = repeats = pixels = 0
    threads = lib.threads
    try:
        for n, f in enumerate(frames):
            got = {}
            for s in streams:
                (reqs, sampler), secs = _timed(lambda: frame_requests(scene, f, src, "trilinear", stream=s))
                got[s] = [reqs, sampler, None]
                tot[s]["requests_s"] += secs
            for nt, key in ((threads, "sim_s"), (1, "sim_1t_s")):
                if key == "sim_1t_s" and threads == 1:
                    continue                                            # the default is one thread
                lib.set_threads(nt)
                for s in (streams if n % 2 == 0 else streams[::-1]):        # alternate who goes first
                    res, secs = _timed(lambda: run_batch(lib, info, got[s][0]))
                    tot[s][key] += secs
                    got[s][2] = res
            lib.set_threads(threads)
            images = {}
            for s in streams:
                reqs, sampler, res = got[s]
                images[s], secs = _timed(lambda: sampler.resolve(res.responses))
                tot[s]["resolve_s"] += secs
                tot[s]["requests"] += len(reqs)
                tot[s]["cycles"] += res.cycles
            if not np.array_equal(images["fixed"], images["sparse"]):
                raise AssertionError(f"{scene.name} frame {f}: the sparse stream's frame differs from the fixed one's")
            k = got["sparse"][1].skipped
            zero, repeats, pixels = zero + k.zero_weight, repeats + k.repeats, pixels + len(got["sparse"][1].counts)
    finally:
        lib.close()
    nf = len(frames)
    per = {s: {"requests_per_frame": round(tot[s]["requests"] / nf, 1), "cycles_per_frame": round(tot[s]["cycles"] / nf, 1),
               "sim_seconds": round(tot[s]["sim_s"], 3), "sim_seconds_1_thread": round(tot[s]["sim_1t_s"], 3),
               "request_seconds": round(tot[s]["requests_s"], 3), "resolve_seconds": round(tot[s]["resolve_s"], 3)}
           for s in streams}
    if threads == 1:
        for s in streams:
            per[s]["sim_seconds_1_thread"] = per[s]["sim_seconds"]
    f, s = tot["fixed"], tot["sparse"]
    return {
        "scene": scene.name, "frames": nf, "covered_pixels_per_frame": round(pixels / nf, 1),
        "fixed": per["fixed"], "sparse": per["sparse"],
        "skipped_zero_weight_per_frame": round(zero / nf, 1), "skipped_repeats_per_frame": round(repeats / nf, 1),
        "requests_saved": round(1 - s["requests"] / f["requests"], 4) if f["requests"] else 0.0,
        "cycles_saved": round(1 - s["cycles"] / f["cycles"], 4) if f["cycles"] else 0.0,
        "sim_time_saved": round(1 - s["sim_s"] / f["sim_s"], 4) if f["sim_s"] else 0.0,
        "frames_identical": True, "rtl_backend": "cxxrtl", "threads": threads,
    }


def run(json_out: bool = False, scenes=("topspin", "town")) -> list[dict]:
    """Benchmark every frame of ``scenes``; print a table (or one JSON object) and return the rows."""
    rows = [bench_scene(s) for s in scenes]
    if json_out:
        print(json.dumps({"skip": rows}, sort_keys=True))
        return rows
    print(f"{'scene':8} {'frames':>6} {'stream':7} {'requests/frame':>15} {'cycles/frame':>13} "
          f"{'RTL s':>7} {'RTL s 1t':>8} {'requests s':>10} {'resolve s':>9}")
    for r in rows:
        for s in ("fixed", "sparse"):
            p = r[s]
            print(f"{r['scene']:8} {r['frames']:6} {s:7} {p['requests_per_frame']:15,.0f} {p['cycles_per_frame']:13,.0f} "
                  f"{p['sim_seconds']:7.2f} {p['sim_seconds_1_thread']:8.2f} {p['request_seconds']:10.2f} "
                  f"{p['resolve_seconds']:9.2f}")
        print(f"{'':8} sparse saves {100 * r['requests_saved']:.1f}% of requests, {100 * r['cycles_saved']:.1f}% of "
              f"cycles, {100 * r['sim_time_saved']:.1f}% of RTL time ({r['threads']} threads); per frame "
              f"{r['skipped_zero_weight_per_frame']:,.0f} zero-weight requests and {r['skipped_repeats_per_frame']:,.0f} "
              f"repeats left out; frames identical")
    return rows


if __name__ == "__main__":
    run()
