"""The design the tools get: the unit in a harness of flip-flops (:class:`Harness`), its RTLIL, and
the shapes of its memories as Yosys names them."""

from __future__ import annotations

from amaranth import Module
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .target import HARNESS_NAME

__all__ = ["Harness", "design_rtlil", "design_memories"]


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
