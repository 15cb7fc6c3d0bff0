"""The loadable unit's bus slave port: Wishbone B4 pipelined, as amaranth-soc defines it.

amaranth-soc is not on the package index, so its Wishbone signature is written here
(:func:`wishbone_signature`), with amaranth-soc's member names and directions (seen from the
initiator): ``adr``, ``dat_w``, ``sel``, ``cyc``, ``stb``, ``we`` out; ``dat_r``, ``ack``, ``err``,
``stall`` in. Data is 32 bits, ``adr`` a word address, granularity 32 (``sel`` is one bit; a write
with ``sel`` low changes nothing and is acknowledged).

:class:`BusPort` decodes the register map of :mod:`golden.register_map` and turns each transfer
into one *load command* (:func:`load_layout`), a register that every memory of the unit and the
colour matrix watch (:func:`attach_memory`). The rule that keeps requests and loads apart (the
*drain rule*):

* while ``cyc`` is high (seen one cycle later: ``pause`` is a flip-flop) the unit accepts no
  texel request (``i.ready`` low);
* a transfer is accepted (``stall`` low) only when no request is in flight (``idle``: every valid
  bit of the pipeline, skid register included, is 0), so a write never changes a memory under a
  request, and a read sees every earlier write;
* so the host's transfers wait for the responses in flight to leave: a host that never takes the
  responses (``o.ready`` low for ever) waits for ever.

Timing: a write accepted in cycle ``t`` is acknowledged (or refused with ``err``) in cycle
``t + 1`` and is in the memory from cycle ``t + 2``; writes go back to back. A read accepted in
cycle ``t`` is answered in cycle ``t + READ_LATENCY`` with ``dat_r``; the port stalls during a
read, so answers come in order. ``err`` answers (one cycle after acceptance) an address the
geometry does not map and a write to a read-only register.
"""

from __future__ import annotations

from dataclasses import dataclass

from amaranth import *
from amaranth.lib import data, memory, wiring
from amaranth.lib.wiring import In, Out

from vqtex.golden.geometry import Geometry
from vqtex.golden.register_map import (CONTROL, REGION_BITS, REGIONS, RegisterMap, geometry_words)

__all__ = ["wishbone_signature", "load_layout", "BusPort", "LoadTarget", "attach_memory", "READ_LATENCY",
           "DATA_WIDTH"]

#: Bus data width.
DATA_WIDTH = 32
#: Cycles from a read's acceptance to its ``ack`` and ``dat_r``.
READ_LATENCY = 3


def wishbone_signature(addr_width: int) -> wiring.Signature:
    """amaranth-soc's ``wishbone.Signature(addr_width=addr_width, data_width=32, granularity=32,
    features={"err", "stall"})``, member for member (seen from the initiator)."""
    return wiring.Signature({
        "adr": Out(addr_width), "dat_w": Out(DATA_WIDTH), "dat_r": In(DATA_WIDTH), "sel": Out(1),
        "cyc": Out(1), "stb": Out(1), "we": Out(1), "ack": In(1), "err": In(1), "stall": In(1),
    })


def load_layout(rmap: RegisterMap) -> data.StructLayout:
    """The load command: ``write`` or ``read`` (each high for one cycle), the ``region`` and the word
    ``offset`` inside it, and the write ``data``."""
    return data.StructLayout({"write": 1, "read": 1, "region": REGION_BITS, "offset": rmap.offset_bits,
                              "data": DATA_WIDTH})


