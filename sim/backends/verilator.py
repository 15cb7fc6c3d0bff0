"""The ``verilator`` backend: a unit's exported Verilog (``vqtex export``) simulated by Verilator.

It is the proof that the export is right: the very text :func:`sim.backends.verilog.export_verilog`
(the texel-fetch unit) or :func:`sim.backends.verilog.export_filter_verilog` (the texture filter)
writes, memories included (their ``initial`` blocks), is verilated (``--cc``), compiled with
:file:`sim/backends/drivers/verilator_driver.cc` into a shared library with the same batch C API as the
CXXRTL backend, and run through the same ctypes code (:class:`sim.backends.cxxrtl.BatchLibrary`), so
responses, cycles, stall counts, straddles and occupancy are comparable one for one. One build
function serves both units (:func:`build_design`, from the unit's
:class:`sim.backends.design.DesignInfo`); :func:`build_verilator`, :func:`open_verilator` and
:func:`run` are the texel-fetch unit's entry points. ``halves=True`` builds the baked texel-fetch
unit instead as its two halves, two models run by drivers/halves.h as the CXXRTL backend runs its
halves (measured, not the default: slower on one thread; docs/simulation.md).

Builds are cached (:mod:`sim.backends.toolchain`) by a hash of the Verilog, the driver sources, the Verilator
and compiler versions and the flags; Verilator's runtime (``verilated.cpp``) is compiled once per
Verilator version into its own cache entry and linked into every model.
"""

from __future__ import annotations

import os
import re
import time

from .cxxrtl import DRIVER_DIR, SHARED_DRIVER_SOURCES, Build, batch_header, driver_sources, open_design, run_unit
from .design import HALVES, DesignInfo, design_info
from .toolchain import (ToolchainError, cache_dir, cached_build, digest, find_cxx, find_tool, index_get, index_put,
                        run_tool, source_stamp, tool_version)

__all__ = ["run", "build_verilator", "build_design", "open_verilator", "build_library", "VERILATOR_FLAGS",
           "CXXFLAGS", "MODEL_OPT", "SLOW_OPT", "MODEL_CXXFLAGS", "CLANG_TUNING", "model_tuning_flags",
           "verilator_include_dir", "verilator_runtime",
           "model_sources", "harness_verilog", "top_ports", "HARNESS_NAME", "eval_header", "fast_eval"]

VERILATOR_FLAGS = ["--cc", "-O3", "--x-assign", "fast", "--x-initial", "fast",
                   "--noassert", "-Wno-fatal", "-Wno-lint", "-Wno-style"]
#: Verilator's runtime (verilated.cpp, verilated_threads.cpp), compiled once per Verilator and compiler.
CXXFLAGS = ["-std=c++17", "-O2", "-fPIC", "-DNDEBUG"]
#: The model's per-cycle ("fast") C++ is compiled in one translation unit with the driver, at -O3, so
#: that the compiler sees ``eval()`` and the clocked region beside the run loop of batch.h (measured
#: on the default unit, one run: the model and the driver as separate objects at -O2, Verilator's
#: makefile, 105-112 ns a cycle; one unit at -O2 103-109; one unit at -O3 96-100: docs/simulation.md).
MODEL_OPT = "-O3"
#: The model's run-once ("slow") C++ holds the memories' initial blocks (one statement per word): at
#: -O2 g++ spends about two minutes on the default unit's, at -O0 seven seconds.
SLOW_OPT = "-O0"
#: clang++ options for the model's per-cycle C++ (``model.cc``), measured on the default unit
#: (thread CPU time a cycle, each against the build without it, alternated in one process;
#: docs/simulation.md, Verilator section): the clocked region inlined into the driver's run loop
#: (batch.h, through the driver's ``cycle``; clang's inliner otherwise keeps ``_nba_sequent``, some
#: 5 KB of code, a call, and the loop cannot keep the model's state in registers across the ports
#: it sets and reads), 83-85 -> 75-77 ns; and if-conversion of larger two-way selects (the bank and
#: word selects Verilator writes as nested ``?:`` and ``if``: branches on random bits otherwise),
#: 70-71 -> 68-69.5 ns. LLVM's own options (``-mllvm``): :func:`model_tuning_flags` probes them and
#: drops them if the compiler refuses them. g++ gets the inlining from the driver's ``flatten``
#: attribute (recursive in GCC).
CLANG_TUNING = ["-mllvm", "-inline-threshold=100000", "-mllvm", "-phi-node-folding-threshold=40",
                "-mllvm", "-two-entry-phi-node-folding-threshold=40"]
