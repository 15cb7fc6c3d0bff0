"""The AXI4 read channels (AR, R) as an Amaranth signature, from the master's side.

Only what a read master needs: one ID (``ARID``/``RID`` left out: responses come back in order),
no user, lock, cache, protection, QoS or region signals (a slave ties them to their defaults). A
burst is ``arlen + 1`` beats of ``2**arsize`` bytes from ``araddr``; ``arburst`` 1 is INCR. Names are
AMBA's, lower case.
"""

from __future__ import annotations

from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

__all__ = ["axi4_read_signature", "INCR"]

#: ``arburst`` of an incrementing burst.
INCR = 1


def axi4_read_signature(addr_width: int, data_width: int) -> wiring.Signature:
    """AR and R of an AXI4 read master: ``araddr`` (``addr_width``), ``arlen`` (8), ``arsize`` (3),
    ``arburst`` (2), ``arvalid`` out, ``arready`` in; ``rdata`` (``data_width``), ``rresp`` (2),
    ``rlast``, ``rvalid`` in, ``rready`` out.

    Raises ValueError if ``data_width`` is not 8 to 1024 bits, a power of two."""
    if data_width < 8 or data_width > 1024 or data_width & (data_width - 1):
        raise ValueError(f"AXI data width {data_width} must be a power of two from 8 to 1024 bits")
    return wiring.Signature({
        "araddr": Out(addr_width), "arlen": Out(8), "arsize": Out(3), "arburst": Out(2),
        "arvalid": Out(1), "arready": In(1),
        "rdata": In(data_width), "rresp": In(2), "rlast": In(1), "rvalid": In(1), "rready": Out(1),
    })
