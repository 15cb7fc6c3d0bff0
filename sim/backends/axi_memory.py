"""An AXI4 read slave for Amaranth's simulator, answering from a golden memory model.

:class:`AxiMemory` holds a memory image (bytes) and a model with the read contract of
:mod:`golden.memory.external` (``FixedMemory``, ``DramMemory``). Called once per cycle from a
testbench, before the clock edge, it accepts the AR offered in that cycle (``arready`` is always
high, as the model assumes; or low in the cycles an ``arready`` pattern says, for tests of the
master's side alone: the model then sees the AR at its handshake), asks the model for the first beat's cycle, and drives R with the
burst's beats at the cycles the model gives, data from the image. It checks the master's side of the
protocol as it goes: INCR bursts of the bus width, never crossing 4 KB, never past the image, and an
AR held by ``arready`` low keeps ``arvalid`` and its address and length until its handshake.
"""

from __future__ import annotations

__all__ = ["AxiMemory", "AxiError"]


class AxiError(AssertionError):
    """The master broke the AXI4 read protocol (or read outside the memory)."""


class AxiMemory:
    """See the module docstring. ``ar`` lists the cycles of every AR handshake, in order, and
    ``addresses`` their byte addresses."""

    def __init__(self, image: bytes, model, bus_bytes: int, arready=None):
        """``arready``: a sequence of bools, ``arready`` in cycle ``c`` (high past its end); default
        always high."""
        self.image, self.model, self.bus = image, model, bus_bytes
        self.arready = arready
        self._held = None               # (address, length) of an AR offered and not yet taken
        self.offered = []               # the cycles an AR was offered (``arvalid``), taken or not
        self.beats = []                 # scheduled R beats: (cycle, address, last), in order
        self.ar = []
        self.addresses = []             # the byte address of every burst, in order

    def start(self, ctx, axi):
        ctx.set(axi.arready, 1)

    def step(self, ctx, axi, cycle: int):
        """Drive R for ``cycle`` and take the AR offered in it (call before ``await ctx.tick()``)."""
        if self.beats and self.beats[0][0] == cycle:
            _, addr, last = self.beats.pop(0)
            ctx.set(axi.rvalid, 1)
            ctx.set(axi.rdata, int.from_bytes(self.image[addr: addr + self.bus], "little"))
            ctx.set(axi.rlast, int(last))
        else:
            ctx.set(axi.rvalid, 0)
            ctx.set(axi.rlast, 0)
        ready = self.arready is None or cycle >= len(self.arready) or bool(self.arready[cycle])
        if self.arready is not None:
            ctx.set(axi.arready, int(ready))
        if self._held is not None and (not ctx.get(axi.arvalid) or
                                       (ctx.get(axi.araddr), ctx.get(axi.arlen)) != self._held):
            raise AxiError(f"cycle {cycle}: an AR held by arready low changed or was withdrawn")
        self._held = None
        if ctx.get(axi.arvalid):
            self.offered.append(cycle)
        if ctx.get(axi.arvalid) and not ready:
            self._held = (ctx.get(axi.araddr), ctx.get(axi.arlen))
        elif ctx.get(axi.arvalid):
            addr = ctx.get(axi.araddr)
            n = ctx.get(axi.arlen) + 1
            if ctx.get(axi.arburst) != 1 or 1 << ctx.get(axi.arsize) != self.bus:
                raise AxiError(f"cycle {cycle}: only INCR bursts of {self.bus}-byte beats are served")
            if addr // 4096 != (addr + n * self.bus - 1) // 4096:
                raise AxiError(f"cycle {cycle}: burst at {addr:#x} of {n} beats crosses 4 KB")
            if addr % self.bus or addr + n * self.bus > len(self.image):
                raise AxiError(f"cycle {cycle}: burst at {addr:#x} of {n} beats outside the memory")
            first = self.model.read(cycle, addr, n)
            d = self.model.beat_interval
            if first <= cycle or (self.beats and first <= self.beats[-1][0]):
                raise AxiError(f"cycle {cycle}: the memory model answered out of order")
            self.beats += [(first + k * d, addr + k * self.bus, k == n - 1) for k in range(n)]
            self.ar.append(cycle)
            self.addresses.append(addr)