#: What Verilator's makefile (verilated.mk) defines for a model without coverage, SystemC or tracing,
#: and the warnings it silences in generated code; hidden symbols, so that the model's functions bind
#: inside the library (no calls through the PLT).
MODEL_CXXFLAGS = ["-fvisibility=hidden", "-DVERILATOR=1", "-DVM_COVERAGE=0", "-DVM_SC=0", "-DVM_TIMING=0", "-DVM_TRACE=0",
                 "-DVM_TRACE_FST=0", "-DVM_TRACE_VCD=0", "-faligned-new", "-Wno-bool-operation",
                 "-Wno-sign-compare", "-Wno-uninitialized", "-Wno-unused-but-set-variable",
                 "-Wno-unused-parameter", "-Wno-unused-variable", "-Wno-shadow"]


_tuning: dict = {}


def model_tuning_flags(cxx: str) -> list:
    """``CLANG_TUNING`` for a clang++ that accepts it (probed once per compiler: an empty
    translation unit compiled with them), else none (g++, or a clang without those options)."""
    import subprocess
    if cxx not in _tuning:
        ok = "clang" in tool_version(cxx).lower()
        if ok:
            try:
                ok = subprocess.run([cxx, "-x", "c++", "-", "-c", "-o", os.devnull, *CLANG_TUNING], input="",
                                    capture_output=True, text=True, timeout=60).returncode == 0
            except (OSError, subprocess.SubprocessError):
                ok = False
        _tuning[cxx] = list(CLANG_TUNING) if ok else []
    return list(_tuning[cxx])


def verilator_include_dir(verilator: str) -> str:
    import subprocess
    root = None
    try:
        root = subprocess.run([verilator, "--getenv", "VERILATOR_ROOT"], capture_output=True, text=True,
                              timeout=30).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        pass
    for cand in ([os.path.join(root, "include")] if root else []) + ["/usr/share/verilator/include"]:
        if os.path.isfile(os.path.join(cand, "verilated.cpp")):
            return cand
    raise ToolchainError("Verilator's runtime sources (verilated.cpp) not found: reinstall verilator")


def _bits(off: int, width: int) -> str:
    """C++ of bits ``off .. off + width - 1`` (width <= 64) of the vq_payload ``p``."""
    w, sh = divmod(off, 64)
    x = f"(p.w[{w}] >> {sh})" if sh else f"p.w[{w}]"
    if sh and sh + width > 64:
        x = f"({x} | (p.w[{w + 1}] << {64 - sh}))"
    return f"({x} & {hex((1 << width) - 1)}ULL)" if width < 64 else x


