"""Banked ROM: a memory split into banks of at most 512 words, each read registered twice; read-only,
or loaded at run time through the unit's bus port (``load``: :mod:`hw.bus_port`).

An ECP5 DP16KD block RAM is 512 words deep at its widest (36 bits); Yosys builds a deeper memory from
several of them and puts a LUT multiplexer on their read data in the same cycle as the block RAM's
clock-to-out (4.26 ns of a 6.67 ns cycle at 150 MHz), and it does not use the block RAM's own output
register. ``BankedROM`` makes the banks explicit: one ``amaranth.lib.memory.Memory`` per 512 words
(``bank0``, ``bank1``, ...), each read port followed by a fabric register, and the bank number
delayed beside them, so that the bank select happens after a register. It is the hardware's internal
organisation only: the contents are the memory image word for word (word ``a`` is word
``a % 512`` of bank ``a // 512``), and a run-time loader finds each bank by its name.
"""

from __future__ import annotations

from amaranth import *
from amaranth.lib import data, memory, wiring
from amaranth.lib.wiring import In, Out
from amaranth.utils import ceil_log2

from .bus_port import DATA_WIDTH, LoadTarget, attach_memory, load_decode_banks, or_all
from .pick import pick

__all__ = ["BankedROM", "BANK_DEPTH", "LOADABLE_BANK_DEPTH", "LATENCY", "addr_bits"]

#: Words per bank: the depth of one DP16KD at its 36-bit width.
BANK_DEPTH = 512
#: Words per bank of a loadable memory: the depth of one DP16KD at its 18-bit width, as a true
#: dual-port block RAM (the pipeline reads on one port, the bus reads and writes on the other) is
#: at most 18 bits wide per port. 1024 x 18 holds what 512 x 36 does: the same block RAM count for
#: any memory of 512 words or more.
LOADABLE_BANK_DEPTH = 1024
#: Cycles from the address to the banks' data: the memory's read register, then a fabric register.
LATENCY = 2


def addr_bits(depth: int) -> int:
    """Bits of an address into ``depth`` words (at least 1)."""
    return max(1, ceil_log2(max(1, depth)))


