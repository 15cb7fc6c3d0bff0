"""The exact cycle count of a request stream through the cached unit: caches, memory, pipeline.

The unit (docs/memory.md)
-------------------------
::

    requests -> address (2 stages) -> lookup -> tag check -> reference FIFO -> data read -> output register
                                                   |  (Q entries)             ^              |
                                                   v AR                       | R            v
                                                AXI4 read master  <------  memory      texel pipeline (LATENCY)
                                                                                             |
                                                                                          responses

The address stages (descriptor, block address) compute the words a request reads; the tag check
takes two cycles: the lookup (``LOOKUP_STAGES``; its input holds the requests accepted and not
yet taken, so its ready is a register) reads the tag rows and the counts of the request's sets,
compares the tags and registers the results (what the check writes in that cycle is forwarded to
it), and the check proper decides from them for its references
(:mod:`golden.memory.system`) in the index or raw cache, allocating a line and issuing its burst
on a miss; the reference waits in a FIFO of ``Q = config.prefetch`` entries until
its lines are filled; the data read takes the words from the cache into an output register, which
the texel pipeline (``hw.texel_fetch``'s, ``LATENCY`` registers and the skid register, advancing on
its registered ``advance``) accepts. ``Q = 1`` is the blocking cache.

The rules, in cycles (each event at the first cycle that meets all its rules; requests are presented
back to back from cycle 0, or for the cache block alone, ``address_stages = 0``, request n from
cycle ``offer[n]`` on, held until taken; ``x[n-k]`` for ``n < k`` imposes nothing):

- ``a[n]`` (request n accepted): ``>= a[n-1] + 1``, ``>= offer[n]`` (0 by default), ``>= b[n - ADDRESS_STAGES]`` (the address
  stages are a chain of stream registers that moves as a whole against the lookup's acceptance: a
  stage takes a new item when its item leaves, in the same cycle).
- ``b[n]`` (the lookup, the tag check's first cycle, takes request n): ``>= a[n] + ADDRESS_STAGES``;
  ``>= b[n-1] + 1``; ``>= g[n - LOOKUP_PLACES] + 1`` (the lookup's buffer holds the requests
  accepted and not yet taken by the check, at most three, and its ready is the registered ``count
  != 3``). With ``address_stages = 0``, ``a[n] = b[n]``.
- ``g[n]`` (tag check, its second cycle, where it is decided and the state written): the check is
  first tried in cycle ``c = max(b[n] + LOOKUP_STAGES, g[n-1] + 1)`` (:func:`first_check`: the lookup
  takes request n while n-1 is checked, as if n-1 were taken); a try whose rules do not hold is
  killed and request n looked up again, so it is tried again ``REPLAY`` = 3 cycles later (the kill
  acts from a register, a cycle after the try: :data:`REPLAY`): ``g[n]`` is
  the first of ``c, c + REPLAY, c + 2 REPLAY, ...`` (:func:`attempt`) that is ``>= g[n-1] +
  misses[n-1]`` (one burst issued per cycle); ``>= p[n-Q] + fifo_slack(Q)`` (a FIFO entry frees
  when its reference is read: the check sees the room in the FIFO's registered level, so from the
  cycle after the read, for ``Q > 1``; the blocking cache, ``Q = 1``, takes the read's room in the
  same cycle); for a miss whose victim line has a reference ``v`` not yet read, ``>= p[v] +
  VICTIM_READ`` (a line is never replaced under a waiting reference; the lookup, a cycle before the
  check, reads the counts of references read out as the reads before its own cycle left them).
- The j-th miss of request n issues its burst (AR) in cycle ``g[n] + 1 + j``; the memory model gives
  the first beat ``f``; the line is filled, readable by the data read, from ``f + (beats - 1) *
  beat_interval + FILL_READ``.
- ``p[n]`` (data read): ``>= g[n] + 1``; ``>= p[n-1] + 1``; ``>= e[n-1]`` (the output register is
  free: the pipeline takes n-1 from it that cycle); ``>=`` the fill of every line n references that
  was brought in by a miss (its own or an earlier request's: a line refilled while references wait on
  it serves them all, and is read from memory once).
- ``e[n]`` (the pipeline accepts n; ``i.ready`` is its ``advance``): the first advancing cycle
  ``>= max(p[n] + 1, e[n-1] + 1)``. A cycle ``u`` is advancing unless ``u - 1`` was a cycle of output
  backpressure (``o.valid & ~o.ready``).
- The pipeline's output, as ``sim.backends.cycle_model`` derives it: the items entering the
  pipeline in advancing cycles are requests and bubbles (an advancing cycle without a request); a
  bubble costs one output cycle. So ``arrive[0] = e[0] + LATENCY``, ``arrive[n] = T[n-1] + 1 +
  b[n]`` with ``b[n]`` the advancing cycles strictly between ``e[n-1]`` and ``e[n]``, and ``T[n]``
  (the response transfers) is the first cycle ``>= arrive[n]`` with ``o.ready`` high. Output
  backpressure is ``[arrive[n], T[n])`` for every n.

``cycles = T[N-1] + 1``. With every reference a hit and no backpressure, ``cycles = N + LATENCY +
ADDRESS_STAGES + LOOKUP_STAGES + 2``.

Stall cycles by cause: ``output_backpressure`` (cycles with ``o.valid & ~o.ready``, as the on-chip
unit counts them); ``miss`` and ``bandwidth``: the cycles by which a line fill held a data read back
beyond its other rules, split into the wait of the binding burst behind earlier bursts in the memory
(``bandwidth``: the memory's ``queued``) and the rest (``miss``: the memory's latency);
``fifo_full`` and ``victim``: cycles by which the FIFO's capacity or a waiting reference to the victim
line held a tag check back (counted in that order, each from the try the previous rules left,
``REPLAY`` rounding included).

Why a loop over requests: the rules chain each request's times to its predecessors' through maxima
with the backpressure pattern and the memory's state (a DRAM's open rows and refresh), so the model
walks the requests in order, a few dozen integer operations and three binary searches each; the
cache classification, the references and the bursts are computed beforehand with numpy. It runs at
about 1e5 requests per second; the compiled simulators are the tool for long streams.
"""

