"""Every memory of an elaborated design, with its contents: the one walk the simulators and the
synthesis report share.

The memories are what :mod:`vqtex.golden.format` produced, split as the hardware holds them (even and
odd index banks, 512-word banks, descriptor rows, codebook entries): ``memories(fragment)`` reads them
back from the design through Amaranth's public interfaces (``Fragment``'s sub-fragments and origins,
``lib.memory.Memory.data``), so "what is in the chip" is taken from the chip itself.
"""

from __future__ import annotations

from dataclasses import dataclass

from amaranth.hdl import Const, Fragment, Shape, ShapeCastable
from amaranth.lib import memory

__all__ = ["MemoryContents", "memories", "elaborate"]


@dataclass(frozen=True)
class MemoryContents:
    """One memory: its place in the hierarchy, its word width and depth, and its words as integers
    (``len(words) <= depth``; the rest are zero)."""
    path: tuple
    width: int
    depth: int
    words: list


def elaborate(top) -> Fragment:
    """``top`` elaborated for the back ends (``Fragment.get(top, platform=None)``)."""
    return Fragment.get(top, None)


def memories(fragment: Fragment) -> list:
    """Every ``lib.memory.Memory`` under ``fragment``, depth first in the order of the sub-fragments:
    a list of :class:`MemoryContents` whose ``path`` holds the sub-fragment names from ``fragment`` down."""
    out, stack = [], [(fragment, ())]
    while stack:
        frag, path = stack.pop()
        for origin in frag.origins or ():
            if isinstance(origin, memory.Memory):
                data = origin.data
                shape = data.shape
                words = [Const.cast(shape.const(v)).value if isinstance(shape, ShapeCastable) else int(v)
                         for v in data.init]
                out.append(MemoryContents(path, Shape.cast(shape).width, data.depth, words))
        stack += [(sub, path + (str(name),)) for sub, name, _ in reversed(frag.subfragments)]
    return out
