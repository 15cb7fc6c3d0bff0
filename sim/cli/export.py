"""``vqtex export FILE.vqt -o OUT.v [--one-port] [--tag-width N] [--name NAME] [--dialect sv|v2005] [--testbench DIR]
[--lint] [--json]``; ``vqtex export [FILE.vqt] --unit loadable [--geometry NAME|FILE.toml] -o OUT.v``;
``vqtex export FILE.vqt --memory external [--cache-size B --raw-cache-size B --cache-line B --cache-ways N
--prefetch Q --bus-bytes B] -o OUT.sv``.

``vqtex export [FILE.vqt] --filter-lanes N --memory external [--unit loadable --geometry NAME] -o OUT.sv``
exports the texture filter through the memory system (:class:`hw.memory.filter.CachedTextureFilter`,
docs/memory.md): N lanes, each behind its own caches of the options' shape, one AXI4 read master
(``axi_*``); with ``--unit loadable`` the loadable filter (no texture data, the Wishbone port
``bus_*``, the loadable cached unit's register map and C header beside it).

``--memory external`` exports the cached unit (:class:`hw.memory.unit.CachedTexelFetch`, docs/memory.md):
the index map and raw levels in a memory outside it, read by its AXI4 read master (ports ``axi_*``)
through the caches the options shape (the same options as ``vqtex sim``; the memory's own timing
options do not apply: the memory is whatever answers the master).

``--testbench DIR`` (with FILE.vqt, the texel-fetch unit) also writes a cocotb testbench of the
unit into DIR (:mod:`vqtex.sim.testbench.write`: ``tb_texel_fetch.py``, ``run_tb.py``,
``tb_config.json``, ``tb_set.vqt``; docs/verification.md), staged with the other outputs.

With ``--unit loadable --memory external`` it is the loadable cached unit: no texture data, the
Wishbone port (``bus_*``) and the AXI4 read master (``axi_*``), and the register map with the base
registers (``INDEX_BASE``, ``RAW_BASE``) and no index or raw regions; its ``--testbench`` loads the
set over the bus, places its image in cocotbext-axi's RAM where the base registers say, and reloads
it elsewhere in the same simulation (docs/verification.md).

The loadable unit (``--unit loadable``) holds no texture data: its Verilog is the geometry's (the
named one, or the smallest that holds FILE), and beside it go its register map, ``OUT.regs.md``,
and the C header a CPU driver includes, ``OUT.h`` (:mod:`golden.register_map`).

Writes the Verilog of the texel-fetch unit holding that file's memories (see
:mod:`sim.backends.verilog`) and, beside it, ``OUT.vlt``: the Verilator configuration file that
waives the five rules Yosys's output trips (:data:`LINT_WAIVERS`, explained in docs/usage.md), so
``verilator --lint-only -Wall OUT.vlt OUT.v`` is clean in the user's own flow. Both files appear
together or not at all. ``--lint`` also runs
``verilator --lint-only -Wall`` with the project's documented waivers (docs/simulation.md) and fails
(exit 2) on any remaining warning.
"""

from __future__ import annotations

import os
import re
import subprocess
import tempfile

from .common import (Outputs, add_hardware_options, add_index_banks, add_json, add_memory_options, add_tag_width,
                     add_unit, emit, load_set, memory_config, unit_geometry, with_default)

__all__ = ["add_parser", "cmd_export", "lint_verilog", "waiver_path", "LINT_WAIVERS", "ExportError"]


class ExportError(OSError):
    """A user error of ``vqtex export`` (an ``OSError``, so the command line prints it as one line
    and exits 2)."""

