"""What a memory read is, and a memory of fixed latency and bandwidth.

The read contract (AXI4, one ID, reads only)
--------------------------------------------
The master issues bursts on the AR channel; the memory accepts one in every cycle the master offers
one (``ARREADY`` high: the controller's command queue is not modelled as full). A burst is an INCR
burst of ``beats`` beats of ``bus_bytes`` bytes from a byte ``address`` aligned to the burst's size.
Its beats come back on R in order, bursts in the order they were issued (one AXI ID), the master
always ready (``RREADY`` high: it reserves room for a burst before issuing it). A memory answers a
burst accepted in cycle ``t`` with the cycle of its first beat, ``first >= t + 1``; beat ``k`` of
the burst is on R in cycle ``first + k * beat_interval``. Bursts are presented in issue order with
non-decreasing ``t``.

Every memory model is an object with the same three members:

- ``beat_interval``: cycles between two beats of R (1: a beat every cycle);
- ``read(t, address, beats) -> first``: one burst, in issue order (the state advances);
- ``reads(t, address, beats) -> first``: a whole sequence at once (numpy arrays), the same answers
  as calling ``read`` on each in order; and ``queued``, after ``read``, the cycles that burst waited
  behind earlier ones (the bandwidth share of its wait; the rest is the memory's latency).

``reset()`` forgets every burst (a new stream).
"""

from __future__ import annotations

import numpy as np

__all__ = ["FixedMemory", "beat_interval"]


def beat_interval(bus_bytes: int, bytes_per_clock: int) -> int:
    """Cycles per R beat of ``bus_bytes`` when the memory delivers ``bytes_per_clock``: 1 when it
    delivers at least a beat per clock, else ``bus_bytes / bytes_per_clock`` (which must divide).

    Raises ValueError if either is not a positive integer or the quotient is not whole."""
    for name, v in (("bus width", bus_bytes), ("bandwidth", bytes_per_clock)):
        if not isinstance(v, (int, np.integer)) or isinstance(v, bool) or v < 1:
            raise ValueError(f"{name} must be a positive number of bytes, not {v!r}")
    if bytes_per_clock >= bus_bytes:
        return 1
    if bus_bytes % bytes_per_clock:
        raise ValueError(f"bandwidth {bytes_per_clock} bytes/clock must divide the bus width {bus_bytes} bytes")
    return bus_bytes // bytes_per_clock


class FixedMemory:
    """A memory of fixed latency and bandwidth: an idealised SRAM or a controller seen from far away.

    Timing: a burst accepted in cycle ``t`` has its first beat in cycle ``t + latency`` unless the R
    channel is still busy with earlier bursts; beats are ``beat_interval`` cycles apart, in one
    stream over all bursts::

        first[k] = max(t[k] + latency, first[k-1] + beats[k-1] * beat_interval)

    so bursts overlap their latency with earlier bursts' data (a pipelined memory) and the R channel
    carries at most ``bytes_per_clock`` bytes per clock on average. ``queued`` is
    ``first - (t + latency)``.

    Arguments
    ---------
    latency : int
        Cycles from AR to the first R beat (>= 1).
    bytes_per_clock : int
        The memory's bandwidth; at most one beat per clock is delivered (see :func:`beat_interval`).
    bus_bytes : int
        Bytes per beat (the AXI data width).
    """

    def __init__(self, latency: int, bytes_per_clock: int, bus_bytes: int):
        if not isinstance(latency, (int, np.integer)) or isinstance(latency, bool) or latency < 1:
            raise ValueError(f"memory latency must be at least 1 cycle, not {latency!r}")
        self.latency = int(latency)
        self.bytes_per_clock = int(bytes_per_clock)
        self.bus_bytes = int(bus_bytes)
        self.beat_interval = beat_interval(bus_bytes, bytes_per_clock)
        self.reset()

    def describe(self) -> str:
        return (f"fixed latency {self.latency} cycles, {min(self.bytes_per_clock, self.bus_bytes)} bytes/clock "
                f"({self.bus_bytes}-byte beats every {self.beat_interval} cycle{'s' if self.beat_interval > 1 else ''})")

    def reset(self):
        self._free = 0          # the first cycle the R channel can carry the next burst's first beat
        self.queued = 0

    def read(self, t: int, address: int, beats: int) -> int:
        """The first beat's cycle of one burst accepted in cycle ``t``."""
        ready = int(t) + self.latency
        first = max(ready, self._free)
        self.queued = first - ready
        self._free = first + int(beats) * self.beat_interval
        return first

    def reads(self, t, address, beats) -> np.ndarray:
        """``read`` over sequences (int64 arrays of equal length), vectorised: with ``c[k]`` the beat
        cycles before burst ``k``, ``first[k] - c[k] = max over j <= k of (t[j] + latency - c[j])``."""
        t = np.asarray(t, np.int64)
        beats = np.asarray(beats, np.int64)
        if not len(t):
            return np.zeros(0, np.int64)
        c = np.concatenate([[0], np.cumsum(beats[:-1])]) * self.beat_interval
        first = np.maximum.accumulate(np.maximum(t + self.latency, self._free) - c) + c
        self.queued = int(first[-1] - (t[-1] + self.latency))
        self._free = int(first[-1] + beats[-1] * self.beat_interval)
        return first
