"""Picks: one of several values chosen by an index, as a balanced tree of 2:1 multiplexers
(:func:`pick`), and the first half of such a pick for a choice split over two pipeline stages
(:func:`pick_group`). Combinational; no registers, no latency of their own. Used by the banked
memories' bank select, the codebook ROM's word picks, the bus port's lane pick and the filter's
footprint and index banks.
"""

from __future__ import annotations

from amaranth import *

__all__ = ["pick", "pick_group"]


def pick(values: list, index):
    """``values[index]``, combinational: a balanced tree of 2:1 multiplexers on the bits of
    ``index``, least significant first (what a shifter by whole values is, without its
    out-of-range cases). The list is padded to a power of two with its last value; index bits
    above the tree are ignored. One value: no multiplexer."""
    values = list(values)
    if len(values) > 1:
        values += [values[-1]] * ((1 << (len(values) - 1).bit_length()) - len(values))
    bit = 0
    while len(values) > 1:
        values = [Mux(index[bit], values[n + 1], values[n]) for n in range(0, len(values), 2)]
        bit += 1
    return values[0]


def pick_group(values: list, index, group: int) -> list:
    """The first half of ``pick(values, index)`` over two stages: the ``group`` values of ``index``'s
    aligned group (``values[(index & ~(group - 1)) + lo]`` for ``lo`` in ``range(group)``), picked
    by ``index``'s high bits, combinational. ``pick(pick_group(values, index, group),
    index[:log2(group)])`` is ``pick(values, index)`` for every ``index`` (the list padded with its
    last value, index bits above the tree ignored, as :func:`pick`). ``group``: a power of two."""
    if group < 1 or group & (group - 1):
        raise ValueError(f"group {group} is not a power of two")
    values = list(values)
    size = 1 << (len(values) - 1).bit_length() if len(values) > 1 else 1
    values += [values[-1]] * (size - len(values))
    values = [values[n % size] for n in range(max(size, group))]     # (the index modulo the tree)
    g = group.bit_length() - 1
    return [pick(values[lo::group], index[g:]) for lo in range(group)]
