"""Long request streams through ``vqtex sim``: the compiled RTL against golden, under load.

``load_check`` writes the default unit's texture set (the built-in ``topspin`` scene) and a random
request stream (every texture and level) to a folder, then runs the command a user would run,
``vqtex sim SET REQUESTS -o RESPONSES --backend B --stall P [--one-port] --json``, once with the
golden backend and once with the compiled one, each in its own process, and compares what they
wrote: every response (RGBA, in request order) and every count (cycles, stall cycles by cause,
straddling index reads). A response lost, duplicated or reordered changes the responses (and the
batch driver checks each response's tag against its request number besides); a cycle gained or
lost changes the counts.

Each process's wall time and peak resident memory (``os.wait4``'s ``ru_maxrss``) are reported, so
the memory a stream of N requests costs is a measured figure (docs/stability.md).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

__all__ = ["load_check", "run_command"]


def run_command(argv: list, timeout: float = 1800.0) -> dict:
    """Run ``python -m vqtex.sim.cli *argv`` and return its exit status, stdout, stderr, wall seconds,
    CPU (user + system) seconds and peak resident memory in MiB (Linux ``ru_maxrss`` is in KiB)."""
    t0 = time.perf_counter()
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        p = subprocess.Popen([sys.executable, "-m", "vqtex.sim.cli", *argv], stdout=out, stderr=err)
        deadline = time.monotonic() + timeout
        while True:
            pid, status, usage = os.wait4(p.pid, os.WNOHANG)
            if pid:
                break
            if time.monotonic() > deadline:
                p.kill()
                pid, status, usage = os.wait4(p.pid, 0)
                break
            time.sleep(0.02)
        p.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        return {"returncode": p.returncode, "stdout": out.read().decode(), "stderr": err.read().decode(),
                "seconds": time.perf_counter() - t0, "peak_mib": usage.ru_maxrss / 1024.0,
                "cpu_seconds": usage.ru_utime + usage.ru_stime}


def load_check(n: int = 10_000_000, *, stall: float = 0.3, one_port: bool = False, seed: int = 0,
               backend: str = "cxxrtl", ts=None, folder: str | None = None) -> dict:
    """``n`` random requests through ``vqtex sim`` on golden and on ``backend``; returns the figures.

    Raises ``AssertionError`` naming the first difference if the two runs disagree (or a run fails).
    """
    from vqtex.golden.fetch import random_requests
    from ..simulators.simulation import default_unit

    with tempfile.TemporaryDirectory(dir=folder) as tmp:
        set_path = os.path.join(tmp, "unit.vqt")
        req_path = os.path.join(tmp, "requests.npy")
        (ts if ts is not None else default_unit()).save(set_path)
        from vqtex.golden.format import TextureSet
        np.save(req_path, random_requests(TextureSet.load(set_path), n, seed=seed))
        runs, reports, responses = {}, {}, {}
        for name in ("golden", backend):
            out = os.path.join(tmp, f"{name}.npy")
            argv = ["sim", set_path, req_path, "-o", out, "--backend", name, "--stall", str(stall),
                    "--seed", str(seed), "--json"] + (["--one-port"] if one_port else [])
            r = run_command(argv)
            assert r["returncode"] == 0, f"vqtex sim --backend {name}: {r['stderr'].strip()[-300:]}"
            runs[name] = r
            reports[name] = json.loads(r["stdout"])
            responses[name] = np.load(out, mmap_mode="r")
        g, b = responses["golden"], responses[backend]
        assert g.shape == b.shape == (n, 4), f"responses of shape {g.shape} and {b.shape}, expected ({n}, 4)"
        differ = np.flatnonzero(np.any(np.asarray(g) != np.asarray(b), axis=1))
        assert not len(differ), f"{len(differ)} responses differ, the first at request {differ[0]}"
        keys = ("requests", "cycles", "stall_cycles", "straddling_index_reads", "latency")
        for k in keys:
            assert reports["golden"][k] == reports[backend][k], \
                f"{k}: golden {reports['golden'][k]} != {backend} {reports[backend][k]}"
        rep = reports[backend]
        return {
            "backend": backend, "requests": n, "stall": stall, "one_port": one_port,
            "cycles": rep["cycles"], "stall_cycles": rep["stall_cycles"],
            "straddling_index_reads": rep["straddling_index_reads"],
            "mismatches": 0,
            "seconds": {k: round(v["seconds"], 2) for k, v in runs.items()},
            "peak_mib": {k: round(v["peak_mib"], 1) for k, v in runs.items()},
            "request_file_mib": round(os.path.getsize(req_path) / 2**20, 1),
        }