from __future__ import annotations

from bisect import bisect_right
from dataclasses import dataclass

import numpy as np

from ..format import TextureSet
from .cache import classify
from .system import Layout, MemoryConfig, references

__all__ = ["ADDRESS_STAGES", "LOOKUP_STAGES", "LOOKUP_PLACES", "REPLAY", "VICTIM_READ", "FILL_READ", "FRONT_LATENCY", "first_check", "attempt", "Plan", "plan", "fifo_slack", "accept_and_lookup", "run", "run_requests", "TexelPipeline", "StreamSink"]

#: The unit's address stages before the cache block (descriptor, block address).
ADDRESS_STAGES = 2
#: Cycles from the cache block's acceptance of a request to its first tag check: the lookup's
#: buffer (the request's sets and tags computed and registered) and the lookup (the sets' tag rows
#: and counts read, the tags compared, registered).
LOOKUP_STAGES = 2
#: Requests the cache block holds accepted and not yet taken by the tag check (the lookup's buffer:
#: the one checked, the one looked up, the one arriving): ``b[n] >= g[n - LOOKUP_PLACES] + 1``.
LOOKUP_PLACES = 3
#: Cycles between two tries of a tag check that does not take its request. The lookup takes the
#: next requests as if every check took its own; the check's decision ``take`` reaches only a few
#: registers, among them the kill (``lookup_kill``), which acts the cycle after the try: then the
#: request behind it in the check and the one in the lookup are killed, and the lookup takes the
#: request not taken again, so the check tries it again in the third cycle after its try (try in
#: ``c``, kill in ``c + 1``, looked up in ``c + 2``, checked in ``c + 3``). With the kill acting in
#: the try's own cycle (``take`` choosing the lookup's next request: its ~250 loads) it was 2.
REPLAY = 3
#: Cycles after the read of a line's last waiting reference before a tag check may replace the
#: line: the lookup (the cycle before the check) reads the counts of references read out, as
#: written by the reads before its own cycle.
VICTIM_READ = 2
#: Cycles from a line's last beat to the first data read of it: the fill is written at the end of
#: the beat's cycle and the data read's ``filled`` register takes it the cycle after.
FILL_READ = 2
#: Cycles from accepting a request to offering it to the texel pipeline when every reference hits:
#: the address stages, the lookup, the tag check and the data read.
FRONT_LATENCY = ADDRESS_STAGES + LOOKUP_STAGES + 2


