"""The design the tools get: the unit in a harness of flip-flops (:class:`Harness`), its RTLIL, and
the shapes of its memories as Yosys names them."""

from __future__ import annotations

from amaranth import Module
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .target import HARNESS_NAME, UNIT_NAME

__all__ = ["Harness", "design_rtlil", "design_memories", "stage_names", "resolve_stage", "stage_rtlil",
           "StageError"]


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

    def rtlil(self) -> str:
        """The harness as RTLIL: top module ``vqtex_harness``, the unit ``vqtex_harness.unit``."""
        from amaranth.back import rtlil
        return rtlil.convert(self, name=HARNESS_NAME, emit_src=False)

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
    return Harness(ts, one_port=one_port, tag_width=tag_width, specialise=specialise).rtlil()


def design_memories(ts, *, one_port: bool = False, tag_width: int = 8, specialise: bool = True,
                    filter_lanes: int | None = None, index_banks: str = "parity", geometry=None,
                    memory=None) -> dict:
    """Every memory of ``TexelFetch(ts)`` -> ``(depth, width)``, named as Yosys names it inside the
    unit (``fetch.back.codebook_rom.codebook.bank0``, ``fetch.front.descriptor.table``): the banks of
    :class:`hw.banked_rom.BankedROM` are memories of their own. With ``filter_lanes``, those of
    ``TextureFilter(ts, lanes=filter_lanes)`` (``filter.lane0.back.codebook_rom.codebook.bank0``, ...).
    With ``memory``, those of ``CachedTexelFetch(ts, memory)`` (``unit.reader.index_tags0``,
    ``unit.texel.back.codebook_rom.codebook.bank0``, ...; with ``geometry`` too, the loadable one's); with
    ``memory`` and ``filter_lanes``, those of ``CachedTextureFilter`` (``unit.lane0_reader.index_tags0``,
    ``unit.lane0.back.codebook_rom.codebook.bank0``, ``unit.arbiter.ar_queue0``, ...)."""
    from vqtex.hw.memories import elaborate, memories
    if memory is not None and filter_lanes is not None:
        from vqtex.hw.memory.filter import CachedTextureFilter
        unit = {} if geometry is None else {"geometry": geometry, "loadable": True}
        top, prefix = CachedTextureFilter(None if geometry is not None else ts, memory, lanes=filter_lanes,
                                          tag_width=tag_width, **unit), "unit"
    elif memory is not None:
        from vqtex.hw.memory.unit import CachedTexelFetch
        unit = {} if geometry is None else {"geometry": geometry, "loadable": True}
        top, prefix = CachedTexelFetch(None if geometry is not None else ts, memory, tag_width=tag_width,
                                       **unit), "unit"
    elif filter_lanes is not None:
        from vqtex.hw.filter import TextureFilter
        top, prefix = TextureFilter(ts, lanes=filter_lanes, tag_width=tag_width, index_banks=index_banks), "filter"
    else:
        from vqtex.hw.texel_fetch import TexelFetch
        unit = {} if geometry is None else {"geometry": geometry, "loadable": True}
        top, prefix = TexelFetch(None if geometry is not None else ts, one_port=one_port, tag_width=tag_width,
                                 specialise=specialise, **unit), "fetch"
    return {".".join((prefix,) + mem.path): (mem.depth, mem.width) for mem in memories(elaborate(top))}


# ---------------------------------------------------------------------------------------------
# one block of the unit alone (``vqtex report area ... --stage NAME``)

class StageError(ValueError):
    """``--stage NAME`` names no block of the unit, or more than one. ``str()`` is one line."""


def _rtlil_modules(il: str) -> dict:
    """RTLIL text -> {module name (without the backslash): its text, the attribute lines before it
    included}, in order."""
    modules, pending, current, name = {}, [], None, None
    for line in il.splitlines(keepends=True):
        if current is None:
            if line.startswith("module "):
                name, current = line.split()[1].lstrip("\\"), pending + [line]
                pending = []
            elif line.startswith("attribute "):
                pending.append(line)
            continue
        current.append(line)
        if line.rstrip("\n") == "end":
            modules[name], current = "".join(current), None
    return modules


def _ports(module_text: str) -> list:
    """A module's ports in order: ``(name, width, "input"|"output")``."""
    ports = []
    for line in module_text.splitlines():
        f = line.split()
        if f and f[0] == "wire" and ("input" in f or "output" in f):
            width = int(f[f.index("width") + 1]) if "width" in f else 1
            way = "input" if "input" in f else "output"
            ports.append((int(f[f.index(way) + 1]), f[-1].lstrip("\\"), width, way))
    return [p[1:] for p in sorted(ports)]


def stage_names(il: str) -> list:
    """The blocks of the unit in ``il`` (RTLIL of :class:`Harness`) that ``--stage`` can take: every
    submodule of the unit, by its path inside the unit (``fetch.back.codebook_rom``)."""
    prefix = UNIT_NAME + "."
    return [n[len(prefix):] for n in _rtlil_modules(il) if n.startswith(prefix)]


def resolve_stage(il: str, stage: str) -> str:
    """``stage`` as a path inside the unit: the path itself, or a unique tail of one
    (``codebook_rom`` -> ``fetch.back.codebook_rom``). :class:`StageError` (one line, the blocks listed) if
    none or more than one matches."""
    names = stage_names(il)
    hits = [n for n in names if n == stage] or [n for n in names if n.endswith("." + stage)]
    if len(hits) != 1:
        what = "is ambiguous" if hits else "is not a block of this unit"
        raise StageError(f"--stage {stage!r} {what} (blocks: {', '.join(names)})")
    return hits[0]


#: User I/O pins of the target package (LFE5U-85F in CABGA381): a block with more port bits than
#: this gets the chain harness of :func:`stage_rtlil` instead of a pin per port bit.
PACKAGE_IOS = 205


