"""Write the cocotb testbench of an exported texel-fetch unit (``vqtex export ... --testbench DIR``).

Into DIR go, beside or away from the Verilog (the configuration names it by a path relative to DIR):

- ``tb_texel_fetch.py``: the cocotb test module (driver, backpressure, monitor, the scoreboard
  ``vqtex.golden.fetch``, the loadable unit's Wishbone load, cocotb-coverage bins), a verbatim copy of
  :mod:`vqtex.sim.testbench.tb_texel_fetch`;
- ``run_tb.py``: its runner on cocotb's Python runner, ``SIM=icarus`` or ``SIM=verilator``, a verbatim
  copy of :mod:`vqtex.sim.testbench.run_tb`;
- ``tb_config.json``: the top module, the unit (``specialised``, ``full``, ``loadable`` with its
  geometry, ``external``: the cached unit with its caches' shapes under ``memory``; ``loadable``
  with ``memory``: the loadable cached unit), tag width and latency (the
  cached unit's when every reference hits), the Verilog and its Verilator waivers, the default run
  (``requests``, ``seed``, ``stall``, ``gap``, ``per_bin``), the texture set and its digest;
- ``tb_set.vqt``: the texture set, the one baked into the unit's ROMs or the one the bench loads
  through the bus (the scoreboard computes the expected responses from it at run time).

Why the scoreboard is golden.fetch at run time and not a file of expected responses: the bench draws
its requests from the seed, directs some at the coverage bins, and adds closure requests for the bins
the random phase missed, all decided while it runs; a file would freeze one stream. The price is that
the simulator's Python needs vqtex installed (``pip install 'vqtex[cocotb]'``).
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil

__all__ = ["FILES", "DEFAULTS", "write_testbench", "set_digest", "testbench_files", "memory_dict"]

HERE = os.path.dirname(os.path.abspath(__file__))
#: What DIR receives: the copied modules and the two data files.
FILES = ("tb_texel_fetch.py", "run_tb.py", "tb_config.json", "tb_set.vqt")
#: The default run: a few hundred requests (seconds on Icarus), 30 % output backpressure, 10 % input gaps.
DEFAULTS = {"requests": 300, "seed": 1, "stall": 0.3, "gap": 0.1, "per_bin": 4}


def set_digest(ts) -> str:
    """SHA-256 of the set's ``.vqt`` bytes: a baked unit's bench refuses any other set."""
    return hashlib.sha256(ts.to_bytes()).hexdigest()


def testbench_files(folder: str) -> list:
    """The paths the testbench occupies in ``folder`` (for the export's output checks)."""
    return [os.path.join(folder, name) for name in FILES]


def memory_dict(memory) -> dict:
    """A :class:`golden.memory.system.MemoryConfig`'s shape as JSON: the caches (size, line, ways),
    the FIFO depth and the bus width (what the exported cached unit is built with; its memory's
    timing is whatever answers its AXI master)."""
    return {"index_cache": {"size": memory.index_cache.size, "line": memory.index_cache.line,
                            "ways": memory.index_cache.ways},
            "raw_cache": {"size": memory.raw_cache.size, "line": memory.raw_cache.line, "ways": memory.raw_cache.ways},
            "prefetch": memory.prefetch, "bus_bytes": memory.bus_bytes}


def write_testbench(paths: dict, *, verilog: str, ts, top: str, unit: str, tag_width: int, latency: int,
                    geometry=None, folder: str | None = None, memory=None) -> dict:
    """Write :data:`FILES` to ``paths[name]`` (staging paths; ``folder`` is where they end up, default
    that of ``paths``' config file, so the Verilog and its ``.vlt`` are named relative to it).
    ``memory``: the cached unit's MemoryConfig (``unit`` ``external``, or ``loadable`` with ``geometry``:
    the loadable cached unit). Returns the configuration written."""
    folder = os.path.abspath(folder or os.path.dirname(paths["tb_config.json"]))
    stem = os.path.splitext(os.path.abspath(verilog))[0]
    cfg = {"top": top, "unit": unit, "tag_width": int(tag_width), "latency": int(latency),
           "verilog": os.path.relpath(os.path.abspath(verilog), folder),
           "waivers": os.path.relpath(stem + ".vlt", folder),
           "set": "tb_set.vqt", "set_digest": set_digest(ts),
           "geometry": geometry.dumps() if geometry is not None else None,
           "memory": memory_dict(memory) if memory is not None else None, **DEFAULTS}
    for name in ("tb_texel_fetch.py", "run_tb.py"):
        shutil.copyfile(os.path.join(HERE, name), paths[name])
    with open(paths["tb_config.json"], "w") as f:
        json.dump(cfg, f, indent=1)
        f.write("\n")
    with open(paths["tb_set.vqt"], "wb") as f:
        f.write(ts.to_bytes())
    return cfg