@dataclass
class Plan:
    """What the timing needs from a request stream, computed with numpy before the loop.

    Per request (N,): ``misses`` (bursts it issues), ``fills`` ((N, 2) burst numbers its data read
    waits for, -1 none), ``victim`` (the latest request whose reference to a line this request evicts
    must have been read, -1 none). Per burst (B,), in issue order: ``address`` (bytes), ``beats``,
    ``cache`` (0 index, 1 raw). Per cache: ``references``, ``hits``."""
    misses: np.ndarray
    fills: np.ndarray
    victim: np.ndarray
    address: np.ndarray
    beats: np.ndarray
    cache: np.ndarray
    references: tuple
    hits: tuple


def plan(ts: TextureSet, requests: np.ndarray, config: MemoryConfig, ideal: bool = False,
         layout: Layout | None = None) -> Plan:
    """Classify the references of ``requests`` in the two caches and number the bursts.

    ``ideal``: every reference hits (the zero-latency figure: the same unit with a perfect cache).
    ``layout``: where the set lies in external memory (default ``Layout.of(ts)``)."""
    refs = references(ts, requests, config, layout or Layout.of(ts))
    n = len(np.asarray(requests).reshape(-1, 4))
    m = len(refs.line)
    hit = np.ones(m, bool)
    victim_ref = np.full(m, -1, np.int64)           # request index of the victim's last reference
    fill_ref = np.full(m, -1, np.int64)             # reference position (global) of the filling miss
    shapes = (config.index_cache, config.raw_cache)
    counts, hits = [], []
    for c, shape in enumerate(shapes):
        sel = np.flatnonzero(refs.cache == c)
        counts.append(int(len(sel)))
        if ideal or not len(sel):
            hits.append(int(len(sel)))
            continue
        lines = refs.line[sel]
        cl = classify(lines, lines % shape.sets, shape.sets, shape.ways)
        hit[sel] = cl.hit
        victim_ref[sel] = np.where(cl.victim_last >= 0, refs.request[sel][np.maximum(cl.victim_last, 0)], -1)
        fill_ref[sel] = sel[cl.fill]
        hits.append(int(cl.hit.sum()))
    miss = ~hit
    burst_of_ref = np.cumsum(miss) - 1                  # burst number of each miss, in reference order
    fill_burst = np.where(fill_ref >= 0, burst_of_ref[np.maximum(fill_ref, 0)], -1)
    misses = np.bincount(refs.request[miss], minlength=n).astype(np.int64)
    fills = np.full((n, 2), -1, np.int64)
    first = np.ones(m, bool)
    first[1:] = refs.request[1:] != refs.request[:-1]
    fills[refs.request[first], 0] = fill_burst[first]
    fills[refs.request[~first], 1] = fill_burst[~first]
    victim = np.full(n, -1, np.int64)
    np.maximum.at(victim, refs.request, victim_ref)
    line_bytes = np.array([s.line for s in shapes], np.int64)[refs.cache[miss]]
    return Plan(misses, fills, victim, refs.line[miss] * line_bytes, line_bytes // config.bus_bytes,
                refs.cache[miss].astype(np.int64), tuple(counts), tuple(hits))


