"""``vqtex bench sim [--json]``: simulation backends side by side on the default unit.

The default unit is ``TexelFetch`` (two-bank index memory, tag width 8) holding the built-in
``topspin`` scene's texture set (three 256x256 mipmapped textures, 256-entry codebooks). The same
random request stream (every texture and level) runs on pysim (a short prefix: about 1e4 cycles/s),
on the CXXRTL library and on the Verilator library; the numbers printed are simulated cycles per
second of the run (end to end: ``run_batch``, the numpy side and ``vq_run``, best of three for the
compiled backends), of ``vq_run`` alone ("in library", best of three, without backpressure; it
packs the requests and checks the response tags itself), and the build times of a *first* build (a
fresh, temporary cache: Yosys or Verilator plus the C++ compiler) and of a cached build (a second
process would see the same). The CXXRTL library runs the unit's two halves on two threads when the
machine has two CPUs (``VQTEX_SIM_THREADS``); the same library on one thread is measured in the same
run and printed as ``cxxrtl 1t``, and the Verilator library's speed as a ratio to it
(``verilator_vs_cxxrtl_1t``: both end to end, best of three, in this run).
Responses and cycle counts of every backend are checked against the golden model on the way.

``filter`` (in the default backends): a second table, the RTL texture filter (four lanes) on CXXRTL
on the pixels of topspin frames 0-2 in bilinear mode, as ``vqtex render --filter-in-rtl`` runs it:
cycles per second end to end and in the library, wall and CPU (:mod:`.filter`).
"""

from __future__ import annotations

import json
import tempfile
import time

import numpy as np

from vqtex.golden.fetch import random_requests

__all__ = ["run", "default_unit"]


def default_unit():
    from vqtex.golden.render.scene import build_texture_set, load_scene
    return build_texture_set(load_scene("topspin"))


def _timed(fn):
    t = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t


def _library_seconds(lib, info, req, repeats: int = 3) -> float:
    """Best time of the ``vq_run`` call alone (it packs the requests and checks the tags itself)."""
    from vqtex.sim.backends.cxxrtl import batch_layout
    req = np.ascontiguousarray(req, dtype=np.int64).reshape(-1, 4)
    layout = batch_layout(info)
    best = float("inf")
    for _ in range(repeats):
        _, secs = _timed(lambda: lib.run(req, layout, None, 2 * len(req) + 64))
        best = min(best, secs)
    return best


