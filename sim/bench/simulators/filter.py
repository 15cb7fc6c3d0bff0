"""The RTL texture filter's simulation speed on the frames it renders (``vqtex bench sim``'s filter
table, :func:`filter_speeds`).

The four-lane filter (:class:`hw.filter.TextureFilter`, index memory banked by block parity) holding
the built-in ``topspin`` scene's texture set, on the per-pixel inputs of topspin frames 0, 1 and 2 in
bilinear mode: what ``vqtex render topspin --frames 0:3 --mode bilinear --backend cxxrtl
--filter-in-rtl`` runs. Measured: the set-up once (elaborating the filter and building its library,
or finding it in the build cache: :func:`sim.backends.filter.prepare_filter`), then per frame

- *end to end*: :func:`sim.backends.filter.simulate_filter`, what the renderer's ``rtl_seconds``
  times (checking the pixels, opening the library, loading its memories, ``vq_run``, the result);
- *in library*: ``vq_run`` alone on the same pixels (one library, opened once);

each best of ``repeats``, in wall time and in this thread's CPU time (``time.thread_time``: on a
shared machine the wall time includes the time the thread waited for a core, the CPU time does not).
Cycles and colours are checked against the golden filter on the way.
"""

from __future__ import annotations

import time

import numpy as np

__all__ = ["filter_speeds", "scene_pixels", "print_table", "main"]


def scene_pixels(ts, scene: str = "topspin", frames=(0, 1, 2), mode: str = "bilinear") -> list:
    """``[(frame, pixels, frac)]``: the filter's per-pixel inputs of ``frames`` of ``scene`` rendered
    from ``ts`` (:meth:`golden.render.sampling.Sampler.filter_inputs`, as ``vqtex render
    --filter-in-rtl`` makes them)."""
    from vqtex.golden.render.frame import frame_requests
    from vqtex.golden.render.pyramid import VQSource
    from vqtex.golden.render.scene import load_scene
    sc, src = load_scene(scene), VQSource(ts)
    out = []
    for f in frames:
        _, sampler = frame_requests(sc, f, src, mode)
        out.append((f, sampler.filter_inputs(sampler.fragments, sampler.frac), sampler.frac))
    return out


def _best(fn, repeats: int) -> tuple:
    """(last result, best wall seconds, best thread CPU seconds) of ``repeats`` calls."""
    wall = cpu = float("inf")
    for _ in range(repeats):
        w, c = time.perf_counter(), time.thread_time()
        out = fn()
        cpu = min(cpu, time.thread_time() - c)
        wall = min(wall, time.perf_counter() - w)
    return out, wall, cpu


