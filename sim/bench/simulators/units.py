"""CXXRTL speed of the specialised and the full texel-fetch unit, side by side
(``python -m vqtex.sim.bench.simulators.units SET.vqt ... [--requests N] [--runs R]``).

For each texture set: both libraries (:func:`vqtex.sim.backends.cxxrtl.open_cxxrtl`, built or from
the cache), the same random requests (every texture and level, :func:`golden.fetch.random_requests`)
with output backpressure, run alternately (specialised, full, specialised, ...) ``runs`` times at one
thread and at two; the best cycles per second of each, and their ratio. Only the run is timed (no
build, no elaboration). Prints one JSON object.
"""

from __future__ import annotations

import argparse
import json
import time

__all__ = ["unit_speeds", "main"]


def unit_speeds(ts, *, requests: int = 2_000_000, runs: int = 3, stall: float = 0.1, seed: int = 1) -> dict:
    """``{threads: {"specialised": cycles/s, "full": cycles/s, "ratio": specialised / full}}`` for
    threads 1 and 2, best of ``runs`` alternated runs each; both units' responses must agree."""
    import numpy as np

    from vqtex.golden.fetch import random_requests
    from vqtex.sim.backends import cxxrtl as cb
    req = random_requests(ts, requests, seed=seed)
    libs = {unit: cb.open_cxxrtl(ts, specialise=unit == "specialised") for unit in ("specialised", "full")}
    out = {}
    try:
        for threads in (1, 2):
            best = {unit: 0.0 for unit in libs}
            answers = {}
            for _ in range(runs):
                for unit, (lib, info, _) in libs.items():
                    lib.set_threads(threads)
                    t0 = time.perf_counter()
                    res = cb.run_batch(lib, info, req, stall=stall, seed=seed)
                    best[unit] = max(best[unit], res.cycles / (time.perf_counter() - t0))
                    answers[unit] = (res.responses, res.cycles)
            if not (np.array_equal(answers["specialised"][0], answers["full"][0])
                    and answers["specialised"][1] == answers["full"][1]):
                raise RuntimeError("the specialised and the full unit disagree")
            out[threads] = {**{u: round(v) for u, v in best.items()},
                            "ratio": round(best["specialised"] / best["full"], 3)}
    finally:
        for lib, _, _ in libs.values():
            lib.close()
    return out


def main(argv=None) -> None:
    p = argparse.ArgumentParser(prog="python -m vqtex.sim.bench.simulators.units", description=__doc__.split("\n")[0])
    p.add_argument("sets", nargs="+", metavar="SET.vqt", help="texture sets to measure")
    p.add_argument("--requests", type=int, default=2_000_000, help="requests per run (default 2000000)")
    p.add_argument("--runs", type=int, default=3, help="alternated runs per unit and thread count (default 3)")
    args = p.parse_args(argv)
    from vqtex.golden.format import TextureSet
    print(json.dumps({path: unit_speeds(TextureSet.load(path), requests=args.requests, runs=args.runs)
                      for path in args.sets}))


if __name__ == "__main__":
    main()