#: Verilator lint waivers for the exported Verilog; each is explained in docs/simulation.md.
LINT_WAIVERS = """`verilator_config
// The module is named by --name, the file by -o: they need not agree.
lint_off -rule DECLFILENAME
// Amaranth keeps named aliases of struct fields and whole intermediate results of which only some
// bits are used (e.g. the low byte of a widened sum); Yosys writes them all out.
lint_off -rule UNUSEDSIGNAL
// Yosys writes arithmetic whose operands are narrower than the result and relies on Verilog's
// context-determined widths (zero or sign extension); that is the intended meaning.
lint_off -rule WIDTH
// A memory of one word has a zero-width address; Yosys declares it as [-1:0] (only bit 0 is used,
// and it is always 0).
lint_off -rule LITENDIAN
// Yosys writes a multiplexer of several cases as a function whose inputs are named a, b and s; a
// signal of the design with one of those names (the index width b) is hidden inside the function
// only, where it is not used.
lint_off -rule VARHIDDEN
"""


def waiver_path(output: str) -> str:
    """The waiver file written beside the exported Verilog: ``OUT.vlt`` for ``OUT.v`` or ``OUT.sv``."""
    return os.path.splitext(output)[0] + ".vlt"


def lint_verilog(path: str, top: str) -> list:
    """``verilator --lint-only -Wall`` with :data:`LINT_WAIVERS`; returns the warning lines."""
    from vqtex.sim.backends.toolchain import find_tool
    verilator = find_tool("verilator")
    with tempfile.TemporaryDirectory() as tmp:
        vlt = os.path.join(tmp, "waivers.vlt")
        with open(vlt, "w") as f:
            f.write(LINT_WAIVERS)
        res = subprocess.run([verilator, "--lint-only", "-Wall", "--top-module", top, vlt, path],
                             capture_output=True, text=True)
    lines = [ln for ln in (res.stderr + res.stdout).splitlines() if ln.startswith("%")]
    if res.returncode != 0 and not lines:
        lines = [(res.stderr or res.stdout or "verilator failed").strip().splitlines()[0]]
    return [ln for ln in lines if not ln.startswith("%Error: Exiting due to")]


