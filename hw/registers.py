"""The pipeline's register: a value registered in ``sync`` when its stage's enable is high.

Every stage of the unit holds its data this way (the stage advances when ``en`` is high, and holds
otherwise); the blocks and the front end's carried fields all use this one helper.
"""

from __future__ import annotations

from amaranth import Signal

__all__ = ["enabled_register"]


def enabled_register(m, en, value, name: str):
    """A register of ``value``'s shape named ``name``, loaded with ``value`` in cycles where ``en``
    is high (one stage of latency), added to module ``m``; returns the register."""
    r = Signal.like(value, name=name)
    with m.If(en):
        m.d.sync += r.eq(value)
    return r
