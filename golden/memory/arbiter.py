"""The AXI arbiter's rule: the lanes' bursts share one AXI4 read master (twin of ``hw.memory.arbiter``).

Each lane's cache offers a burst (its AR) in some cycle; the arbiter takes every offer at once (the
lanes see ``arready`` high always) and puts them on the one master in the order (cycle, lane), one AR
per cycle, the first one in the cycle it is offered when nothing waits::

    issue[b] = max(offer[b], issue[b-1] + 1)

over the offers sorted by cycle, then by lane. With one lane and offers at most one per cycle the
arbiter is a wire (``issue = offer``). Bursts come back in issue order (one AXI ID), and each R beat
goes to the lane that issued its burst.
"""

from __future__ import annotations

__all__ = ["Arbiter"]


class Arbiter:
    """The rule above, one offer at a time: call :meth:`issue` with the offers in (cycle, lane) order.
    ``waited`` sums the cycles the offers waited behind earlier ones (``issue - offer``)."""

    def __init__(self):
        self.last = -1
        self.waited = 0

    def issue(self, offer: int) -> int:
        t = offer if offer > self.last else self.last + 1
        self.waited += t - offer
        self.last = t
        return t
