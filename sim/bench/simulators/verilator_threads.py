"""``python -m vqtex.sim.bench.simulators.verilator_threads [--requests N] [--json]``: the default
unit's Verilator model verilated for one thread and with ``--threads 2``, beside the CXXRTL library on
one thread, on the same random request stream in one run.

Printed: simulated cycles per second of the ``vq_run`` call (best of three; wall time, since a
threaded model's work is on other threads too) and each against CXXRTL on one thread. The stream is
short by default (2e5 requests): the threaded model is slow (docs/simulation.md, Verilator section).
Responses and cycles are checked against the golden model.
"""

from __future__ import annotations

import json
import time

import numpy as np

from vqtex.golden.fetch import random_requests

__all__ = ["run"]


def run(json_out: bool = False, *, n: int = 200_000, threads=(1, 2)) -> dict:
    from vqtex.sim.backends.cxxrtl import batch_layout, open_cxxrtl
    from vqtex.sim.backends.interface import simulate
    from vqtex.sim.backends.verilator import open_verilator
    from vqtex.sim.bench.simulators.simulation import default_unit

    ts = default_unit()
    req = np.ascontiguousarray(random_requests(ts, n), dtype=np.int64).reshape(-1, 4)
    golden = simulate(ts, req, backend="golden")
    libs = {f"verilator --threads {t}" if t > 1 else "verilator": open_verilator(ts, threads=t)[:2]
            for t in threads}
    cxx, info = open_cxxrtl(ts)[:2]
    cxx.set_threads(1)
    libs["cxxrtl 1t"] = (cxx, info)
    rows = {}
    for name, (lib, info) in libs.items():
        layout = batch_layout(info)
        best = float("inf")
        for _ in range(3):
            t = time.perf_counter()
            rc, rgba, counters = lib.run(req, layout, None, 2 * n + 64)
            best = min(best, time.perf_counter() - t)
        rows[name] = {"cycles": int(counters[0]), "run_s": best, "cycles_per_s": int(counters[0]) / best,
                      "agrees_with_golden": bool(rc == 0 and np.array_equal(rgba, golden.responses)
                                                 and int(counters[0]) == golden.cycles)}
        lib.close()
    for r in rows.values():
        r["vs_cxxrtl_1t"] = r["cycles_per_s"] / rows["cxxrtl 1t"]["cycles_per_s"]
    report = {"requests": n, "backends": rows}
    if json_out:
        print(json.dumps(report, sort_keys=True))
    else:
        print(f"Verilator threads on the default unit, {n} random requests, vq_run wall time, best of three")
        for name, r in rows.items():
            print(f"{name:<22} {r['cycles_per_s']:>10.3g} cycles/s {r['vs_cxxrtl_1t']:>6.2f}x cxxrtl 1t  "
                  f"agrees {r['agrees_with_golden']}")
    return report


if __name__ == "__main__":
    import sys
    n = int(sys.argv[sys.argv.index("--requests") + 1]) if "--requests" in sys.argv else 200_000
    run(json_out="--json" in sys.argv, n=n)