def run(json_out: bool = False, *, n_compiled: int = 4_000_000, n_pysim: int = 3000, stall: float = 0.0,
        backends=("pysim", "cxxrtl", "verilator", "filter")) -> dict:
    """Run the benchmark, print a table (or one JSON object) and return the numbers."""
    from vqtex.sim.backends.interface import simulate
    from vqtex.sim.backends.toolchain import ToolchainError, using_cache

    ts, t_set = _timed(default_unit)
    req = random_requests(ts, n_compiled)
    report = {"unit": "topspin texture set, two-bank, tag width 8", "requests_compiled": n_compiled,
              "requests_pysim": n_pysim, "stall": stall, "backends": {}}
    rows = report["backends"]
    golden = None
    if "pysim" in backends:
        small = req[:n_pysim]
        res, secs = _timed(lambda: simulate(ts, small, backend="pysim", stall=stall))
        want = simulate(ts, small, backend="golden", stall=stall)
        rows["pysim"] = {"cycles": res.cycles, "run_s": secs, "cycles_per_s": res.cycles / secs,
                         "build_first_s": 0.0, "build_cached_s": 0.0,
                         "agrees_with_golden": bool(np.array_equal(res.responses, want.responses)
                                                    and res.cycles == want.cycles)}
    golden = simulate(ts, req, backend="golden", stall=stall)
    for name in ("cxxrtl", "verilator"):
        if name not in backends:
            continue
        if name == "cxxrtl":
            from vqtex.sim.backends.cxxrtl import build_cxxrtl as build, open_cxxrtl as opener, run_batch
        else:
            from vqtex.sim.backends.verilator import build_verilator as build, open_verilator as opener
            from vqtex.sim.backends.cxxrtl import run_batch
        try:
            with tempfile.TemporaryDirectory(prefix="vqtex-bench-") as cache, using_cache(cache):
                first, t_first = _timed(lambda: build(ts))
                _, t_cached = _timed(lambda: build(ts))
                (lib, info, _), t_open = _timed(lambda: opener(ts))
                secs = float("inf")
                for _ in range(3):          # best of three, as for the library alone
                    res, t = _timed(lambda: run_batch(lib, info, req, stall=stall))
                    secs = min(secs, t)
                if stall <= 0:
                    lib_s = _library_seconds(lib, info, req)
                threads, one = lib.threads, None
                if threads > 1:             # the same library, one thread, side by side
                    lib.set_threads(1)
                    one = float("inf")
                    for _ in range(3):
                        r1, t = _timed(lambda: run_batch(lib, info, req, stall=stall))
                        one = min(one, t)
                    one_ok = bool(np.array_equal(r1.responses, golden.responses) and r1.cycles == golden.cycles)
                lib.close()
        except ToolchainError as e:
            rows[name] = {"error": str(e)}
            continue
        rows[name] = {"cycles": res.cycles, "run_s": secs, "cycles_per_s": res.cycles / secs,
                      "cycles_per_s_in_library": res.cycles / lib_s if stall <= 0 else None,
                      "build_first_s": t_first, "build_cached_s": t_cached, "open_s": t_open,
                      "build_steps_s": {k: round(v, 3) for k, v in first.steps.items()},
                      "agrees_with_golden": bool(np.array_equal(res.responses, golden.responses)
                                                 and res.cycles == golden.cycles
                                                 and res.stall_cycles == golden.stall_cycles
                                                 and res.straddles == golden.straddles),
                      "threads": threads}
        if one is not None:
            rows[f"{name} 1t"] = {"cycles": r1.cycles, "run_s": one, "cycles_per_s": r1.cycles / one,
                                  "cycles_per_s_in_library": None, "build_first_s": t_first,
                                  "build_cached_s": t_cached, "threads": 1, "agrees_with_golden": one_ok}
    one_thread = rows.get("cxxrtl 1t", rows.get("cxxrtl", {})).get("cycles_per_s")
    if one_thread and "cycles_per_s" in rows.get("verilator", {}):
        # the issue-26 target: Verilator at least as fast as CXXRTL on one thread, same stream, one run
        report["verilator_vs_cxxrtl_1t"] = rows["verilator"]["cycles_per_s"] / one_thread
    if "pysim" in rows:
        for name in list(rows):
            if name != "pysim" and "cycles_per_s" in rows[name]:
                rows[name]["speedup_vs_pysim"] = rows[name]["cycles_per_s"] / rows["pysim"]["cycles_per_s"]
    if "filter" in backends:
        from . import filter as filter_bench
        try:
            report["filter"] = filter_bench.filter_speeds(ts, filter_bench.scene_pixels(ts))
        except ToolchainError as e:
            report["filter"] = {"error": str(e)}
    if json_out:
        print(json.dumps(report, sort_keys=True))
    else:
        print(f"simulation backends on the default unit ({report['unit']}), stall {stall}")
        print(f"{'backend':<10} {'cycles':>10} {'run s':>8} {'cycles/s':>12} {'in library':>11} {'x pysim':>9} "
              f"{'1st build s':>11} {'cached s':>9} {'agrees':>7}")
        for name, r in rows.items():
            if "error" in r:
                print(f"{name:<10} {r['error']}")
                continue
            lib_rate = r.get("cycles_per_s_in_library")
            print(f"{name:<10} {r['cycles']:>10} {r['run_s']:>8.3f} {r['cycles_per_s']:>12.3g} "
                  f"{(f'{lib_rate:.3g}' if lib_rate else '-'):>11} "
                  f"{r.get('speedup_vs_pysim', 1.0):>9.0f} {r['build_first_s']:>11.2f} "
                  f"{r['build_cached_s']:>9.2f} {str(r['agrees_with_golden']):>7}")
        if "verilator_vs_cxxrtl_1t" in report:
            print(f"verilator / cxxrtl on one thread (end to end, this run): {report['verilator_vs_cxxrtl_1t']:.2f}")
        if "filter" in report:
            if "error" in report["filter"]:
                print(f"\nRTL texture filter: {report['filter']['error']}")
            else:
                from .filter import print_table
                print_table(report["filter"], "topspin frames 0-2, bilinear")
    return report


if __name__ == "__main__":
    import sys
    run(json_out="--json" in sys.argv)