class BusPort(wiring.Component):
    """Wishbone slave -> load commands, with the drain rule (see the module docstring).

    Arguments
    ---------
    geometry : Geometry

    Members
    -------
    bus : In(wishbone_signature(RegisterMap(geometry).addr_bits))
        The slave port.
    idle : In(1)
        No texel request is in flight.
    pause : Out(1)
        A flip-flop: the host holds a bus cycle; the unit must not accept requests.
    load : Out(load_layout(...))
        The command of the transfer accepted in the previous cycle (registered).
    load_data : In(32)
        The OR of the memories' read answers (each 0 unless addressed), ``READ_LATENCY - 1``
        cycles after a read's acceptance.
    """

    def __init__(self, geometry: Geometry):
        if not isinstance(geometry, Geometry):
            raise TypeError(f"geometry must be a Geometry, not {type(geometry).__name__}")
        self._geometry = geometry
        self._map = RegisterMap(geometry)
        super().__init__({
            "bus": In(wishbone_signature(self._map.addr_bits)),
            "idle": In(1),
            "pause": Out(1),
            "load": Out(load_layout(self._map)),
            "load_data": In(DATA_WIDTH),
        })

    @property
    def register_map(self) -> RegisterMap:
        return self._map

    def _mapped(self, region, offset, we) -> dict:
        """Region code -> combinational: the address answers with ack (else err)."""
        rmap = self._map
        words = rmap.region_words()
        ctrl_ok = Cat(*((offset == off) & (~we | C(int("w" in acc), 1)) for off, acc, _ in CONTROL.values())).any()
        lane_ok = (offset & (rmap.entry_lanes - 1)) < rmap.used_entry_lanes
        return {
            REGIONS["control"]: ctrl_ok,
            REGIONS["descriptors"]: offset < words["descriptors"],
            REGIONS["index"]: offset < words["index"],
            REGIONS["codebook"]: (offset < words["codebook"]) & lane_ok,
            REGIONS["raw"]: offset < words["raw"],
        }

    def elaborate(self, platform):
        m = Module()
        bus = self.bus
        rmap = self._map
        ob = rmap.offset_bits
        region = bus.adr[ob:]
        offset = bus.adr[:ob]

        reading = Signal(READ_LATENCY - 1, name="reading")   # a read in flight, one bit per cycle
        m.d.sync += self.pause.eq(bus.cyc)
        accept = Signal()
        m.d.comb += [
            bus.stall.eq(~(self.pause & self.idle) | reading.any()),
            accept.eq(bus.cyc & bus.stb & ~bus.stall),
        ]
        cases = self._mapped(region, offset, bus.we)
        mapped = Signal()
        with m.Switch(region):
            for code, ok in cases.items():
                with m.Case(code):
                    m.d.comb += mapped.eq(ok)
            with m.Default():
                m.d.comb += mapped.eq(0)

        # The command register: one cycle per accepted transfer.
        m.d.sync += [
            self.load.write.eq(accept & bus.we & bus.sel & mapped),
            self.load.read.eq(accept & ~bus.we & mapped),
            self.load.region.eq(region),
            self.load.offset.eq(offset),
            self.load.data.eq(bus.dat_w),
        ]
        # Answers: a write (or any refused transfer) in the next cycle, a read READ_LATENCY later.
        ack_write = Signal()
        err = Signal()
        m.d.sync += [
            ack_write.eq(accept & bus.we & mapped),
            err.eq(accept & ~mapped),
            reading.eq(Cat(accept & ~bus.we & mapped, reading[:-1])),
        ]
        # The read-only control registers (ID, version, geometry) answer here; everything else
        # through ``load_data``.
        own = Signal(DATA_WIDTH, name="own_data")
        values = geometry_words(self._geometry)
        with m.If(self.load.read & (self.load.region == REGIONS["control"])):
            with m.Switch(self.load.offset):
                for name, value in values.items():
                    with m.Case(CONTROL[name][0]):
                        m.d.sync += own.eq(value)
                with m.Default():
                    m.d.sync += own.eq(0)
        with m.Else():
            m.d.sync += own.eq(0)
        dat_r = Signal(DATA_WIDTH, name="dat_r_reg")
        ack_read = Signal()
        m.d.sync += [dat_r.eq(self.load_data | own), ack_read.eq(reading[-1])]
        m.d.comb += [
            bus.ack.eq(ack_write | ack_read),
            bus.err.eq(err),
            bus.dat_r.eq(dat_r),
        ]
        return m


@dataclass(frozen=True)
class LoadTarget:
    """Where a memory sits in the register map (see :func:`attach_memory`): the load command's
    ``layout``, the ``region`` code, bus words per entry (``lanes``), and which entries the memory
    holds (``stride``, ``phase``)."""
    layout: data.StructLayout
    region: int
    lanes: int = 1
    stride: int = 1
    phase: int = 0