def ports_header(info: DesignInfo, *, halves: bool = False) -> str:
    """``ports.h`` for verilator_driver.cc: batch.h's constants, the payload words spread over the
    request ports of the unit's Verilog top (one port per field, or the payload whole; a port wider
    than 64 bits is Verilator's array of 32-bit words) and the response gathered back. With
    ``halves``, the baked texel-fetch unit as its two models (``VQ_HALVES``): the request goes to
    the front end's ``i_payload`` whole, and ``VQ_O_TAG_OFFSET`` says where the front end's
    ``o_tag`` sits in ``o.payload`` (the back end's ``rgba`` is bits 0..31)."""
    request = [("i_payload", 0, info.request_width)] if halves else info.verilog_request
    sets = []
    for port, off, width in request:
        if width <= 64:
            sets.append(f"top->{port} = {_bits(off, width)};")
        else:
            sets += [f"top->{port}[{k}] = (uint32_t){_bits(off + 32 * k, min(32, width - 32 * k))};"
                     for k in range(-(-width // 32))]
    gets = " | ".join(f"((uint64_t)top->{port} << {off})" for port, off, _ in info.verilog_response)
    strobes = " ".join(f"c[VQ_C_STROBES + {k}] += top->{s};" for k, s in enumerate(info.strobes))
    lines = batch_header(info, "sim/backends/verilator.py")
    lines += [f"#define VQ_SET_REQUEST(top, p) {' '.join(sets)}", f"#define VQ_GET_RESPONSE(top) ({gets or '0'})",
              f"#define VQ_GET_VALID(top) uint32_t(top->{harness_port(info.valid)})",
              f"#define VQ_STROBES(top, c) {strobes}"]
    if halves:
        lines.append("#define VQ_HALVES 1")
        if info.tag_width:
            lines += ["#define VQ_O_TAG 1", f"#define VQ_O_TAG_OFFSET {info.response_fields['tag'][0]}"]
    if info.bus:                            # the loadable unit's Wishbone port (bus_* ports)
        lines.append("#define VQ_BUS 1")
    if info.axi_bytes:                      # the AXI4 read master's rdata from 32-bit words
        bits = 8 * info.axi_bytes
        if bits <= 32:
            rdata = "top->axi_rdata = w[0];"
        elif bits <= 64:
            rdata = "top->axi_rdata = uint64_t(w[0]) | (uint64_t(w[1]) << 32);"
        else:
            rdata = f"for (int k = 0; k < {bits // 32}; k++) top->axi_rdata[k] = w[k];"
        lines.append(f"#define VQ_AXI_SET_RDATA(top, w) {rdata}")
    return "\n".join(lines) + "\n"


def verilator_runtime(verilator: str, cxx: str, inc: str) -> str:
    """Folder holding Verilator's runtime objects (verilated.o, verilated_threads.o) for this
    Verilator and compiler, built once into the cache (shared by every Verilator model)."""
    key = digest("verilated-runtime", tool_version(verilator), tool_version(cxx), CXXFLAGS, inc)

    def build(folder):
        for src in ("verilated.cpp", "verilated_threads.cpp"):
            run_tool([cxx, *CXXFLAGS, "-I", inc, "-I", os.path.join(inc, "vltstd"), "-c",
                      os.path.join(inc, src), "-o", src.replace(".cpp", ".o")],
                     folder, "compiling Verilator's runtime", "build.log")
        open(os.path.join(folder, "done"), "w").close()
    path, _, _ = cached_build("verilator-runtime", key, build, "done")
    return os.path.dirname(path)


#: The module :func:`harness_verilog` wraps around a unit's exported top (the model's top module).
HARNESS_NAME = "vqtex_verilator_harness"
_PORT = re.compile(r"^\s*(input|output)\s+(?:wire\s+|reg\s+)?(?:signed\s+)?(?:\[(\d+):(\d+)\]\s*)?([A-Za-z_][A-Za-z0-9_$]*)\s*;",
                   re.M)


def top_ports(verilog: str, top_name: str) -> list[tuple[str, str, int]]:
    """(direction, name, width) of every port of module ``top_name`` in ``verilog`` (Yosys's
    ``write_verilog``: one ``input [h:l] name;`` declaration per port)."""
    m = re.search(rf"^module\s+{re.escape(top_name)}\s*\(", verilog, re.M)
    if not m:
        raise ToolchainError(f"module {top_name} not found in the exported Verilog")
    body = verilog[m.end():verilog.index("endmodule", m.end())]
    return [(d, name, abs(int(hi) - int(lo)) + 1 if hi else 1) for d, hi, lo, name in _PORT.findall(body)]


def harness_port(name: str) -> str:
    """The harness's name for a port of the unit: the same, with ``__`` as ``_`` (Verilator writes a
    ``__`` in a C++ name as ``___05F``; the halves' ports are Amaranth's ``i__valid``,
    ``i__payload``, ...; the exported tops have no such name)."""
    return name.replace("__", "_")


def harness_verilog(verilog: str, top_name: str) -> str:
    """A simulation-only wrapper around the unit's exported top ``top_name`` (which stays byte for
    byte what ``vqtex export`` writes): one clock edge per ``eval()`` of the Verilated model.

    Its input ``tick`` replaces ``clk``: each toggle of ``tick`` is one rising edge of the unit's
    clock (``clk = tick ^ phase``, and ``phase`` follows ``tick`` at that edge, so ``clk`` falls
    again within the same ``eval()``), and every output of the unit is captured at that edge into
    the harness's output of the same name: after ``eval()`` the driver reads what the outputs were
    in the cycle that edge ended (with that cycle's inputs), which is what a sample between a
    clock-low ``eval()`` and the rising edge read before. Verilator otherwise needs two ``eval()``
    per cycle (clock low, to settle the inputs and to see the clock fall; clock high), and the
    scheduling of each costs as much as a tenth of the default unit's cycle (docs/simulation.md,
    Verilator section). A port's name in the harness is :func:`harness_port`'s."""
    ports = top_ports(verilog, top_name)
    names = [n for _, n, _ in ports]
    if "clk" not in names:
        raise ToolchainError(f"module {top_name} has no clk port")
    if len({harness_port(n) for n in names}) != len(names):
        raise ToolchainError(f"module {top_name}: two ports with the same harness name")
    hp = harness_port

    def rng(width):
        return f"[{width - 1}:0] " if width > 1 else ""
    ins = [(n, w) for d, n, w in ports if d == "input" and n != "clk"]
    outs = [(n, w) for d, n, w in ports if d == "output"]
    lines = [f"// generated by sim/backends/verilator.py: the Verilator backend's harness around {top_name}",
             f"module {HARNESS_NAME}(tick, {', '.join(hp(n) for n in names if n != 'clk')});",
             "  input tick;"]
    lines += [f"  input {rng(w)}{hp(n)};" for n, w in ins]
    lines += [f"  output reg {rng(w)}{hp(n)};" for n, w in outs]
    lines += ["  reg phase = 1'b0;", "  wire clk = tick ^ phase;"]
    lines += [f"  wire {rng(w)}unit_{hp(n)};" for n, w in outs]
    conns = ["    .clk(clk)"] + [f"    .{n}({hp(n)})" for n, _ in ins] + [f"    .{n}(unit_{hp(n)})" for n, _ in outs]
    lines += [f"  {top_name} unit (", ",\n".join(conns), "  );", "  always_ff @(posedge clk) begin",
              "    phase <= tick;"]
    lines += [f"    {hp(n)} <= unit_{hp(n)};" for n, _ in outs]
    lines += ["  end", "endmodule", ""]
    return "\n".join(lines)


def model_sources(obj: str, prefix: str = "Vtop") -> tuple[list[str], list[str]]:
    """The C++ files Verilator wrote into ``obj`` for the model ``prefix``, as (fast, slow) by its own
    classification (``{prefix}_classes.mk``: ``VM_CLASSES_FAST``/``VM_SUPPORT_FAST`` run every cycle,
    ``VM_CLASSES_SLOW``/``VM_SUPPORT_SLOW`` once: construction, initial blocks, constant pool)."""
    lists = {"FAST": [], "SLOW": []}
    with open(os.path.join(obj, f"{prefix}_classes.mk")) as f:
        kind = None
        for line in f:
            words = line.replace("\\", " ").split()
            if len(words) >= 2 and words[1] == "+=" and words[0].startswith("VM_"):
                name = words[0]
                kind = ("FAST" if name in ("VM_CLASSES_FAST", "VM_SUPPORT_FAST") else
                        "SLOW" if name in ("VM_CLASSES_SLOW", "VM_SUPPORT_SLOW") else None)
                words = words[2:]
            elif not line.startswith(("\t", " ")):
                kind = None
                continue
            if kind:
                lists[kind] += [w + ".cpp" for w in words]
    if not lists["FAST"]:
        raise ToolchainError(f"Verilator wrote no model classes into {obj} ({prefix}_classes.mk)")
    return lists["FAST"], lists["SLOW"]


def eval_header(folder: str, prefixes, *, threads: int = 1) -> str:
    """``eval.h`` for verilator_driver.cc: ``VQ_EVAL(prefix, model, root)``, how a cycle evaluates the
    model ``V{prefix}`` (``root``: its ``rootp``) verilated into ``folder/obj_{prefix}``. A one-thread model whose generated C++
    defines the scheduler's evaluation function ``V{prefix}___024root___eval`` (what ``eval()``
    calls inside ``eval_step()``, Verilator 5) is evaluated by calling it on the root directly:
    ``eval_step()``'s bookkeeping around it (a thread-local mtask id, the queue of messages from
    other threads; the first call's initial blocks, which the driver's constructor still runs
    through ``eval()``) cost about 5 ns of the default unit's 90 ns cycle (docs/simulation.md,
    Verilator section). Otherwise (another Verilator's layout, ``--threads``) ``eval()``. One
    function of Verilator's internal naming; :func:`fast_eval` says which path a build took."""
    lines = ["// generated by sim/backends/verilator.py (eval_header)", "#define VQ_EVAL(prefix, model, root) VQ_EVAL_##prefix(model, root)"]
    for prefix in prefixes:
        root = f"V{prefix}___024root"
        obj = os.path.join(folder, f"obj_{prefix}")
        defined = re.compile(rf"^void {root}___eval\({root}\* vlSelf\) \{{$", re.M)
        fast, _ = model_sources(obj, prefix=f"V{prefix}")
        found = False
        for src in fast if threads == 1 else ():
            with open(os.path.join(obj, src)) as f:
                found = found or bool(defined.search(f.read()))
        if found:
            lines += [f"void {root}___eval({root}* vlSelf);   // (the model's, fast path)",
                      f"#define VQ_EVAL_{prefix}(model, root) {root}___eval(root)"]
        else:
            lines.append(f"#define VQ_EVAL_{prefix}(model, root) (model)->eval()")
    return "\n".join(lines) + "\n"


def fast_eval(library: str) -> dict:
    """{prefix: True when the Verilator library at ``library`` calls the model's evaluation function
    directly (:func:`eval_header`), False when it calls ``eval()``}."""
    with open(os.path.join(os.path.dirname(library), "eval.h")) as f:
        return {m.group(1): "___eval(root)" in m.group(2)
                for m in re.finditer(r"^#define VQ_EVAL_(\w+)\(model, root\) (.*)$", f.read(), re.M)}


def build_library(folder: str, models, header: str, *, verilator: str, cxx: str, inc: str, runtime: str,
                  what: str, extra_flags=()) -> dict:
    """In ``folder``: for each model ``(prefix, verilog, top_name)`` of ``models`` (the unit's export,
    prefix ``top``; or the texel-fetch unit's two halves, ``front`` and ``back``) write
    ``{prefix}.v`` and ``{prefix}_harness.v`` (:func:`harness_verilog` around its module
    ``top_name``) and verilate the harness into ``obj_{prefix}`` as class ``V{prefix}`` (C++ only,
    Verilator's makefile is not used); write ``ports.h`` and build ``libvq.so``: the models' run-once
    C++ at ``SLOW_OPT``, their per-cycle C++ and drivers/verilator_driver.cc as one translation unit
    (``model.cc``) at ``MODEL_OPT``, with ``eval.h`` (:func:`eval_header`), linked with Verilator's
    runtime. Returns the seconds of each step, ``{"verilate": s, "link": s}``."""
    import concurrent.futures
    with open(os.path.join(folder, "ports.h"), "w") as f:
        f.write(header)
    t = time.perf_counter()
    fast, slow, includes = [], [], []
    for prefix, verilog, top_name in models:
        with open(os.path.join(folder, f"{prefix}.v"), "w") as f:
            f.write(verilog)
        with open(os.path.join(folder, f"{prefix}_harness.v"), "w") as f:
            f.write(harness_verilog(verilog, top_name))
        obj = f"obj_{prefix}"
        run_tool([verilator, *VERILATOR_FLAGS, *extra_flags, "--prefix", f"V{prefix}", "--top-module", HARNESS_NAME,
                  "--Mdir", obj, f"{prefix}.v", f"{prefix}_harness.v"], folder, "Verilator", "build.log")
        f_, s_ = model_sources(os.path.join(folder, obj), prefix=f"V{prefix}")
        fast += f_
        slow += s_
        includes += ["-I", obj]
    t_verilate = time.perf_counter() - t
    threads = int(extra_flags[list(extra_flags).index("--threads") + 1]) if "--threads" in extra_flags else 1
    with open(os.path.join(folder, "eval.h"), "w") as f:
        f.write(eval_header(folder, [prefix for prefix, _, _ in models], threads=threads))
    for name, files in (("model.cc", fast), ("slow.cc", slow)):
        with open(os.path.join(folder, name), "w") as f:
            f.writelines(f'#include "{src}"\n' for src in files)
            if name == "model.cc":
                f.write(f'#include "{os.path.join(DRIVER_DIR, "verilator_driver.cc")}"\n')
    common = [cxx, *[f for f in CXXFLAGS if not f.startswith("-O")], *MODEL_CXXFLAGS, *includes, "-I", inc,
              "-I", os.path.join(inc, "vltstd"), "-I", DRIVER_DIR, "-I", folder]
    t = time.perf_counter()
    with concurrent.futures.ThreadPoolExecutor(2) as pool:     # the two compilers side by side
        slow_job = pool.submit(run_tool, [*common, SLOW_OPT, "-c", "slow.cc", "-o", "slow.o"], folder,
                               f"C++ compilation of {what} (run-once code)", "slow.log")
        run_tool([*common, MODEL_OPT, *model_tuning_flags(cxx), "-c", "model.cc", "-o", "model.o"], folder,
                 f"C++ compilation of {what}", "build.log")
        slow_job.result()
    run_tool([cxx, "-shared", "-fvisibility=hidden", "model.o", "slow.o",
              os.path.join(runtime, "verilated.o"), os.path.join(runtime, "verilated_threads.o"),
              "-pthread", "-o", "libvq.so"],
             folder, f"linking {what}", "build.log")
    return {"verilate": t_verilate, "link": time.perf_counter() - t}


def build_verilator(ts, *, one_port: bool = False, tag_width: int = 8, specialise: bool = True,
                    geometry=None, threads: int = 1, halves: bool = False) -> Build:
    """The Verilator library of the texel-fetch unit for ``ts`` (built or from the cache): the
    exported Verilog whole; with ``geometry``, of the loadable unit of that geometry (one build per
    geometry); with ``threads`` > 1, verilated with ``--threads`` (measured only:
    sim.bench.simulators.verilator_speed). ``halves=True``: the baked unit's two halves as two
    models, run as the CXXRTL backend runs them (:func:`build_design`)."""
    from .verilog import export_verilog
    t0 = time.perf_counter()
    info = design_info(ts, one_port=one_port, tag_width=tag_width, specialise=specialise, geometry=geometry)
    return build_design(info, lambda: export_verilog(ts, one_port=one_port, tag_width=tag_width,
                                                     specialise=specialise, geometry=geometry), elaborated=t0,
                        threads=threads, halves=halves)


def _verilog_file() -> str:
    from . import verilog
    return verilog.__file__


def build_design(info: DesignInfo, verilog, *, elaborated: float | None = None, threads: int = 1,
                 halves: bool = False) -> Build:
    """The Verilator library of any unit (built or from the cache): ``verilog()`` gives the unit's
    exported Verilog (module ``info.verilog_name``), called only when the library must be built;
    ``threads`` > 1: Verilator's multi-threaded model (``--threads``).

    ``halves=True`` (the baked texel-fetch unit only, ``info.halves``; not with ``threads``): its two
    halves, each verilated as a model of its own from the very fragment the export instantiates
    (:func:`sim.backends.verilog.export_half_verilog`, same Yosys script), run by drivers/halves.h
    as the CXXRTL backend runs its halves: the front end ahead in chunks, the back end replaying the
    recorded link, on one thread or (``BatchLibrary.set_threads(2)``, the default when the process
    may use two CPUs) on two. Same responses, cycles and counters as the whole unit. Not the
    default: on one thread it is slower than the whole export (each half's ``eval()`` has its own
    scheduling, about 10 ns, more than the smaller working sets save; docs/simulation.md, Verilator
    section). Default (``None``, ``False``): the exported Verilog whole, what ``vqtex export``
    writes."""
    verilator = find_tool("verilator")
    # The CXXRTL backend's compiler (clang++ when installed, else g++; $CXX overrides), so that the
    # two backends are compared with the same compiler; on the default unit clang++'s model is also
    # about 14% faster than g++'s (docs/simulation.md, Verilator section).
    cxx = find_cxx()
    halves = bool(halves)
    if halves and (not info.halves or threads > 1):
        raise ToolchainError(f"the {info.unit} unit has no halves to verilate apart" if not info.halves else
                             "Verilator's --threads runs the exported Verilog whole, not the halves")
    t0 = time.perf_counter() if elaborated is None else elaborated
    steps = {"elaborate": time.perf_counter() - t0}
    drivers = driver_sources("verilator_driver.cc", *SHARED_DRIVER_SOURCES)
    extra = ["--threads", str(threads)] if threads > 1 else []
    flags = VERILATOR_FLAGS + extra + CXXFLAGS + [MODEL_OPT, SLOW_OPT] + MODEL_CXXFLAGS + model_tuning_flags(cxx)
    this = b""
    for mod in (__file__, _verilog_file()):     # (ports_header is part of the build; so is the export)
        with open(os.path.abspath(mod), "rb") as f:
            this += f.read()
    quick = digest("verilator-quick", source_stamp(), this, info.unit, *info.options, flags,
                   tool_version(verilator), tool_version(cxx), *drivers, "halves" if halves else "whole")
    key = index_get("verilator", quick)
    root = os.path.join(cache_dir(), "verilator")
    if key and os.path.isfile(os.path.join(root, key, "libvq.so")):
        return Build(os.path.join(root, key, "libvq.so"), 0.0, True, info, key, steps)
    t1 = time.perf_counter()
    if halves:
        from .verilog import export_half_verilog
        models = [(half, export_half_verilog(info, half), "top") for half in HALVES]
    else:
        models = [("top", verilog(), info.verilog_name)]
    header = ports_header(info, halves=halves)
    steps["export"] = time.perf_counter() - t1
    key = digest("verilator", *[(p, text, harness_verilog(text, name)) for p, text, name in models], header,
                 *drivers, flags, tool_version(verilator), tool_version(cxx))
    inc = verilator_include_dir(verilator)
    t2 = time.perf_counter()
    runtime = verilator_runtime(verilator, cxx, inc)
    steps["runtime"] = time.perf_counter() - t2

    def build(folder):
        steps.update(build_library(folder, models, header, verilator=verilator, cxx=cxx, inc=inc, runtime=runtime,
                                   what=f"the Verilator model ({info.unit}{', halves' if halves else ''})",
                                   extra_flags=extra))
    lib, secs, cached = cached_build("verilator", key, build, "libvq.so")
    index_put("verilator", quick, key)
    return Build(lib, 0.0 if cached else time.perf_counter() - t0, cached, info, key, steps)


def open_verilator(ts, *, one_port: bool = False, tag_width: int = 8, specialise: bool = True, geometry=None,
                   threads: int = 1, halves: bool = False):
    """(BatchLibrary, DesignInfo, Build) of the texel-fetch unit's Verilator library (``halves``: as
    :func:`build_verilator`)."""
    return open_design(build_verilator(ts, one_port=one_port, tag_width=tag_width, specialise=specialise,
                                       geometry=geometry, threads=threads, halves=halves))


def run(ts, requests, *, stall: float = 0.0, seed: int = 0, one_port: bool = False, tag_width: int = 8,
        specialise: bool = True, geometry=None):
    """``sim.backends.interface.simulate(..., backend="verilator")``: the backend entry point (with
    ``geometry``: the loadable unit, ``ts`` loaded over its bus first)."""
    return run_unit(open_verilator, ts, requests, stall=stall, seed=seed, geometry=geometry, one_port=one_port,
                    tag_width=tag_width, specialise=specialise)
