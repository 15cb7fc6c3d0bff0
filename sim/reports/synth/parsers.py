"""The tools' output read: Yosys ``stat -json``, its ``memory_libmap`` log lines and netlist, and
nextpnr's JSON report (or, without one, its log), the critical path step by step."""

from __future__ import annotations

import json
import re

from .stages import signal_of, stage_of
from .target import HARNESS_NAME, UNIT_NAME, SynthError

__all__ = ["parse_memory_mapping", "count_memory_blocks", "HEADLINE", "parse_yosys_stat", "parse_nextpnr_report",
           "parse_nextpnr_log"]


_LIBMAP = re.compile(r"^(using FF mapping for memory|mapping memory) (\S+?)(?: via (\S+))?$", re.M)


def parse_memory_mapping(log: str) -> dict:
    """Yosys ``memory_libmap`` decisions from its log: memory (name inside the unit, e.g.
    ``fetch.back.codebook_rom.codebook``) -> ``"block RAM"`` or ``"logic"`` (flip-flops that hold
    constants, i.e. LUTs: a ROM too small for a DP16KD to pay off)."""
    out = {}
    for kind, name, via in _LIBMAP.findall(log):
        short = name[len(UNIT_NAME) + 1:] if name.startswith(UNIT_NAME + ".") else name
        if kind.startswith("using FF"):
            out[short] = "logic"
        elif "DP16KD" in (via or "") or "PDPW16KD" in (via or ""):
            out[short] = "block RAM"
        elif "DPR16X4" in (via or ""):
            out[short] = "distributed RAM"
        else:
            out[short] = via or "?"
    return out


def count_memory_blocks(netlist: dict, module: str) -> dict:
    """DP16KD cells per memory in ``module`` of a Yosys JSON netlist (cells are named
    ``<memory>.<row>.<column>``)."""
    mod = (netlist.get("modules") or {}).get(module) or {}
    out: dict = {}
    for name, cell in (mod.get("cells") or {}).items():
        if cell.get("type") == "DP16KD":
            mem = re.sub(r"\.\d+\.\d+$", "", name.lstrip("\\"))
            out[mem] = out.get(mem, 0) + 1
    return out


#: Cell types reported by name, and the headline keys they feed.
HEADLINE = {"LUT4": "luts", "TRELLIS_FF": "ffs", "DP16KD": "brams", "MULT18X18D": "dsps"}


def parse_yosys_stat(text: str) -> dict:
    """Yosys ``stat -json`` -> ``{module: {"cells": {type: n}, "headline": {...}}}`` for each module
    (Yosys' own module names without the leading backslash)."""
    start = text.find("{")
    if start < 0:
        raise SynthError("yosys stat produced no JSON")
    data = json.loads(text[start:])
    out = {}
    for name, mod in data.get("modules", {}).items():
        cells = {k.lstrip("\\$"): int(v) for k, v in (mod.get("num_cells_by_type") or {}).items()
                 if k != "$scopeinfo" and not k.lstrip("\\").startswith(HARNESS_NAME)}
        head = {key: cells.get(cell, 0) for cell, key in HEADLINE.items()}
        head["carry"] = cells.get("CCU2C", 0)
        head["dist_ram"] = cells.get("TRELLIS_DPR16X4", 0)
        head["wide_mux"] = cells.get("PFUMX", 0) + cells.get("L6MUX21", 0)
        out[name.lstrip("\\")] = {"cells": dict(sorted(cells.items())), "headline": head}
    return out