class BankedROM(wiring.Component):
    """A ROM of ``len(init)`` words in banks of ``bank_depth`` words.

    Latency 2 (both registers advance when ``en`` is high): the memory's synchronous read register,
    then a fabric register per bank. Throughput: one read per cycle.

    Arguments
    ---------
    init : list of int
        The memory image (an empty image is one zero word).
    width : int
        Word width in bits.
    bank_depth : int
        Words per bank, a power of two (default ``BANK_DEPTH`` = 512; tests use small banks to
        exercise the bank select with small memories).
    depth : int, optional
        Words of the memory (default ``len(init)``; more: the rest start as zero).
    data_copies : int
        With ``n`` > 0, the banks' data registers (the fabric registers behind the block RAMs) are
        enabled by the ``n`` bits of ``en_data`` instead of ``en``, each by one bit for a share
        of ``n`` contiguous shares of their bits (the memories' reads and ``bank`` stay on
        ``en``): the caller gives copies of ``en`` (equal in every cycle), so that no one net is
        the clock enable of them all. Default 0: ``en`` only, no ``en_data``.
    load : hw.bus_port.LoadTarget, optional
        Loadable: where the memory sits in the register map; each bank gets a write port, and a
        bank wider than 32 bits is padded to whole bus words. A memory deeper than 512 words
        (``BANK_DEPTH``) is read by the bus on the same port, the block RAMs' second one
        (:func:`hw.bus_port.attach_memory` with ``own_port``: true dual port, at most 18 bits a port
        on an ECP5, so use ``LOADABLE_BANK_DEPTH``), and the pipeline's read address has no
        multiplexer; a shallower one shares the pipeline's read port with the bus's reads.

    Members
    -------
    addr : In(bits(len(init) - 1))
        Word address.
    en : In(1)
        Pipeline advance: read enable of the memories and enable of every register.
    en_data : In(data_copies)
        Only with ``data_copies``: copies of ``en``, the enables of the data registers' shares.
    data : Out(ArrayLayout(width, banks))
        Each bank's word at ``addr % bank_depth``, registered twice.
    bank : Out(max(1, bits(banks - 1)))
        ``addr // bank_depth``, registered twice (beside ``data``; constant 0 for a single bank).
    word : Out(width)
        Combinational: ``data[bank]``, the word at ``addr``.
    load : In(load.layout), load_data : Out(32)
        Only when loadable: the bus port's load command, and this memory's read answer.

    Raises
    ------
    TypeError
        If ``width`` or ``bank_depth`` is not a positive integer.
    ValueError
        If ``bank_depth`` is not a power of two.
    """

    def __new__(cls, init=(), *, width: int, bank_depth: int = BANK_DEPTH, **kwargs):
        # Parameters are checked before the instance exists, so a rejected one is never created
        # (and never reported by Amaranth as an elaboratable that was not used).
        for name, v in (("width", width), ("bank_depth", bank_depth)):
            if not isinstance(v, int) or v < 1:
                raise TypeError(f"{name} must be a positive integer, not {v!r}")
        if bank_depth & (bank_depth - 1):
            raise ValueError(f"bank depth {bank_depth} is not a power of two")
        return super().__new__(cls, init, width=width, bank_depth=bank_depth, **kwargs)

    def __init__(self, init=(), *, width: int, bank_depth: int = BANK_DEPTH, depth: int | None = None,
                 load: LoadTarget | None = None, data_copies: int = 0):
        self._init = [int(v) for v in init] or [0]
        self._depth = max(1, len(self._init) if depth is None else int(depth))
        if len(self._init) > self._depth:
            raise ValueError(f"{len(self._init)} words of contents do not fit a memory of {self._depth}")
        self._width = width
        self._bank_depth = bank_depth
        self._banks = -(-self._depth // bank_depth)
        self._load = load
        self._data_copies = int(data_copies)
        members = {
            "addr": In(addr_bits(self._depth)),
            "en": In(1),
            "data": Out(data.ArrayLayout(width, self._banks)),
            "bank": Out(unsigned(addr_bits(self._banks))),
            "word": Out(width),
        }
        if load is not None:
            members.update(load=In(load.layout), load_data=Out(DATA_WIDTH))
        if self._data_copies:
            members["en_data"] = In(self._data_copies)
        super().__init__(members)

    @property
    def banks(self) -> int:
        return self._banks

    @property
    def depth(self) -> int:
        return self._depth

    @property
    def latency(self) -> int:
        return LATENCY

    def elaborate(self, platform):
        m = Module()
        d = self._bank_depth
        offset_bits = (d - 1).bit_length() if self._banks > 1 else len(self.addr)
        data = []
        answers = []
        load = self._load
        # A loadable bank of more than 32 bits is written 32 bits at a time: its width is padded to
        # whole bus words (the padding is never read by the pipeline).
        stored = self._width if load is None or self._width <= DATA_WIDTH else -(-self._width // DATA_WIDTH) * DATA_WIDTH
        # A loadable memory deeper than one 36-bit DP16KD (512 words) gives the bus the block RAMs'
        # second port (true dual port, 18 bits per port: no more block RAMs from 1024 words a bank);
        # a shallower one shares the pipeline's read port with the bus's reads (a multiplexer on
        # the read address), which keeps it in one 512 x 36 block RAM per 36 bits instead of two.
        own_port = load is not None and self._depth > BANK_DEPTH
        if load is not None:                # the command decoded per bank, into registers of each bank's own
            decoded = load_decode_banks(m, self.load, region=load.region, lanes=load.lanes, stride=load.stride,
                                        phase=load.phase, depth=self._depth, bank_depth=d, name="load",
                                        write_lanes=stored // DATA_WIDTH if stored > DATA_WIDTH else 0)
        for k in range(self._banks):
            part = self._init[k * d:(k + 1) * d]
            depth = min(d, self._depth - k * d) if load is not None or self._depth > len(self._init) else len(part)
            if load is None:
                # A read-only bank is as deep as its read address reaches (every address decodes,
                # the rows past the contents zero; as hw.descriptor's table): a simulator then
                # reads it with one indexed load, not a bounds check, a branch on the address that
                # mispredicts on random addresses (Verilator: the last, partial bank of the index
                # and raw memories; docs/simulation.md). Same block RAMs.
                depth = 1 << ceil_log2(max(1, depth))
            # (a loadable bank: a read in the cycle of a write may read anything, so that Yosys can
            # put the bus's read and write on one port of the block RAM: hw.bus_port.attach_memory)
            m.submodules[f"bank{k}"] = mem = memory.Memory(shape=stored, depth=depth, init=part,
                                                           attrs={"no_rw_check": 1} if own_port else {})
            # The fabric register behind the block RAM (stored bits); a bus read comes through the
            # block RAM's second port and a register of its own (hw.bus_port.attach_memory).
            if load is not None:
                command, row, lane, write_en = decoded[k]
                rd, answer = attach_memory(m, mem, command, hit=C(1, 1), row=row[:offset_bits], lane=lane,
                                           name=f"bank{k}_load", read_addr=self.addr[:offset_bits], read_en=self.en,
                                           own_port=own_port, write_en=write_en)
                answers.append(answer)
            else:
                rd = mem.read_port(domain="sync")
                m.d.comb += [rd.addr.eq(self.addr[:offset_bits]), rd.en.eq(self.en)]
            q = Signal(stored, name=f"data{k}")
            if self._data_copies:           # each share of the bits on its own copy of ``en``
                # (one assignment of a concatenation of the shares' multiplexers: a conditional
                # assignment per slice made CXXRTL 15 % slower on ``paper``, docs/loadable.md)
                n, total = self._data_copies, self._banks * stored
                parts = []
                for s in range(n):
                    lo = max(s * total // n, k * stored) - k * stored
                    hi = min((s + 1) * total // n, (k + 1) * stored) - k * stored
                    if lo < hi:
                        parts.append(Mux(self.en_data[s], rd.data[lo:hi], q[lo:hi]))
                m.d.sync += q.eq(Cat(*parts))
            else:
                with m.If(self.en):
                    m.d.sync += q.eq(rd.data)
            data.append(q if stored == self._width else q[:self._width])
        # A register of its own per bank, and ``data`` driven as one concatenation (pure wiring):
        # simulators (CXXRTL) then read each bank's register directly instead of assembling and
        # slicing one wide value every cycle.
        m.d.comb += self.data.eq(Cat(*data))
        if load is not None:
            m.d.comb += self.load_data.eq(or_all(answers))
        if self._banks == 1:
            m.d.comb += [self.word.eq(data[0]), self.bank.eq(0)]
            return m
        bank_r = Signal.like(self.bank, name="bank_r")
        with m.If(self.en):
            m.d.sync += [bank_r.eq(self.addr >> offset_bits), self.bank.eq(bank_r)]
        m.d.comb += self.word.eq(pick(data, self.bank))
        return m