def attach_memory(m, mem: memory.Memory, load, *, region: int, lanes: int = 1, lane: int | None = None,
                  stride: int = 1, phase: int = 0, first: int = 0, pack=None, unpack=None, name: str,
                  read_addr, read_en):
    """Give ``mem`` (an ``amaranth.lib.memory.Memory``, not yet elaborated) a write port for the load
    command ``load``, and its one read port, shared: the pipeline reads at ``read_addr`` when
    ``read_en``; a bus read takes the port in the cycle of its command (the pipeline is empty then:
    the drain rule), so the memory has two ports, as a true dual-port block RAM does. Returns
    ``(read_port, answer)``: the read port (the pipeline takes ``read_port.data``) and the memory's
    read answer (32 bits, 0 unless this memory was addressed by the read ``READ_LATENCY - 1`` cycles
    after its acceptance).

    Entry ``e`` of ``region`` spans bus words ``e * lanes .. e * lanes + lanes - 1``. The memory holds
    the entries ``e`` with ``e % stride == phase`` (even and odd index banks), from entry ``first``
    (banks of a banked memory) on: memory row ``(e - first) // stride``. With ``lane=None`` a row is
    the entry's lanes side by side (width ``32 * lanes`` or less, written 32 bits at a time); with
    ``lane=k`` the memory holds lane ``k`` of each entry only (``pack(bus_word)`` gives the row,
    ``unpack(row)`` the bus word; default: the low bits).
    """
    width = Shape.cast(mem.shape).width
    depth = mem.depth
    lane_bits = (lanes - 1).bit_length()
    entry = Signal(len(load.offset), name=f"{name}_entry")
    m.d.comb += entry.eq(load.offset >> lane_bits)
    rel = Signal(len(entry) + 1, name=f"{name}_rel")
    m.d.comb += rel.eq(entry - first if first else entry)
    stride_bits = (stride - 1).bit_length()
    row = Signal(range(max(2, depth)), name=f"{name}_row")
    m.d.comb += row.eq(rel >> stride_bits)
    lane_of = load.offset[:lane_bits] if lane_bits else C(0, 1)
    hit = Signal(name=f"{name}_hit")
    cond = (load.region == region) & ((rel >> stride_bits) < depth)
    if first:
        cond &= entry >= first
    if stride > 1:
        cond &= rel[:stride_bits] == phase
    if lane is not None:
        cond &= lane_of == lane
    m.d.comb += hit.eq(cond)

    wide = lane is None and width > DATA_WIDTH
    if wide:
        wp = mem.write_port(granularity=DATA_WIDTH)
        m.d.comb += [wp.addr.eq(row), wp.data.eq(load.data.replicate(width // DATA_WIDTH)),
                     wp.en.eq(Mux(load.write & hit, 1 << lane_of, 0))]
    else:
        wp = mem.write_port()
        m.d.comb += [wp.addr.eq(row), wp.en.eq(load.write & hit)]
        m.d.comb += wp.data.eq(pack(load.data) if pack is not None else load.data[:width])
    rp = mem.read_port(domain="sync")
    bus_read = Signal(name=f"{name}_bus_read")
    m.d.comb += [bus_read.eq(load.read & hit),
                 rp.addr.eq(Mux(bus_read, row, read_addr)), rp.en.eq(read_en | bus_read)]
    hit_r = Signal(name=f"{name}_hit_r")
    lane_r = Signal(max(1, lane_bits), name=f"{name}_lane_r")
    m.d.sync += [hit_r.eq(bus_read), lane_r.eq(lane_of)]
    if wide:
        word = Value.cast(rp.data).word_select(lane_r, DATA_WIDTH)
    else:
        word = unpack(rp.data) if unpack is not None else Value.cast(rp.data)
    answer = Signal(DATA_WIDTH, name=f"{name}_answer")
    m.d.comb += answer.eq(Mux(hit_r, word, 0))
    return rp, answer