def parse_nextpnr_report(report: dict, clock: str | None = None) -> dict:
    """nextpnr's ``--report`` JSON -> ``{"fmax_mhz", "target_mhz", "clock", "utilisation",
    "critical_path"}``. ``critical_path`` is the worst path of ``clock`` (default: the slowest clock)
    as ``{"from", "to", "from_stage", "to_stage", "delay_ns", "logic_ns", "routing_ns", "steps"}``."""
    fmax = report.get("fmax") or {}
    if not fmax:
        raise SynthError("nextpnr report has no clock (no register-to-register path?)")
    if clock is None:
        clock = min(fmax, key=lambda c: fmax[c]["achieved"])
    util = {k: {"used": int(v["used"]), "available": int(v["available"])}
            for k, v in (report.get("utilization") or {}).items()}
    # Register-to-register paths of the clock are "posedge <clock>" -> "posedge <clock>"; the pad
    # paths ("<async>") are not what Fmax measures.
    paths = [p for p in report.get("critical_paths") or []
             if str(p.get("from", "")).split()[-1:] == [clock] and str(p.get("to", "")).split()[-1:] == [clock]]
    crit = _critical_path(paths[0]) if paths else None
    return {"clock": clock, "fmax_mhz": round(float(fmax[clock]["achieved"]), 2),
            "target_mhz": round(float(fmax[clock]["constraint"]), 2), "utilisation": util,
            "critical_path": crit}


def _critical_path(path: dict) -> dict:
    steps, logic, routing = [], 0.0, 0.0
    for seg in path.get("path", []):
        kind, delay = seg.get("type"), float(seg.get("delay", 0.0))
        if kind == "routing":
            routing += delay
        else:
            logic += delay
        steps.append({"type": kind, "delay_ns": round(delay, 3), "net": seg.get("net", ""),
                      "from": f"{seg['from']['cell']}.{seg['from']['port']}",
                      "to": f"{seg['to']['cell']}.{seg['to']['port']}",
                      "stage": stage_of(signal_of(seg["to"]["cell"]))})
    if not steps:
        return {"from": "", "to": "", "from_signal": "", "to_signal": "", "from_stage": "", "to_stage": "",
                "stages": [], "delay_ns": 0.0, "logic_ns": 0.0, "routing_ns": 0.0, "steps": []}
    first, last = path["path"][0], path["path"][-1]
    src, dst = first["from"]["cell"], last["to"]["cell"]
    through = [signal_of(seg["to"]["cell"]) for seg in path["path"] if seg.get("type") != "routing"]
    return {"from": f"{src}.{first['from']['port']}", "to": f"{dst}.{last['to']['port']}",
            "from_signal": signal_of(src), "to_signal": signal_of(dst),
            "from_stage": stage_of(signal_of(src)), "to_stage": stage_of(signal_of(dst)),
            "stages": _dedup([stage_of(signal_of(src))] + [s["stage"] for s in steps]),
            "cells": _dedup([signal_of(src)] + through),
            "delay_ns": round(logic + routing, 3), "logic_ns": round(logic, 3), "routing_ns": round(routing, 3),
            "steps": steps}


def _dedup(seq):
    out = []
    for s in seq:
        if not out or out[-1] != s:
            out.append(s)
    return out


_CRIT_HEAD = re.compile(r"Critical path report for clock '([^']+)' \(posedge -> posedge\)")
_FMAX = re.compile(r"Max frequency for clock\s+'([^']+)':\s+([\d.]+) MHz \((PASS|FAIL) at ([\d.]+) MHz\)")


def parse_nextpnr_log(text: str) -> dict:
    """The human-readable log (fallback when there is no JSON report): the last ``Max frequency``
    line per clock and the source/sink cells of the last critical path report."""
    fm = {}
    for clk, achieved, verdict, target in _FMAX.findall(text):
        fm[clk] = {"fmax_mhz": float(achieved), "target_mhz": float(target), "pass": verdict == "PASS"}
    heads = list(_CRIT_HEAD.finditer(text))
    src = sink = None
    if heads:
        block = text[heads[-1].end():]
        end = re.search(r"ns logic, [\d.]+ ns routing", block)    # the path's summary line ends it
        block = block[:end.start()] if end else block
        sources = re.findall(r"Source (\S+)", block)
        sinks = re.findall(r"Sink (\S+)", block)
        src, sink = (sources[0] if sources else None), (sinks[-1] if sinks else None)
    return {"clocks": fm, "critical_from": src, "critical_to": sink}
