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
read, so answers come in order. A read's path is registered at every step, so that it is never the
unit's critical path (150 MHz on the ECP5-8): the command (``t + 1``), each memory's decoded copy
of it (``t + 2``, :func:`load_decode`), the memory's read (``t + 3``), a fabric register of the read
data (``t + 4``: a block RAM's clock-to-output leaves no time for logic behind it), the lane select
and the answer register (``t + 5``: ``load_data``), then the OR of every answer into ``dat_r``
(``t + 6``). A write reaches the memories in ``t + 2`` (they hold it from ``t + 3``), before any
request can follow it (the drain rule's ``pause`` falls in ``t + 3`` at the earliest). ``err``
answers (one cycle after acceptance) an address the geometry does not map and a write to a
read-only register.
"""

from __future__ import annotations

from dataclasses import dataclass

from amaranth import *
from amaranth.lib import data, memory, wiring
from amaranth.lib.wiring import In, Out

from vqtex.golden.geometry import Geometry
from vqtex.golden.register_map import (CONTROL, REGION_BITS, REGIONS, RegisterMap, geometry_words)

from .pick import pick, pick_group

__all__ = ["wishbone_signature", "load_layout", "BusPort", "LoadTarget", "load_decode", "load_decode_banks",
           "attach_memory", "or_all",
           "READ_LATENCY", "ANSWER_LATENCY", "delayed",
           "DATA_WIDTH"]

#: Bus data width.
DATA_WIDTH = 32
#: Cycles from a read's acceptance to its ``ack`` and ``dat_r``.
READ_LATENCY = 6
#: Cycles from a read's acceptance to its answer on ``load_data`` (one register before ``dat_r``).
ANSWER_LATENCY = READ_LATENCY - 1
#: A memory of more 32-bit lanes than this (``max``'s 84-lane codebook) picks a read's lane over two
#: cycles (:func:`attach_memory`): its group of ``LANE_GROUP`` lanes into registers, then the lane.
SPLIT_LANES = 32
#: Lanes per group of a split lane pick (a power of two).
LANE_GROUP = 4


def or_all(values):
    """The OR of ``values``: the read answers of a unit's memories (each 0 unless addressed) as one
    answer, or masked constants; a 32-bit 0 for none."""
    values = list(values)
    out = values[0] if values else C(0, DATA_WIDTH)
    for v in values[1:]:
        out = out | v
    return out


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
    external : bool
        The loadable cached unit's map (``RegisterMap(geometry, external=True)``: no index or raw
        words, the base registers); the unit answers the base registers' reads on ``load_data``.

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

    def __init__(self, geometry: Geometry, external: bool = False):
        if not isinstance(geometry, Geometry):
            raise TypeError(f"geometry must be a Geometry, not {type(geometry).__name__}")
        self._geometry = geometry
        self._map = RegisterMap(geometry, external)
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
        ctrl_ok = Cat(*((offset == off) & (~we | C(int("w" in acc), 1))
                        for off, acc, _ in rmap.control.values())).any()
        lane_bits = (rmap.entry_lanes - 1).bit_length()
        lane_ok = offset[:lane_bits] < rmap.used_entry_lanes if lane_bits else C(1, 1)
        def below(n):                       # (an empty region: no compare, which lint calls constant)
            return offset < n if n else C(0, 1)

        return {
            REGIONS["control"]: ctrl_ok,
            REGIONS["descriptors"]: below(words["descriptors"]),
            REGIONS["index"]: below(words["index"]),
            REGIONS["codebook"]: below(words["codebook"]) & lane_ok,
            REGIONS["raw"]: below(words["raw"]),
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
        # (one assignment of the whole register: field by field, CXXRTL would assemble it with
        # read-modify-writes every cycle)
        m.d.sync += self.load.eq(Cat(accept & bus.we & bus.sel & mapped, accept & ~bus.we & mapped, region, offset,
                                     bus.dat_w))
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
        # (an OR of masked constants, not a case statement: Yosys would make that a ROM, which
        # simulators then read every cycle)
        own = Signal(DATA_WIDTH, name="own_data")
        values = geometry_words(self._geometry)
        mine = self.load.read & (self.load.region == REGIONS["control"])
        m.d.sync += own.eq(or_all(Mux(mine & (self.load.offset == CONTROL[name][0]), C(value, DATA_WIDTH), 0)
                               for name, value in values.items()))
        own = delayed(m, own, ANSWER_LATENCY - 2, name="own_data")
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


def _entries(load, *, region: int, lanes: int, stride: int, phase: int) -> tuple:
    """The load command's address in a memory's terms (:func:`load_decode`): ``(cond, row,
    lane_bits, stride_bits)``, where ``cond`` is high when the command's region is ``region`` and
    its entry ``e`` has ``e % stride == phase``, ``row`` is ``e // stride`` (no depth check): the
    offset's bits from ``lane_bits + stride_bits`` up, below them the entry's phase and the bus word
    in the entry. Combinational."""
    lane_bits = (lanes - 1).bit_length()
    stride_bits = (stride - 1).bit_length()
    entry = load.offset[lane_bits:]
    cond = load.region == region
    if stride > 1:
        cond &= entry[:stride_bits] == phase
    return cond, entry[stride_bits:], lane_bits, stride_bits


def load_decode(m, load, *, region: int, lanes: int = 1, stride: int = 1, phase: int = 0, depth: int,
                name: str) -> tuple:
    """Which word of a memory of ``depth`` words the load command addresses, decoded once for all
    of that memory's banks and registered: ``(hit, row, lane, command)``, one cycle after ``load``
    (``command`` is ``load`` registered beside them: a memory takes its write data and its read and
    write strobes from it). Entry ``e`` of ``region`` spans bus words ``e * lanes .. e * lanes +
    lanes - 1``; the memory holds the entries with ``e % stride == phase`` (even and odd index
    banks), entry ``e`` in row ``e // stride``; ``hit`` is high when the command's region is
    ``region`` and its entry is one of them, ``lane`` is the bus word in the entry.

    The register is each memory's own copy of the command, next to it: the compare and the fan-out
    to the memory's address and enable inputs start from flip-flops (150 MHz on the ECP5-8)."""
    cond, rows, lane_bits, stride_bits = _entries(load, region=region, lanes=lanes, stride=stride, phase=phase)
    row = Signal(max(1, len(rows)), name=f"{name}_row")
    hit = Signal(name=f"{name}_hit")
    command = Signal.like(load, name=f"{name}_command")
    m.d.sync += [hit.eq(cond & (rows < depth)), row.eq(rows), command.eq(load)]
    lane = Value.cast(command.offset)[:lane_bits] if lane_bits else C(0, 1)
    return hit, row, lane, command


def load_decode_banks(m, load, *, region: int, lanes: int = 1, stride: int = 1, phase: int = 0, depth: int,
                      bank_depth: int, write_lanes: int = 0, name: str) -> list:
    """:func:`load_decode` per bank of ``bank_depth`` rows (a :class:`hw.banked_rom.BankedROM`'s),
    each bank's decode a register of its own, one cycle after ``load`` as :func:`load_decode`'s:
    a list of ``(command, row, lane, write_en)`` per bank, where ``command``'s ``write`` and ``read``
    are high only when the command addresses a row of this bank (``hit`` is then 1: pass
    ``hit=C(1, 1)`` to :func:`attach_memory`), ``row`` is the row in the bank, and ``write_en``
    (``write_lanes`` > 0, a memory wider than the bus) is the registered one-hot of the 32-bit lane
    written (``write_lanes`` bits; else None). The command's other fields are loaded only when the
    bank is addressed, so that the copies differ (Yosys keeps a register per bank): each bank's
    write enables, bus address and write data start at flip-flops beside it, with no compare or
    fan-out across the chip in the cycle before the block RAM (``fetch.back``'s critical path at
    132.8 MHz, docs/area.md "Block by block")."""
    cond, rows, lane_bits, stride_bits = _entries(load, region=region, lanes=lanes, stride=stride, phase=phase)
    offset_bits = (bank_depth - 1).bit_length()
    banks = -(-depth // bank_depth)
    out = []
    for k in range(banks):
        cond_k = cond & (rows < depth) if k == banks - 1 else cond
        if banks > 1:
            cond_k &= rows[offset_bits:] == k
        strobes = Signal(2, name=f"{name}{k}_strobes")
        rest = Signal(len(Value.cast(load)) - 2, name=f"{name}{k}_command")
        m.d.sync += strobes.eq(Cat(load.write & cond_k, load.read & cond_k))
        with m.If(cond_k):
            m.d.sync += rest.eq(Value.cast(load)[2:])
        command = load.shape()(Cat(strobes, rest))
        row = Value.cast(command.offset)[lane_bits + stride_bits:]
        row = Cat(row, C(0, max(0, offset_bits - len(row))))[:max(1, offset_bits)] if banks > 1 else row
        lane = Value.cast(command.offset)[:lane_bits] if lane_bits else C(0, 1)
        write_en = None
        if write_lanes:
            write_en = Signal(write_lanes, name=f"{name}{k}_write_lanes")
            now = load.offset[:lane_bits] if lane_bits else C(0, 1)
            m.d.sync += write_en.eq(Mux(load.write & cond_k, 1 << now, 0))
        out.append((command, row, lane, write_en))
    return out


def delayed(m, value, cycles: int, *, name: str):
    """``value`` through ``cycles`` registers (a read answer brought to ``ANSWER_LATENCY``)."""
    for n in range(cycles):
        r = Signal.like(value, name=f"{name}_d{n + 1}")
        m.d.sync += r.eq(value)
        value = r
    return value


@dataclass(frozen=True)
class _ReadData:
    """The pipeline's read data of :func:`attach_memory` with ``own_port`` (a register)."""
    data: Value


def attach_memory(m, mem: memory.Memory, load, *, hit, row, lane, only_lane: int | None = None, pack=None,
                  unpack=None, name: str, read_addr, read_en, data_r=None, own_port: bool = False,
                  data_en=None, write_en=None):
    """Give ``mem`` (an ``amaranth.lib.memory.Memory``, not yet elaborated) a write port for the load
    command ``load``, and its one read port, shared: the pipeline reads at ``read_addr`` when
    ``read_en``; a bus read takes the port in the cycle of its command (the pipeline is empty then:
    the drain rule), so the memory has two ports, as a true dual-port block RAM does. ``hit``,
    ``row`` and ``lane`` say whether the command addresses this memory, which row, which 32-bit
    lane of it (:func:`load_decode`, then narrowed to a bank by the caller). Returns
    ``(read_port, answer)``: the read port (the pipeline takes ``read_port.data``) and the memory's
    read answer (32 bits, registered, 0 unless this memory was addressed by the read
    ``ANSWER_LATENCY`` cycles after its acceptance).

    The read data goes through a fabric register before the lane select: ``data_r``, a register
    the caller already has for the pipeline (:class:`hw.banked_rom.BankedROM`'s per-bank data
    register, as wide as the memory), which this function makes load the read data in the cycle
    after a bus read as well; without ``data_r``, a register of its own.

    With ``only_lane=None`` a row is the entry's lanes side by side (width ``32 * lanes`` or less,
    written 32 bits at a time); with ``only_lane=k`` the memory holds lane ``k`` of each entry only
    (``pack(bus_word)`` gives the row, ``unpack(row)`` the bus word; default: the low bits).

    With ``own_port`` the bus reads through a read port of its own at the write port's address
    (``row``), which Yosys merges with the write port into one read-write port: the block RAM's
    second port (an ECP5 DP16KD in true dual-port mode, 1024 x 18 bits). The pipeline's read port
    then takes ``read_addr`` with no multiplexer in front of the block RAM's address (the loadable
    unit's critical path at 134.6 MHz, docs/area.md), and the bus's read data has a fabric register
    of its own (``data_r`` is not used). Same timing as the shared port. ``mem`` must then carry
    the attribute ``no_rw_check`` (a read in the cycle of a write to the same word may read
    anything: the drain rule keeps the pipeline's reads and the bus's writes apart, and the bus
    reads only in cycles without a write), and the pipeline's port is an asynchronous read port
    followed by a register enabled by ``read_en`` (returned as ``read_port.data``): Yosys merges
    that register into the block RAM and, with the attribute, may share port B between the bus's
    read and write. With a synchronous port Amaranth states the read-during-write result (the old
    word) and Yosys keeps two copies of the memory instead.
   
    With ``data_en`` (a memory in LUTs: the loadable descriptor table) the read takes two stages:
    the read address is registered here, in a register of this memory's own (its copy of the
    address: loaded with ``read_addr`` when ``read_en``, with the bus's row in the cycle of a bus
    read), the memory is read asynchronously from it (the LUT RAMs' read and the multiplexer
    between them) and the data registered when ``data_en`` (the next stage's enable) or in the
    cycle after a bus read: ``read_port.data`` is that register, two cycles after ``read_addr``.
    No net of the caller's fans out to the LUT RAMs' addresses, and the bus's read data is the
    same register (no ``data_r``). The bus's answer keeps its timing. Not with ``own_port`` or
    ``data_r``.

    A memory of more than ``SPLIT_LANES`` lanes picks the read's lane over two cycles: the
    ``LANE_GROUP`` lanes of its group registered (each 0 unless this memory was addressed), then
    the lane among them, combinational: ``answer`` is then a pick of registers, with the same
    timing (the OR of the unit's answers into ``dat_r`` follows it).

    With ``write_en`` (a memory wider than the bus: :func:`load_decode_banks`'s registered one-hot
    of the lane written) the write port's lane enables are ``write_en`` itself, not decoded here.
    """
    width = Shape.cast(mem.shape).width
    mine = Signal(name=f"{name}_mine")
    m.d.comb += mine.eq(hit & (lane == only_lane) if only_lane is not None else hit)
    wide = only_lane is None and width > DATA_WIDTH
    if wide:
        wp = mem.write_port(granularity=DATA_WIDTH)
        m.d.comb += [wp.addr.eq(row), wp.data.eq(load.data.replicate(width // DATA_WIDTH)),
                     wp.en.eq(Mux(load.write & mine, 1 << lane, 0) if write_en is None else write_en)]
    else:
        wp = mem.write_port()
        m.d.comb += [wp.addr.eq(row), wp.en.eq(load.write & mine)]
        m.d.comb += wp.data.eq(pack(load.data) if pack is not None else load.data[:width])
    if data_en is not None and (own_port or data_r is not None):
        raise ValueError("a registered read address (data_en) takes neither own_port nor data_r")
    bus_read = Signal(name=f"{name}_bus_read")
    m.d.comb += bus_read.eq(load.read & mine)
    rp = mem.read_port(domain="comb" if data_en is not None else "sync")
    if data_en is not None:         # the address registered here, the read asynchronous, its data registered
        addr_r = Signal.like(rp.addr, name=f"{name}_read_addr")
        with m.If(read_en | bus_read):
            m.d.sync += addr_r.eq(Mux(bus_read, row, read_addr))
        m.d.comb += rp.addr.eq(addr_r)
        comb_data = rp.data
        data_r = Signal.like(comb_data, name=f"{name}_read_data")
        bp = rp = _ReadData(data_r)
    elif own_port:                    # the bus's read beside its write: the block RAM's second port
        bp = rp
        comb = mem.read_port(domain="comb")
        rp = _ReadData(Signal.like(comb.data, name=f"{name}_read_data"))
        m.d.comb += [bp.addr.eq(row), comb.addr.eq(read_addr)]
        with m.If(read_en):
            m.d.sync += rp.data.eq(comb.data)
        # (no reset: it is read only under hit_rr, and a register without a reset is one the block
        # RAM's output register can take, docs/area.md "--bram-outreg")
        data_r = Signal.like(bp.data, name=f"{name}_data_r", reset_less=True)
    else:
        bp = rp
        m.d.comb += [rp.addr.eq(Mux(bus_read, row, read_addr)), rp.en.eq(read_en | bus_read)]
    hit_r = Signal(name=f"{name}_hit_r")            # the read data is on the port
    hit_rr = Signal(name=f"{name}_hit_rr")          # ... and in data_r
    m.d.sync += [hit_r.eq(bus_read), hit_rr.eq(hit_r)]
    if data_en is not None:
        with m.If(data_en | hit_r):
            m.d.sync += data_r.eq(comb_data)
    elif own_port or data_r is None:
        # The bus's own data register loads the port's data in every cycle: it is read only under
        # ``hit_rr``, when it holds what the port read in the cycle of ``hit_r``. No enable: ``hit_r``
        # would otherwise be the clock enable of every bit of it (672 flip-flops a bank on
        # ``paper``'s codebook, 2,688 on ``max``'s, docs/area.md "The paths between blocks").
        if data_r is None:
            data_r = Signal.like(rp.data, name=f"{name}_data_r")
        m.d.sync += Value.cast(data_r).eq(bp.data)
    else:                               # the caller's register (the pipeline's): loaded on a bus read too
        with m.If(hit_r):
            m.d.sync += Value.cast(data_r).eq(bp.data)
    if wide:
        lane_r = Signal(len(lane), name=f"{name}_lane_r")
        lane_rr = Signal(len(lane), name=f"{name}_lane_rr")
        m.d.sync += [lane_r.eq(lane), lane_rr.eq(lane_r)]
        lanes = width // DATA_WIDTH
        if lanes > SPLIT_LANES:             # the lane's group registered, the lane in it after
            words = [Value.cast(data_r)[DATA_WIDTH * n:DATA_WIDTH * (n + 1)] for n in range(lanes)]
            fine = LANE_GROUP.bit_length() - 1
            lane_rrr = Signal(fine, name=f"{name}_lane_rrr")
            group = []
            for n, word in enumerate(pick_group(words, Cat(lane_rr, C(0, fine)), LANE_GROUP)):
                r = Signal(DATA_WIDTH, name=f"{name}_answer{n}")
                m.d.sync += r.eq(Mux(hit_rr, word, 0))
                group.append(r)
            m.d.sync += lane_rrr.eq(Cat(lane_rr, C(0, fine))[:fine])
            return rp, pick(group, lane_rrr)
        word = Value.cast(data_r).word_select(lane_rr, DATA_WIDTH)
    else:
        word = unpack(data_r) if unpack is not None else Value.cast(data_r)
    answer = Signal(DATA_WIDTH, name=f"{name}_answer")
    m.d.sync += answer.eq(Mux(hit_rr, word, 0))
    return rp, answer
