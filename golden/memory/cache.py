"""Set-associative caches of lines with LRU replacement, classified over a stream of references.

A cache of ``size`` bytes in lines of ``line`` bytes, ``ways`` lines per set, ``sets = size / (line *
ways)`` sets; line ``L`` (byte address / line) lives in set ``L mod sets``. Replacement is least
recently used: a miss fills an empty way if the set has one (the lowest), else evicts the way used
longest ago. The cache starts empty.

The tag state is updated in reference order whatever the timing (the tags are checked ahead of the
data, :mod:`golden.memory.timing`), so which references hit and which line each miss evicts depend
on the reference stream only: :func:`classify` computes them without any notion of time.

How it is computed: sets are independent, so the stream is split by set and the sets are stepped
together, one reference of every set per step (numpy over the sets). A reference to the line the
set's previous reference used is a hit that changes nothing but that line's last use, so runs of them
are folded first: the steps are the set's changes of line, not its references. The loop runs
``max over sets of (line changes in the set)`` times (a few thousand for a frame in a 16 KB cache),
each step a few numpy operations over at most ``sets`` elements.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["CacheShape", "Classified", "classify"]


def _power_of_two(v) -> bool:
    return isinstance(v, (int, np.integer)) and not isinstance(v, bool) and v >= 1 and not v & (v - 1)


@dataclass(frozen=True)
class CacheShape:
    """A cache's geometry: ``size`` bytes, ``line`` bytes per line, ``ways`` lines per set (powers of
    two; ``size >= line * ways``).

    Raises ValueError on anything else, or a line over 4 KB (an AXI burst may not cross 4 KB)."""
    size: int = 16384
    line: int = 32
    ways: int = 4

    def __post_init__(self):
        for name in ("size", "line", "ways"):
            if not _power_of_two(getattr(self, name)):
                raise ValueError(f"cache {name} must be a power of two, not {getattr(self, name)!r}")
        if self.line > 4096:
            raise ValueError(f"cache line {self.line} bytes: at most 4096 (an AXI burst may not cross 4 KB)")
        if self.line < 4:
            raise ValueError(f"cache line {self.line} bytes: at least one 4-byte word")
        if self.size < self.line * self.ways:
            raise ValueError(f"a {self.size}-byte cache cannot hold {self.ways} ways of {self.line}-byte lines")

    @property
    def sets(self) -> int:
        return self.size // (self.line * self.ways)

    @property
    def lines(self) -> int:
        return self.size // self.line

    def describe(self) -> str:
        kb = f"{self.size // 1024} KB" if self.size >= 1024 else f"{self.size} B"
        return f"{kb}: {self.sets} sets x {self.ways} ways of {self.line}-byte lines, LRU"


@dataclass
class Classified:
    """What each reference of a stream did in the cache (all (N,) arrays).

    ``hit``: bool. ``way``: the way it used. ``victim_last``: for a miss that evicted a line, the
    position (in the stream) of the last reference to the evicted line, else -1. ``fill``: for every
    reference, the position of the miss that brought its line in (itself for a miss): the reference
    must wait for that fill."""
    hit: np.ndarray
    way: np.ndarray
    victim_last: np.ndarray
    fill: np.ndarray

    @property
    def misses(self) -> int:
        return int((~self.hit).sum())


def classify(lines, sets, n_sets: int, ways: int) -> Classified:
    """Classify a stream of references to ``lines`` (int64 (N,), non-negative), each in set
    ``sets`` (int64 (N,), in ``[0, n_sets)``), in an initially empty LRU cache of ``ways`` ways.

    See the module docstring for the method."""
    lines = np.asarray(lines, np.int64)
    sets = np.asarray(sets, np.int64)
    n = len(lines)
    hit = np.zeros(n, bool)
    way = np.zeros(n, np.int64)
    victim_last = np.full(n, -1, np.int64)
    if n == 0:
        return Classified(hit, way, victim_last, np.zeros(0, np.int64))
    order = np.argsort(sets, kind="stable")
    s, ln = sets[order], lines[order]
    head = np.ones(n, bool)                              # a change of line within the set
    head[1:] = (s[1:] != s[:-1]) | (ln[1:] != ln[:-1])
    hpos = np.flatnonzero(head)
    # Each head's run: the folded repeats after it; its last reference is the line's last use.
    run_end = np.append(hpos[1:], n) - 1
    new_set = np.ones(len(hpos), bool)
    new_set[1:] = s[hpos[1:]] != s[hpos[:-1]]
    first_of_set = np.flatnonzero(new_set)
    step = np.arange(len(hpos)) - np.repeat(first_of_set, np.diff(np.append(first_of_set, len(hpos))))
    by_step = np.argsort(step, kind="stable")
    bounds = np.searchsorted(step[by_step], np.arange(int(step.max()) + 2))
    tags = np.full((n_sets, ways), -1, np.int64)
    used = np.full((n_sets, ways), -1, np.int64)         # step of last use (LRU age); -1: empty
    last = np.full((n_sets, ways), -1, np.int64)         # stream position of the line's last reference
    h_hit = np.zeros(len(hpos), bool)
    h_way = np.zeros(len(hpos), np.int64)
    h_victim = np.full(len(hpos), -1, np.int64)
    for k in range(len(bounds) - 1):
        hs = by_step[bounds[k]: bounds[k + 1]]          # one head per set
        if not len(hs):
            continue
        S = s[hpos[hs]]
        L = ln[hpos[hs]]
        match = tags[S] == L[:, None]
        is_hit = match.any(axis=1)
        victim = np.argmin(used[S], axis=1)              # empty ways (-1) first, lowest way on ties
        w = np.where(is_hit, np.argmax(match, axis=1), victim)
        evicts = ~is_hit & (tags[S, w] >= 0)
        h_victim[hs] = np.where(evicts, last[S, w], -1)
        h_hit[hs], h_way[hs] = is_hit, w
        tags[S, w] = L
        used[S, w] = k
        last[S, w] = order[run_end[hs]]
    # Back to stream order: the folded repeats hit in their head's way.
    run_of = np.cumsum(head) - 1
    hit[order] = np.where(head, h_hit[run_of], True)
    way[order] = h_way[run_of]
    victim_last[order] = np.where(head, h_victim[run_of], -1)
    # The fill each reference waits for: the latest miss of its (set, line) at or before it.
    miss_pos = np.where(~hit, np.arange(n), -1)
    by_line = np.lexsort((np.arange(n), lines))
    ml = miss_pos[by_line]
    new_line = np.ones(n, bool)
    new_line[1:] = lines[by_line][1:] != lines[by_line][:-1]
    # maximum.accumulate restarted at each line: offset each line's values above the previous lines'.
    gid = np.cumsum(new_line) - 1
    acc = np.maximum.accumulate(np.where(ml >= 0, ml + gid * (n + 1), gid * (n + 1) - 1)) - gid * (n + 1)
    fill = np.empty(n, np.int64)
    fill[by_line] = acc
    return Classified(hit, way, victim_last, fill)