def filter_speeds(ts, frames: list, *, lanes: int = 4, backend: str = "cxxrtl", index_banks: str = "parity",
                  repeats: int = 3) -> dict:
    """Measure the RTL filter on ``frames`` (``[(frame, pixels, frac)]``, :func:`scene_pixels`): the
    set-up seconds, then per frame cycles, end-to-end and in-library seconds (wall and CPU, best of
    ``repeats``), cycles per second, and whether colours and cycles are the golden filter's
    (colours) and the same on both paths (cycles). Returns ``{"setup_s", "frames": [...], "total":
    {...}}``."""
    from vqtex.sim.backends import cxxrtl
    from vqtex.sim.backends.design import FIELDS
    from vqtex.sim.backends.filter import (TAG_WIDTH, compiled_build, golden_colors, prepare_filter,
                                           simulate_filter, texel_slots)
    frac0 = frames[0][2]
    setup = prepare_filter(backend, ts, lanes=lanes, frac=frac0, index_banks=index_banks)
    lib, info, _ = cxxrtl.open_design(compiled_build(backend, ts, lanes=lanes, frac=frac0, index_banks=index_banks))
    rows = []
    try:
        layout = cxxrtl.batch_layout(info)
        for f, pixels, frac in frames:
            if frac != frac0:
                raise ValueError("the frames' coordinates have different fractional bits")
            res, e2e_wall, e2e_cpu = _best(lambda: simulate_filter(ts, pixels, backend=backend, lanes=lanes, frac=frac,
                                                                   index_banks=index_banks), repeats)
            req = np.stack([np.asarray(pixels[k], np.int64) for k in FIELDS], 1)
            groups = texel_slots(pixels["mode"], lanes) // lanes
            (rgba, counters), lib_wall, lib_cpu = _best(lambda: cxxrtl.run_checked(
                lib, req, layout, n=len(req), transfers=groups, latency=info.latency,
                worst=groups + info.latency + 64, stall=0.0, seed=0, tag_width=TAG_WIDTH, what="colour"), repeats)
            cycles = int(res.cycles)
            rows.append({
                "frame": int(f), "pixels": int(res.pixels), "cycles": cycles,
                "e2e_s": e2e_wall, "e2e_cpu_s": e2e_cpu, "library_s": lib_wall, "library_cpu_s": lib_cpu,
                "cycles_per_s": cycles / e2e_wall, "cycles_per_s_cpu": cycles / e2e_cpu,
                "cycles_per_s_in_library": cycles / lib_wall, "cycles_per_s_in_library_cpu": cycles / lib_cpu,
                "agrees_with_golden": bool(np.array_equal(res.colors, golden_colors(ts, pixels, frac))
                                           and np.array_equal(rgba, res.colors)
                                           and int(counters[cxxrtl.C_CYCLES]) == cycles),
            })
    finally:
        lib.close()
    cyc = sum(r["cycles"] for r in rows)
    total = {key: cyc / sum(r[sec] for r in rows) for key, sec in (
        ("cycles_per_s", "e2e_s"), ("cycles_per_s_cpu", "e2e_cpu_s"), ("cycles_per_s_in_library", "library_s"),
        ("cycles_per_s_in_library_cpu", "library_cpu_s"))}
    total.update(cycles=cyc, agrees_with_golden=all(r["agrees_with_golden"] for r in rows))
    return {"unit": f"TextureFilter, {lanes} lanes, index banks {index_banks}, tag width {TAG_WIDTH}",
            "backend": backend, "setup_s": setup, "repeats": repeats, "frames": rows, "total": total}


def print_table(rep: dict, what: str) -> None:
    """The filter's table as ``vqtex bench sim`` prints it."""
    print(f"\nRTL texture filter ({rep['unit']}) on {what}, {rep['backend']}, one model on one thread; "
          f"set-up (elaborate, build or find) {rep['setup_s']:.2f} s once; best of {rep['repeats']}")
    print(f"{'frame':>6} {'pixels':>8} {'cycles':>8} {'e2e s':>7} {'cycles/s':>9} {'(cpu)':>9} "
          f"{'in library':>10} {'(cpu)':>9} {'agrees':>7}")
    for r in rep["frames"] + [dict(rep["total"], frame="all", pixels=sum(f["pixels"] for f in rep["frames"]),
                                   e2e_s=sum(f["e2e_s"] for f in rep["frames"]))]:
        print(f"{r['frame']:>6} {r['pixels']:>8} {r['cycles']:>8} {r['e2e_s']:>7.3f} {r['cycles_per_s']:>9.3g} "
              f"{r['cycles_per_s_cpu']:>9.3g} {r['cycles_per_s_in_library']:>10.3g} "
              f"{r['cycles_per_s_in_library_cpu']:>9.3g} {str(r['agrees_with_golden']):>7}")


def main(argv=None) -> None:
    """``python -m vqtex.sim.bench.simulators.filter [--json] [--repeats N]``: the filter table of
    ``vqtex bench sim`` alone (topspin's set and frames 0-2, bilinear, four lanes)."""
    import argparse
    import json
    p = argparse.ArgumentParser(prog="python -m vqtex.sim.bench.simulators.filter", description=main.__doc__)
    p.add_argument("--json", action="store_true")
    p.add_argument("--repeats", type=int, default=3)
    args = p.parse_args(argv)
    from vqtex.golden.render.scene import build_texture_set, load_scene
    ts = build_texture_set(load_scene("topspin"))          # (simulation.default_unit: the same set)
    rep = filter_speeds(ts, scene_pixels(ts), repeats=args.repeats)
    if args.json:
        print(json.dumps(rep, sort_keys=True))
    else:
        print_table(rep, "topspin frames 0-2, bilinear")


if __name__ == "__main__":
    main()
