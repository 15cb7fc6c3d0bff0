"""A DDR3 SDRAM behind an in-order, open-page controller: banks, open rows, refresh.

The part
--------
:data:`MT41K256M16_125` is Micron's MT41K256M16 (4 Gb, 256M x 16, DDR3L) at speed grade -125
(DDR3-1600, CL 11): 8 banks of 32,768 rows of 1,024 columns of 16 bits (a 2 KB page), 512 MiB. Its
timings are the datasheet's (Micron, "4Gb: x4, x8, x16 DDR3L SDRAM", MT41K256M16, -125 column):
tCK 1.25 ns, CL 11 tCK, tRCD 13.75 ns, tRP 13.75 ns, tRAS 35 ns, tRC 48.75 ns, tRFC 260 ns (4 Gb),
tREFI 7.8 us (case temperature up to 85 C), tRRD max(4 tCK, 7.5 ns) and tFAW 40 ns (2 KB page),
tRTP max(4 tCK, 7.5 ns), tCCD 4 tCK, burst length 8. LiteDRAM's module table (litedram/modules.py,
class MT41J256M16, which MT41K256M16 subclasses; speed grade "1600") gives the same tRP, tRCD, tRAS
and tFAW, tRFC as 208 tCK (= 260 ns) and tREFI as 64 ms / 8192 = 7.8125 us; its tRRD is
max(4 tCK, 10 ns), ours the x16 part's 7.5 ns (2 cycles at 200 MHz either way). CL, tRC, tRRD and tRTP
are the datasheet's as given here, not cross-checked against a second source.

The controller
--------------
It runs at ``clock_mhz`` (the unit's clock; default 200 MHz: LiteDRAM's DDR3 PHYs at rate 1:4 run the
controller at a quarter of the 800 MHz DRAM clock of DDR3-1600). Every timing is converted to
controller cycles as ``ceil(max(n_tCK * tCK, t_ns) / period)``. The x16 DDR bus moves 4 bytes per
DRAM clock, ``dram_bytes_per_clock`` per controller clock (16 at 200 MHz); an AXI beat of
``bus_bytes`` takes ``beat_interval = ceil(bus_bytes / dram_bytes_per_clock)`` cycles (at least 1).

Addresses map row-bank-column (LiteDRAM's default): byte address ``a`` is column ``(a / 2) mod
1024``, bank ``(a / 2048) mod 8``, row ``a / 16384``. A burst (one cache line, never crossing 4 KB,
so never a page) is one row access.

Bursts are served one after the other in issue order (one AXI ID: responses in order), open page:

1. ``start = max(t, previous burst's column command + 1)``: the controller turns to this burst.
2. Refresh: every refresh that fell due (at ``k * tREFI``, k >= 1) by ``start`` is done first, at
   ``max(due, previous column command + 1)``: precharge every open bank (after its ``tRAS`` from
   activation and ``tRTP`` from its last read), ``tRP``, then ``REF`` for ``tRFC``; every bank is
   then closed and ``start`` is at least the refresh's end.
3. The burst's bank: row open -> column command at ``start``. Bank closed -> ``ACT`` at ``start``.
   Another row open -> ``PRE`` at ``max(start, ACT + tRAS, last read + tRTP)``, ``ACT`` ``tRP``
   later. An ``ACT`` also waits ``tRC`` from the bank's previous ``ACT``, ``tRRD`` from any bank's,
   and ``tFAW`` from the fourth-last; the column command follows ``tRCD`` after it.
4. The column command waits until the previous burst's data has left (``beats * beat_interval``
   cycles after its column command). The first beat is ``CL + controller_cycles`` after it.

``controller_cycles`` (default 0) is the controller's and PHY's own pipeline, not a datasheet
figure: set it to the controller used (a real LiteDRAM or MIG adds several cycles). ``queued`` is the
wait for earlier bursts (step 1 and the data bus in step 4); everything else is latency.

Why a loop: each burst's timing depends on the bank state and refresh schedule that earlier bursts
left, and the times of those depend on their own predecessors, so ``reads`` serves bursts one at a
time in Python (a handful of integer operations each). Only cache misses reach the memory, so the
loop runs once per line fill, not per texel.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["DramPart", "MT41K256M16_125", "PARTS", "DramMemory"]


@dataclass(frozen=True)
class DramPart:
    """A DRAM part's geometry and timings (ns, or DRAM clocks where the datasheet gives both: the
    larger applies)."""
    name: str
    description: str
    data_rate: int          # transfers per second, millions (DDR3-1600: 1600)
    tck_ns: float
    width_bits: int         # data pins
    banks: int
    rows: int
    columns: int
    cl_ck: int
    trcd_ns: float
    trp_ns: float
    tras_ns: float
    trc_ns: float
    trfc_ns: float
    trefi_ns: float
    trrd: tuple             # (tCK, ns)
    tfaw_ns: float
    trtp: tuple             # (tCK, ns)
    tccd_ck: int
    source: str

    @property
    def page_bytes(self) -> int:
        return self.columns * self.width_bits // 8

    @property
    def bytes(self) -> int:
        return self.page_bytes * self.banks * self.rows


#: Micron MT41K256M16-125: 4 Gb DDR3L-1600, x16 (see the module docstring for the figures' sources).
MT41K256M16_125 = DramPart(
    name="MT41K256M16-125", description="Micron MT41K256M16 DDR3L-1600 CL11, 4 Gb x16 (512 MiB)",
    data_rate=1600, tck_ns=1.25, width_bits=16, banks=8, rows=32768, columns=1024,
    cl_ck=11, trcd_ns=13.75, trp_ns=13.75, tras_ns=35.0, trc_ns=48.75, trfc_ns=260.0, trefi_ns=7800.0,
    trrd=(4, 7.5), tfaw_ns=40.0, trtp=(4, 7.5), tccd_ck=4,
    source="Micron 4Gb DDR3L datasheet (MT41K256M16, -125); LiteDRAM modules.py MT41J256M16 '1600'")

#: The parts by name (``--dram-part``).
PARTS = {"MT41K256M16-125": MT41K256M16_125}


class DramMemory:
    """A :class:`DramPart` behind the in-order open-page controller of the module docstring; the
    read contract of :mod:`golden.memory.external`.

    Arguments
    ---------
    part : DramPart
    bus_bytes : int
        Bytes per AXI beat.
    clock_mhz : float
        The controller's (and unit's) clock.
    controller_cycles : int
        The controller's own latency from column command to the first beat, beyond CL.
    """

    def __init__(self, part: DramPart = MT41K256M16_125, *, bus_bytes: int = 16, clock_mhz: float = 200.0,
                 controller_cycles: int = 0):
        if not isinstance(part, DramPart):
            raise TypeError(f"part must be a DramPart, not {type(part).__name__}")
        if not (isinstance(clock_mhz, (int, float)) and 0 < clock_mhz <= 1e4):
            raise ValueError(f"controller clock {clock_mhz!r} MHz must be positive")
        if not isinstance(controller_cycles, int) or controller_cycles < 0:
            raise ValueError(f"controller latency must be a non-negative number of cycles, not {controller_cycles!r}")
        if not isinstance(bus_bytes, int) or bus_bytes < 1:
            raise ValueError(f"bus width must be a positive number of bytes, not {bus_bytes!r}")
        self.part, self.bus_bytes, self.clock_mhz = part, bus_bytes, float(clock_mhz)
        self.controller_cycles = controller_cycles
        period = 1000.0 / self.clock_mhz

        def cycles(ns=0.0, ck=0):
            return max(1, math.ceil(max(ck * part.tck_ns, ns) / period - 1e-9))

        self.timings = {
            "CL": cycles(ck=part.cl_ck), "tRCD": cycles(part.trcd_ns), "tRP": cycles(part.trp_ns),
            "tRAS": cycles(part.tras_ns), "tRC": cycles(part.trc_ns), "tRFC": cycles(part.trfc_ns),
            "tREFI": math.floor(part.trefi_ns / period), "tRRD": cycles(part.trrd[1], part.trrd[0]),
            "tFAW": cycles(part.tfaw_ns), "tRTP": cycles(part.trtp[1], part.trtp[0]),
        }
        # Bytes the DRAM's data pins move per controller clock (two transfers per tCK).
        self.dram_bytes_per_clock = 2 * part.width_bits / 8 * period / part.tck_ns
        self.beat_interval = max(1, math.ceil(bus_bytes / self.dram_bytes_per_clock - 1e-9))
        self.reset()

    def describe(self) -> str:
        t = self.timings
        return (f"{self.part.description} at {self.clock_mhz:g} MHz: CL {t['CL']}, tRCD {t['tRCD']}, "
                f"tRP {t['tRP']}, tRAS {t['tRAS']}, tRFC {t['tRFC']}, tREFI {t['tREFI']} cycles, "
                f"{self.bus_bytes}-byte beats every {self.beat_interval} cycle(s)")

    def reset(self):
        banks = self.part.banks
        never = -(1 << 40)
        self._open = [-1] * banks          # open row per bank, -1 closed
        self._act = [never] * banks        # last ACT per bank
        self._read = [never] * banks       # last column read per bank
        self._acts = [never] * 4           # the last four ACTs (tFAW)
        self._next_cmd = 0                 # the controller turns to the next burst from here
        self._data_free = 0                # the next column command's earliest cycle (data bus)
        self._next_ref = self.timings["tREFI"]
        self.queued = 0
        self.refreshes = 0
        self.row_hits = self.row_misses = self.row_conflicts = 0

    def locate(self, address: int):
        """(bank, row, column) of a byte address (row-bank-column).

        Raises ValueError beyond the part."""
        p = self.part
        if not 0 <= address < p.bytes:
            raise ValueError(f"address {address:#x} is beyond the {p.name}'s {p.bytes >> 20} MiB")
        col = (address // (p.width_bits // 8)) % p.columns
        bank = (address // p.page_bytes) % p.banks
        row = address // (p.page_bytes * p.banks)
        return bank, row, col

    def read(self, t: int, address: int, beats: int) -> int:
        """The first beat's cycle of one burst accepted in cycle ``t`` (issue order)."""
        T = self.timings
        bank, row, _ = self.locate(int(address))
        t = int(t)
        start = max(t, self._next_cmd)
        queued = start - t
        while self._next_ref <= start:              # refreshes that fell due: done before this burst
            at = max(self._next_ref, self._next_cmd)
            opened = [b for b in range(len(self._open)) if self._open[b] >= 0]
            if opened:
                at = max([at] + [self._act[b] + T["tRAS"] for b in opened]
                         + [self._read[b] + T["tRTP"] for b in opened]) + T["tRP"]
            done = at + T["tRFC"]
            self._open = [-1] * len(self._open)
            self.refreshes += 1
            self._next_ref += T["tREFI"]
            start = max(start, done)
        if self._open[bank] == row:
            column = start
            self.row_hits += 1
        else:
            act = start
            if self._open[bank] >= 0:
                act = max(start, self._act[bank] + T["tRAS"], self._read[bank] + T["tRTP"]) + T["tRP"]
                self.row_conflicts += 1
            else:
                self.row_misses += 1
            act = max(act, self._act[bank] + T["tRC"], max(self._acts) + T["tRRD"], self._acts[0] + T["tFAW"])
            self._acts = self._acts[1:] + [act]
            self._act[bank] = act
            self._open[bank] = row
            column = act + T["tRCD"]
        if column < self._data_free:
            queued += self._data_free - column
            column = self._data_free
        data = int(beats) * self.beat_interval
        self._data_free = column + data
        self._read[bank] = column + data - 1
        self._next_cmd = column + 1
        self.queued = queued
        return column + T["CL"] + self.controller_cycles

    def reads(self, t, address, beats) -> np.ndarray:
        """``read`` over sequences, one burst at a time (see the module docstring for why)."""
        return np.array([self.read(a, b, c) for a, b, c in
                         zip(np.asarray(t).tolist(), np.asarray(address).tolist(), np.asarray(beats).tolist())],
                        np.int64)