def _slice(wire: str, lo: int, width: int) -> str:
    return f"{wire} [{lo}]" if width == 1 else f"{wire} [{lo + width - 1}:{lo}]"


def _dff(name: str, width: int, d: str, q: str) -> list:
    return [f"  cell $dff {name}\n", f"    parameter \\WIDTH {width}\n", "    parameter \\CLK_POLARITY 1\n",
            "    connect \\CLK \\clk\n", f"    connect \\D {d}\n", f"    connect \\Q {q}\n", "  end\n"]


def _pin_wrapper(ports: list) -> tuple:
    """The harness of a block whose port bits fit the package's pins: each port a pin of its own and
    a flip-flop between the pin and the block (none on ``clk`` and ``rst``). Returns what
    :func:`_chain_wrapper` does."""
    wrapper, cell, bits = [], [], 0
    for k, (name, width, way) in enumerate(ports):
        wrapper.append(f"  wire width {width} {way} {k} \\{name}\n")
        if name in ("clk", "rst"):
            cell.append(f"    connect \\{name} \\{name}\n")
            continue
        inner = f"\\{name}$q"
        wrapper.append(f"  wire width {width} {inner}\n")
        d, q = (f"\\{name}", inner) if way == "input" else (inner, f"\\{name}")
        wrapper += _dff(f"$port_ff{k}", width, d, q)
        cell.append(f"    connect \\{name} {inner}\n")
        bits += width
    return wrapper, cell, bits


def _chain_wrapper(ports: list) -> tuple:
    """The harness of a block with more port bits than the package has pins: its inputs the bits of
    one shift register fed from a pin ``si``, its outputs registered and XORed into one flip-flop on
    a pin ``so`` (every port bit still starts or ends at a flip-flop, none is a constant, none is
    optimised away). Returns ``(wrapper lines, cell connection lines, flip-flops added)``."""
    ins = [(n, w) for n, w, way in ports if way == "input" and n not in ("clk", "rst")]
    outs = [(n, w) for n, w, way in ports if way == "output"]
    n_in, n_out = sum(w for _, w in ins), sum(w for _, w in outs)
    names = [n for n, _, _ in ports if n in ("clk", "rst")]
    wrapper = [f"  wire width 1 input {k} \\{n}\n" for k, n in enumerate(names)]
    wrapper += [f"  wire width 1 input {len(names)} \\si\n", f"  wire width 1 output {len(names) + 1} \\so\n",
                f"  wire width {n_in} \\in_chain\n", f"  wire width {n_out} \\out_d\n",
                f"  wire width {n_out} \\out_q\n", "  wire width 1 \\so_d\n"]
    chain = "\\in_chain"
    shifted = "\\si" if n_in == 1 else f"{{ {_slice(chain, 0, n_in - 1)} \\si }}"
    wrapper += _dff("$in_chain", n_in, shifted, chain)
    wrapper += _dff("$out_regs", n_out, "\\out_d", "\\out_q")
    wrapper += ["  cell $reduce_xor $out_xor\n", "    parameter \\A_SIGNED 0\n", f"    parameter \\A_WIDTH {n_out}\n",
                "    parameter \\Y_WIDTH 1\n", "    connect \\A \\out_q\n", "    connect \\Y \\so_d\n", "  end\n"]
    wrapper += _dff("$so", 1, "\\so_d", "\\so")
    cell, pos = [f"    connect \\{n} \\{n}\n" for n in names], {"input": 0, "output": 0}
    for name, width, way in ports:
        if name in ("clk", "rst"):
            continue
        wire = chain if way == "input" else "\\out_d"
        cell.append(f"    connect \\{name} {_slice(wire, pos[way], width)}\n")
        pos[way] += width
    return wrapper, cell, n_in + n_out + 1


def stage_rtlil(il: str, stage: str) -> tuple:
    """One block of the unit alone, out of context: ``il`` (RTLIL of :class:`Harness`) cut down to
    the block at ``stage`` (:func:`resolve_stage`) and its submodules, the block renamed to the
    unit's module (``vqtex_harness.unit``, so that the flow counts it as it counts a unit) inside a
    new harness with a flip-flop on every port but ``clk`` and ``rst`` (as :class:`Harness` does for
    the unit): only the block's own paths count in Fmax. A block with more port bits than the
    package has pins (:data:`PACKAGE_IOS`; the cached unit's reader) takes its inputs from one
    shift chain and XORs its registered outputs into one pin instead (:func:`_chain_wrapper`). What the rest of the unit drives into the
    block (a constant included) becomes a free, registered input. Returns ``(rtlil, path,
    port_bits)``: the RTLIL, the block's path and the flip-flops the new harness adds."""
    path = resolve_stage(il, stage)
    old = f"{UNIT_NAME}.{path}"
    modules = _rtlil_modules(il)
    keep = {n: t for n, t in modules.items() if n == old or n.startswith(old + ".")}
    ports = _ports(keep[old])
    out = []
    for n, text in keep.items():            # the block becomes vqtex_harness.unit, its submodules under it
        out.append(text.replace(f"\\{old}", f"\\{UNIT_NAME}").replace("attribute \\top 1\n", ""))
    chain = sum(w for n, w, _ in ports if n not in ("clk", "rst")) > PACKAGE_IOS
    wrapper, connections, bits = (_chain_wrapper if chain else _pin_wrapper)(ports)
    wrapper = (["attribute \\top 1\n", f"module \\{HARNESS_NAME}\n"] + wrapper
               + [f"  cell \\{UNIT_NAME} \\unit\n"] + connections + ["  end\n", "end\n"])
    return "".join(out) + "".join(wrapper), path, bits