class _Ready:
    """The first cycle >= t with ``o.ready`` high, over the shared backpressure pattern, extended
    (doubled) on demand (``sim.streams``: every length is a prefix of one sequence)."""

    def __init__(self, pattern, length: int):
        self._pattern = pattern
        self._grow(length)

    def _grow(self, length):
        ready = self._pattern(length)
        pos = np.flatnonzero(ready)
        idx = np.searchsorted(pos, np.arange(length))
        self.next = np.where(idx < len(pos), pos[np.minimum(idx, len(pos) - 1)], -1).tolist()

    def __call__(self, t: int) -> int:
        while t >= len(self.next) or self.next[t] < 0:
            self._grow(2 * len(self.next) + 64)
        return self.next[t]


class TexelPipeline:
    """The texel pipeline's timing seen from its input (``hw.texel_fetch.TexelFetch``: ``latency``
    registers and a skid register, all moving on the registered ``advance``; ``i.ready = advance``).

    :meth:`take` is called once per request, in order, with the first cycle ``s`` the request is
    offered (``s`` after the previous request's acceptance); it returns the acceptance cycle ``e``
    (the first advancing cycle >= s) and records the response's arrival at the output and its
    transfer (the rules of the module docstring)."""

    def __init__(self, latency: int, ready_pattern, length: int = 1024):
        self.latency = int(latency)
        self.ready = _Ready(ready_pattern, length)
        self.arrive, self.transfer = [], []
        self.backpressure = [0]             # [k]: output backpressure cycles of the items before k
        self._e = None                      # the previous acceptance
        self._sb = 0                        # backpressure cycles before it

    def _stalls_before(self, z: int) -> int:
        """Backpressure cycles u < z of the items recorded so far."""
        T = self.transfer
        k = bisect_right(T, z)
        return self.backpressure[k] + (max(0, z - self.arrive[k]) if k < len(T) else 0)

    def take(self, s: int) -> int:
        T = self.transfer
        k = bisect_right(T, s - 1)
        e = T[k] + 1 if k < len(T) and self.arrive[k] <= s - 1 else s
        if self._e is None:
            ar = e + self.latency
        else:
            bubbles = (e - 1 - self._e) - (self._stalls_before(e - 1) - self._sb)
            ar = T[-1] + 1 + bubbles
        self._sb = self._stalls_before(e)
        self._e = e
        t = self.ready(ar)
        self.arrive.append(ar)
        T.append(t)
        self.backpressure.append(self.backpressure[-1] + t - ar)
        return e


class StreamSink:
    """A consumer that takes the offered item in the first cycle >= s with its ``ready`` high (a
    plain stream sink; what the cache block alone is tested against, ``hw.memory``). ``transfer``
    lists the cycles it took each item."""

    def __init__(self, ready_pattern, length: int = 1024):
        self.ready = _Ready(ready_pattern, length)
        self.transfer = []
        self.backpressure = [0]

    def take(self, s: int) -> int:
        t = self.ready(s)
        self.transfer.append(t)
        self.backpressure.append(self.backpressure[-1] + t - s)
        return t



def fifo_slack(q: int) -> int:
    """Cycles after the read of reference ``n - q`` before the tag check may put reference ``n`` in
    a FIFO of ``q`` entries (the rule ``g[n] >= p[n-q] + fifo_slack(q)``): 1 for a prefetching FIFO
    (``q > 1``: the check's ready sees the room in the FIFO's registered level only, so the data
    read's ``pop`` stays off the check's path), 0 for the blocking cache (``q = 1``: a read and the
    next check in the same cycle, else every reference would take two cycles)."""
    return 1 if q > 1 else 0


def first_check(i: int, b_i: int, g: list) -> int:
    """The cycle request (or group) ``i`` is first in the tag check: ``>= b[i] + LOOKUP_STAGES``
    (looked up), ``>= g[i-1] + 1`` (the lookup takes it while its predecessor is checked, as if that
    one were taken)."""
    c = b_i + LOOKUP_STAGES
    return g[i - 1] + 1 if i and g[i - 1] + 1 > c else c


