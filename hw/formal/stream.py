"""The valid/ready rules of an ``amaranth.lib.stream`` interface, as claims on its producer.

A producer that has raised ``valid`` keeps it, and keeps the payload unchanged, until the cycle the
consumer's ``ready`` is high (the transfer): in every cycle after a stalled one (``valid & ~ready``),
``valid`` is high and ``payload`` is what it was. Nothing is assumed of the consumer: ``ready`` is
whatever the harness drives (a free value for the unit's output, the next stage for an internal
stream), so the claim holds under every pattern of backpressure.
"""

from __future__ import annotations

from amaranth import *

__all__ = ["stream_rules"]


def stream_rules(harness, m: Module, stream, name: str) -> None:
    """Claim the producer's rules on ``stream`` (valid held until ready, payload held until ready),
    with ``harness``'s :meth:`~vqtex.hw.formal.harness.Harness.claim`; ``name`` names the stream in
    the claims' texts."""
    payload = Value.cast(stream.payload)
    stalled = Signal(name=f"{name}_stalled")
    held = Signal.like(payload, name=f"{name}_held")
    m.d.sync += [stalled.eq(stream.valid & ~stream.ready), held.eq(payload)]
    with m.If(stalled):
        harness.claim(m, stream.valid, f"{name}: valid held until ready")
        harness.claim(m, payload == held, f"{name}: payload held until ready")