def cmd_export(args) -> int:
    if args.name is None:
        args.name = "texel_fetch" if args.filter_lanes is None else "texture_filter"
    if args.filter_lanes is None and args.index_banks is not None:
        raise ExportError("--index-banks is how the texture filter's lanes hold the index memory: it needs "
                          "--filter-lanes")
    if args.filter_lanes is not None and args.unit not in (None, "loadable" if args.memory == "external" else None):
        raise ExportError("--filter-lanes builds specialised texel-fetch lanes; --unit applies to the texel-fetch "
                          "unit alone (and --unit loadable to the filter through memory, --memory external)")
    if args.filter_lanes is not None and args.memory == "external" and args.index_banks is not None:
        raise ExportError("--index-banks: the filter through memory reads through a cache per lane (no index memory "
                          "to bank)")
    args.unit = args.unit or "specialised"
    args.index_banks = args.index_banks or "parity"
    if args.filter_lanes is not None and (args.one_port or args.dialect != "sv"):
        raise ExportError("--filter-lanes: the texture filter is exported as SystemVerilog with two-bank lanes "
                          "(no --one-port, no --dialect v2005)")
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", args.name):
        raise ExportError(f"--name {args.name!r} is not a Verilog identifier")
    if args.file is None and args.unit != "loadable":
        raise ExportError("FILE.vqt is required (only --unit loadable --geometry NAME exports without one)")
    if args.testbench is not None and args.filter_lanes is not None:
        raise ExportError("--testbench: the cocotb testbench is the texel-fetch unit's; --filter-lanes exports the "
                          "texture filter")
    if args.testbench is not None and args.file is None:
        raise ExportError("--testbench needs FILE.vqt: the texture set the bench loads and checks responses against")
    memory = _memory(args)
    with Outputs() as outs:
        out = outs.add(args.output, (".v", ".sv"), "Verilog")
        vlt = outs.add(waiver_path(args.output))
        regs = outs.add(register_map_paths(args.output)[0]) if args.unit == "loadable" else None
        header = outs.add(register_map_paths(args.output)[1]) if args.unit == "loadable" else None
        bench = None
        if args.testbench is not None:
            from vqtex.sim.testbench.write import FILES
            folder = outs.folder(args.testbench)
            bench = {name: outs.add(os.path.join(folder, name)) for name in FILES}
        text, ports, geometry, ts, latency = _export(args, out, memory)
        with open(outs.path(out), "w") as f:
            f.write(text)
        with open(outs.path(vlt), "w") as f:
            f.write(LINT_WAIVERS)
        if geometry is not None:
            from vqtex.golden.register_map import c_header, markdown
            with open(outs.path(regs), "w") as f:
                f.write(markdown(geometry, external=memory is not None))
            with open(outs.path(header), "w") as f:
                f.write(c_header(geometry, external=memory is not None))
        if bench is not None:
            from vqtex.sim.testbench.write import write_testbench
            write_testbench({name: outs.path(p) for name, p in bench.items()}, verilog=out, ts=ts,
                            top=args.name, unit="external" if memory is not None and geometry is None else args.unit,
                            tag_width=args.tag_width, latency=latency, geometry=geometry, folder=folder,
                            memory=memory)
    report = {"output": args.output, "lint_waivers": waiver_path(args.output), "module": args.name, "bytes": len(text.encode()),
              "one_port": bool(args.one_port), "unit": args.unit, "dialect": args.dialect, "tag_width": args.tag_width,
              "latency": latency, "ports": ports, "lint": "clean" if args.lint else "not run",
              "top": "texel fetch" if args.filter_lanes is None else f"texture filter, {args.filter_lanes} lane(s)"}
    if args.filter_lanes is not None and memory is None:
        report["index_banks"] = args.index_banks
    if memory is not None:
        from vqtex.sim.testbench.write import memory_dict
        report["memory"] = memory_dict(memory)
    also = ""
    if geometry is not None:
        from vqtex.golden.register_map import RegisterMap
        report.update(geometry=geometry.to_dict(), register_map=register_map_paths(args.output)[0],
                      c_header=register_map_paths(args.output)[1],
                      bus_addr_bits=RegisterMap(geometry, external=memory is not None).addr_bits)
        also = f", its register map {register_map_paths(args.output)[0]} and C header {register_map_paths(args.output)[1]}"
    if bench is not None:
        report["testbench"] = {name: p for name, p in bench.items()}
        also += f"; its cocotb testbench in {args.testbench} (python {bench['run_tb.py']})"
    emit(report, args.json, f"wrote {args.output} (module {args.name}, {len(ports)} ports, "
                             f"latency {latency}{' when every reference hits' if memory else ''}, "
                             f"{len(text.encode())} bytes"
                             f"{', lint clean' if args.lint else ''}), its Verilator lint waivers "
                             f"{waiver_path(args.output)}{also}")
    return 0


def register_map_paths(output: str) -> tuple:
    """The loadable unit's register map and C header written beside ``OUT.v``: ``OUT.regs.md``, ``OUT.h``."""
    stem = os.path.splitext(output)[0]
    return stem + ".regs.md", stem + ".h"


def _memory(args):
    """``--memory external``'s MemoryConfig (None on chip); what the cached unit cannot be refused."""
    for timing in ("memory_latency", "memory_bandwidth", "memory_model", "dram_part", "dram_clock", "controller_cycles"):
        if getattr(args, timing) is not None:
            raise ExportError(f"--{timing.replace('_', '-')}: the memory's timing is not part of the exported "
                              "unit (whatever answers its AXI master is the memory)")
    memory = memory_config(args)                    # a CliError (one line, exit 2) if refused
    if memory is None:
        return None
    if args.one_port or args.unit == "full" or args.dialect != "sv":
        raise ExportError("--memory external exports the cached unit or, with --filter-lanes, the filter through "
                          "memory: specialised or loadable, two index banks, SystemVerilog (no --one-port, --unit "
                          "full or --dialect v2005)")
    return memory