def attempt(c: int, r: int) -> int:
    """The first cycle ``>= r`` at which a check first tried in cycle ``c`` is tried again: a check
    not taken is killed and looked up again, so its tries are ``c, c + REPLAY, c + 2 REPLAY, ...``
    (``attempt(attempt(c, r1), r2) == attempt(c, max(r1, r2))``)."""
    return c if r <= c else c + -(-(r - c) // REPLAY) * REPLAY


def accept_and_lookup(i: int, a: list, b: list, g: list, La: int, start: int) -> tuple:
    """Request (or group) ``i``'s accept and lookup cycles ``(a[i], b[i])`` from its predecessors'
    (the rules of the module docstring; one definition for :func:`run` and the filter's
    :func:`golden.memory.filter.run`): ``a[i] >= a[i-1] + 1`` (``start`` for the first),
    ``>= b[i - La]`` (the address stages move against the lookup); ``b[i] >= a[i] + La``, ``>= b[i-1]
    + 1``, ``>= g[i-3] + 1`` (the lookup's buffer). ``La``: the address stages (0: the cache
    block alone). Lists of ints, filled up to ``i - 1``."""
    ai = a[i - 1] + 1 if i else start
    if La and i >= La and b[i - La] > ai:
        ai = b[i - La]
    bi = ai + La
    if i and b[i - 1] + 1 > bi:
        bi = b[i - 1] + 1
    if i >= LOOKUP_PLACES and g[i - LOOKUP_PLACES] + 1 > bi:
        bi = g[i - LOOKUP_PLACES] + 1
    return ai, bi

def run(p: Plan, config: MemoryConfig, pipeline_latency: int, ready_pattern, n_hint: int = 0,
        address_stages: int = ADDRESS_STAGES, consumer=None, offer=None) -> dict:
    """Walk the rules of the module docstring over a :class:`Plan`.

    ``ready_pattern(length)`` gives ``o.ready`` for cycles ``0 .. length-1`` (bool array, every
    length a prefix of one sequence). ``address_stages`` = 0 is the cache block alone
    (``hw.memory``): the input handshake is the lookup's (``a[n] = b[n]``).
    ``consumer`` (default the texel pipeline, :class:`TexelPipeline`) takes each item from the
    output register (``take(s) -> e``; :class:`StreamSink` for the cache block alone, whose
    ``transfer`` are then the output's transfers). ``offer`` (int (N,), nondecreasing; the cache
    block alone only, ``address_stages = 0``): the first cycle request n is offered on ``i`` (held
    until taken); default back to back from cycle 0. Returns a dict: ``cycles``, ``transfer`` (int64 (N,)),
    ``stall_cycles`` (cause -> cycles), ``bursts``, ``memory_bytes`` (per cache), ``burst_first``
    (int64 (B,), the first beat of each burst) and the per-stage event times ``accept``, ``lookup``, ``tag``,
    ``read``, ``enter`` (int64 (N,))."""
    n = len(p.misses)
    La, Q, L = int(address_stages), config.prefetch, int(pipeline_latency)
    if offer is not None:
        if La:
            raise ValueError("offer: the cache block alone only (address_stages=0)")
        offer = np.asarray(offer, np.int64).tolist()
        if len(offer) != n:
            raise ValueError(f"offer: {len(offer)} cycles for {n} requests")
    slack = fifo_slack(Q)
    mem = config.make_memory()
    d = mem.beat_interval
    pipe = consumer if consumer is not None else TexelPipeline(L, ready_pattern, max(64, 2 * n + L + 64, n_hint))
    misses, victim = p.misses.tolist(), p.victim.tolist()
    fa, fb = p.fills[:, 0].tolist(), p.fills[:, 1].tolist()
    address, beats = p.address.tolist(), p.beats.tolist()
    nb = len(address)
    filled = [0] * nb
    queued = [0] * nb
    first_beat = [0] * nb
    a, b, g, pr, e = [0] * n, [0] * n, [0] * n, [0] * n, [0] * n
    miss_c = bw_c = fifo_c = victim_c = 0
    burst = 0

    for i in range(n):
        # accept, lookup and tag check
        ai, bi = accept_and_lookup(i, a, b, g, La, 0)
        if offer is not None and offer[i] > bi:     # the cache block alone: a[i] = b[i]
            bi = offer[i]
        b[i] = bi
        gi = first_check(i, bi, g)
        if i:
            gi = attempt(gi, g[i - 1] + misses[i - 1])
        if i >= Q:
            t = attempt(gi, pr[i - Q] + slack)
            fifo_c += t - gi
            gi = t
        v = victim[i]
        if v >= 0:
            t = attempt(gi, pr[v] + VICTIM_READ)
            victim_c += t - gi
            gi = t
        g[i] = gi
        a[i] = bi if La == 0 else ai
        for j in range(misses[i]):
            f = mem.read(gi + 1 + j, address[burst], beats[burst])
            first_beat[burst] = f
            queued[burst] = mem.queued
            filled[burst] = f + (beats[burst] - 1) * d + FILL_READ
            burst += 1
        # data read
        pi = gi + 1
        if i:
            pi = max(pi, pr[i - 1] + 1, e[i - 1])
        wait_b = -1
        for fbst in (fa[i], fb[i]):
            if fbst >= 0 and filled[fbst] > pi and (wait_b < 0 or filled[fbst] > filled[wait_b]):
                wait_b = fbst
        if wait_b >= 0:
            wait = filled[wait_b] - pi
            bw = min(wait, queued[wait_b])
            bw_c += bw
            miss_c += wait - bw
            pi = filled[wait_b]
        pr[i] = pi
        # the texel pipeline takes it
        e[i] = pipe.take(pi + 1 if i == 0 else max(pi + 1, e[i - 1] + 1))
    T = pipe.transfer
    cycles = T[-1] + 1 if n else 0
    line_bytes = (config.index_cache.line, config.raw_cache.line)
    per_cache = np.bincount(p.cache, minlength=2) if nb else np.zeros(2, np.int64)
    return {
        "cycles": cycles,
        "transfer": np.array(T, np.int64),
        "stall_cycles": {"output_backpressure": pipe.backpressure[-1], "miss": miss_c, "bandwidth": bw_c,
                         "fifo_full": fifo_c, "victim": victim_c},
        "bursts": nb,
        "memory_bytes": {"index": int(per_cache[0]) * line_bytes[0], "raw": int(per_cache[1]) * line_bytes[1]},
        "burst_first": np.array(first_beat, np.int64),
        "accept": np.array(a, np.int64), "lookup": np.array(b, np.int64), "tag": np.array(g, np.int64),
        "read": np.array(pr, np.int64), "enter": np.array(e, np.int64),
        "memory": mem,
    }


def run_requests(ts: TextureSet, requests: np.ndarray, config: MemoryConfig, pipeline_latency: int,
                 ready_pattern, ideal: bool = False, layout: Layout | None = None) -> dict:
    """:func:`plan` then :func:`run`, with the hit rates and bytes per texel added: ``hit_rate`` and
    ``references`` per cache, ``bytes_per_texel`` (memory bytes read per request). ``layout``: as
    for :func:`plan`."""
    p = plan(ts, requests, config, ideal=ideal, layout=layout)
    out = run(p, config, pipeline_latency, ready_pattern)
    n = len(p.misses)
    out["references"] = {"index": p.references[0], "raw": p.references[1]}
    out["hit_rate"] = {name: (p.hits[c] / p.references[c] if p.references[c] else None)
                       for c, name in enumerate(("index", "raw"))}
    out["bytes_per_texel"] = (sum(out["memory_bytes"].values()) / n) if n else 0.0
    out["requests"] = n
    return out
