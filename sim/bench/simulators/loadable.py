"""CXXRTL speed of the loadable unit (``python -m vqtex.sim.bench.simulators.loadable [--scene
topspin] [--geometry NAME] [--requests N] [--runs R] [--json]``).

The built-in scene's texture set (:func:`vqtex.sim.reports.synth.scene_texture_set`) loaded over the
bus (:func:`vqtex.sim.backends.cxxrtl.load_set`) into the loadable unit of its own geometry
(:meth:`golden.geometry.Geometry.of`) or of a preset (``--geometry paper``), then ``requests``
random requests (every texture and level, :func:`golden.fetch.random_requests`) through
``vq_run`` on one thread, ``runs`` times: the best cycles per second in this thread's CPU time
(``time.thread_time``: on a shared machine wall time includes waiting for a core) and in wall time.
Only the run is timed (no build, no load). The responses must equal ``golden.fetch``'s. To compare
two builds, run this command in each tree alternately (docs/loadable.md).
"""

from __future__ import annotations

import argparse
import json
import time

__all__ = ["loadable_speed", "main"]


def loadable_speed(ts, geometry=None, *, requests: int = 1_000_000, runs: int = 3, seed: int = 1) -> dict:
    """``{"cycles", "requests", "load_cycles", "cycles_per_cpu_second", "cycles_per_second"}`` of the
    loadable unit holding ``ts`` (``geometry``: a :class:`golden.geometry.Geometry`, default the
    set's own), best of ``runs``."""
    import numpy as np

    from vqtex.golden.fetch import fetch, random_requests
    from vqtex.golden.geometry import Geometry
    from vqtex.sim.backends.cxxrtl import load_set, open_cxxrtl, run_batch
    geometry = Geometry.of(ts) if geometry is None else geometry
    req = random_requests(ts, requests, seed=seed)
    lib, info, _ = open_cxxrtl(ts, geometry=geometry)
    try:
        load = load_set(lib, ts, geometry)
        cpu = wall = float("inf")
        for _ in range(runs):
            c, w = time.thread_time(), time.perf_counter()
            res = run_batch(lib, info, req)
            cpu, wall = min(cpu, time.thread_time() - c), min(wall, time.perf_counter() - w)
    finally:
        lib.close()
    if not np.array_equal(res.responses, fetch(ts, *req.T)):
        raise AssertionError("the loadable unit's responses differ from golden.fetch")
    return {"cycles": res.cycles, "requests": requests, "load_cycles": int(load),
            "cycles_per_cpu_second": res.cycles / cpu, "cycles_per_second": res.cycles / wall}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default="topspin", help="a built-in scene whose texture set is loaded")
    ap.add_argument("--geometry", default=None, help="a geometry preset (default: the set's own geometry)")
    ap.add_argument("--requests", type=int, default=1_000_000)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    from vqtex.golden.geometry import preset
    from vqtex.sim.reports.synth import scene_texture_set
    r = loadable_speed(scene_texture_set(a.scene), None if a.geometry is None else preset(a.geometry),
                       requests=a.requests, runs=a.runs)
    r.update(scene=a.scene, geometry=a.geometry or "own")
    if a.json:
        print(json.dumps(r, indent=1))
        return
    print(f"loadable unit, {a.scene}'s set in geometry {r['geometry']}: load {r['load_cycles']} cycles; "
          f"{r['cycles']} cycles for {r['requests']} requests: {r['cycles_per_cpu_second']:.3e} cycles per CPU "
          f"second, {r['cycles_per_second']:.3e} per wall second (best of {a.runs}, one thread)")


if __name__ == "__main__":
    main()