def _export(args, out, memory=None):
    """The Verilog text, its ports, the loadable unit's geometry (None for the baked units), the
    texture set (None without FILE) and the latency (with ``memory``: when every reference hits);
    linted when ``--lint`` (an ExportError on a warning)."""
    from vqtex.golden.format import FormatError
    from vqtex.sim.backends.verilog import export_verilog
    ts = None
    if args.file is not None:
        ts = load_set(args.file)
        try:
            ts.validate()
        except FormatError as e:
            raise ExportError(f"{args.file}: {e}") from None
    geometry = unit_geometry(args, ts, args.file)
    if geometry is not None and args.filter_lanes is not None and memory is None:
        raise ExportError("--filter-lanes exports the baked texture filter on chip; --unit loadable is the texel-fetch "
                          "unit, or with --memory external the filter through memory")
    ports = {}
    if memory is not None and args.filter_lanes is not None:
        from vqtex.hw.memory.filter import LATENCY as latency
        from vqtex.sim.backends.verilog import export_cached_filter_verilog
        text = export_cached_filter_verilog(ts, memory, lanes=args.filter_lanes, tag_width=args.tag_width,
                                            name=args.name, geometry=geometry, ports=ports)
    elif memory is not None:
        from vqtex.sim.backends.verilog import export_cached_verilog
        text, top = export_cached_verilog(ts, memory, tag_width=args.tag_width, name=args.name, ports=ports,
                                          geometry=geometry)
        latency = top.unit.latency
    elif args.filter_lanes is not None:
        from vqtex.hw.filter import LATENCY as latency
        from vqtex.sim.backends.verilog import export_filter_verilog
        text, top = export_filter_verilog(ts, lanes=args.filter_lanes, tag_width=args.tag_width, name=args.name,
                                          index_banks=args.index_banks)
        ports.update({n: len(getattr(top, n)) for n in top.signature.members})
    else:
        from vqtex.hw.texel_fetch import LATENCY as latency
        text = export_verilog(ts, one_port=args.one_port, tag_width=args.tag_width, name=args.name,
                              dialect=args.dialect, ports=ports, specialise=args.unit == "specialised",
                              geometry=geometry)
    if args.lint:
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, os.path.basename(out))
            with open(path, "w") as f:
                f.write(text)
            warnings = lint_verilog(path, args.name)
        if warnings:
            raise ExportError(f"verilator lint: {len(warnings)} warning(s), first: {warnings[0]}")
    return text, ports, geometry, ts, latency


def add_parser(sub) -> None:
    e = sub.add_parser("export", help="Verilog of the texel-fetch unit holding a .vqt's memories, or of a "
                                      "loadable unit (and its register map)")
    e.add_argument("file", metavar="FILE.vqt", nargs="?", default=None,
                   help="a texture set written by vqtex encode or vqtex import, or a Dreamcast VQ texture (.dt); "
                        "optional with --unit loadable --geometry NAME")
    e.add_argument("-o", "--output", required=True, help="Verilog file to write (.v or .sv)")
    add_hardware_options(e, stall=False)
    add_unit(e)
    add_tag_width(e)
    e.add_argument("--name", default=None,
                   help=with_default("top module name", "texel_fetch, or texture_filter with --filter-lanes"))
    e.add_argument("--filter-lanes", type=int, choices=[1, 2, 4, 8], default=None,
                   help=with_default("export the texture filter (hw.filter, docs/filter.md) with this many "
                                     "texel-fetch lanes instead of the texel-fetch unit; with --memory external "
                                     "the filter through memory, a cache per lane (docs/memory.md), baked or "
                                     "--unit loadable", "the texel-fetch unit"))
    add_index_banks(e)
    add_memory_options(e)
    e.add_argument("--dialect", choices=["sv", "v2005"], default="sv",
                   help=with_default("sv: assign and always_ff (X-free in Icarus -g2012); v2005: plain Verilog", "sv"))
    e.add_argument("--testbench", metavar="DIR", default=None,
                   help=with_default("also write a cocotb testbench of the unit into DIR (created if new): "
                                     "tb_texel_fetch.py, run_tb.py (SIM=icarus|verilator), tb_config.json, tb_set.vqt; "
                                     "the scoreboard is vqtex.golden.fetch (docs/verification.md)", "none"))
    e.add_argument("--lint", action="store_true",
                   help="also run verilator --lint-only -Wall on it and fail on any warning (default off)")
    add_json(e)
    e.set_defaults(func=cmd_export)
