"""The exact cycle model of ``hw.texel_fetch.TexelFetch``, vectorised with numpy.

It reproduces the RTL's cycle count, stall cycles by cause, straddling index reads and per-stage
occupancy exactly (tests compare it with pysim), without simulating the datapath.

How the RTL moves (see ``docs/hardware.md``)
---------------------------------------------
``LATENCY`` = 15 registers ``R1..R15`` (``hw.texel_fetch.STAGES``), then a skid register in front of
the output: ``o.valid = skid_valid | R15.valid``, and ``o`` shows the skid register when it is full.
Every register moves on ``advance``, a flip-flop holding ``~(o.valid & ~o.ready)`` of the previous
cycle; in an advancing cycle the skid register takes the response leaving ``R15`` (it counts as
full if that response was valid and not taken), so ``skid_valid = ~advance``. With ``one_port`` the
first ``UPSTREAM_STAGES`` = 4 registers (``R4`` holds the bit address the index reader is reading)
and the input *hold* for one advancing cycle when ``R4``'s item straddles a word boundary on the
first of its two reads: ``R5`` receives a bubble. Requests are presented back to back from cycle 0.

So the items entering ``R5``, one per advance, are: 4 bubbles (the pipeline filling), then for each
request a bubble if it is a one-port straddler, then the request. The output shows that sequence in
order, and a bubble there costs exactly one cycle: after a response transfers in cycle ``T``, the
next item is at the output in cycle ``T + 1`` (in ``R15``, which either moved on in cycle ``T`` or
was frozen behind the skid register), and a bubble in ``R15`` is never stalled (the skid register
is empty then, ``advance`` is high). A response waits for a cycle with ``o.ready`` high. Hence the
transfer cycle of request n::

    arrive[0] = LATENCY + bubble[0]
    T[n]      = first cycle >= arrive[n] with ready high
    arrive[n+1] = T[n] + 1 + bubble[n+1]

the same recurrence as a pipeline whose last register is the output and which freezes
combinationally on ``o.valid & ~o.ready``; the registered ``advance`` only moves the freeze one cycle
later: ``advance[t] = ~stall[t-1]`` with ``stall = o.valid & ~o.ready``, and the skid register is
full exactly in the cycles after a stall.

Counting cycles
---------------
Cycle 0 is the first cycle the first request is presented (``i.valid`` high); ``cycles`` counts
cycles 0 .. T[N-1] inclusive, so with no backpressure ``cycles = N + LATENCY (+ straddles with
one_port)``. ``output_backpressure`` counts cycles with ``o.valid & ~o.ready``; ``one_port_straddle``
counts the extra read cycles (one per straddling request, one-port only). Occupancy of a stage is
the fraction of those ``cycles`` in which its valid bit is high; the skid register's (``"skid"``)
is the fraction of cycles after an output stall, i.e. ``output_backpressure / cycles``.
"""

from __future__ import annotations

import numpy as np

from vqtex.golden.fetch import block_address, lookup_descriptor, straddles as golden_straddles
from vqtex.golden.format import TextureSet

from ..streams import pattern_length, ready_pattern

__all__ = ["straddle_flags", "transfer_cycles", "run_cycles", "run_flags", "run_cached", "LATENCY", "STAGES", "REGISTERS"]

# The RTL's constants (hw imports amaranth; these are plain ints and names).
from vqtex.hw.texel_fetch import LATENCY, REGISTERS, STAGES, UPSTREAM_STAGES  # noqa: E402


def straddle_flags(ts: TextureSet, requests: np.ndarray) -> np.ndarray:
    """Bool (N,): request n is compressed and its index read straddles a word boundary."""
    req = np.asarray(requests, dtype=np.int64).reshape(-1, 4)
    out = np.zeros(len(req), dtype=bool)
    if not len(req):
        return out
    d = lookup_descriptor(ts, req[:, 0], req[:, 1])
    comp = d["compressed"].astype(bool)
    if comp.any():
        k, _, _ = block_address(d[comp], req[comp, 2], req[comp, 3])
        out[comp] = golden_straddles(d[comp], k, ts.word_bits)
    return out


def transfer_cycles(bubbles: np.ndarray, ready: np.ndarray, latency: int = LATENCY):
    """Transfer cycle of every request (int64 (N,)), or None if ``ready`` is too short.

    ``bubbles[n]``: a one-port bubble precedes request n. Vectorised per run of requests between
    bubbles: a run of m requests arriving at cycle s transfers in the first m ready cycles >= s.
    """
    bubbles = np.asarray(bubbles, dtype=bool)
    n = len(bubbles)
    if n == 0:
        return np.zeros(0, np.int64)
    pos = np.flatnonzero(ready)                          # ready cycles
    before = np.concatenate([[0], np.cumsum(ready)])     # ready cycles in [0, t)
    starts = np.flatnonzero(bubbles[1:]) + 1             # runs begin at 0 and at every later bubble
    bounds = np.concatenate([[0], starts, [n]])
    out = np.empty(n, np.int64)
    arrive = latency + int(bubbles[0])
    for a, b in zip(bounds[:-1], bounds[1:]):
        if arrive >= len(ready):
            return None
        first = before[arrive]
        if first + (b - a) > len(pos):
            return None
        out[a:b] = pos[first: first + (b - a)]
        arrive = int(out[b - 1]) + 2                      # the next run starts with its bubble
    return out


def run_cycles(ts: TextureSet, requests: np.ndarray, *, stall: float = 0.0, seed: int = 0,
               one_port: bool = False, occupancy: bool = True, latency: int = LATENCY) -> dict:
    """Cycles, stall cycles, straddles and occupancy of ``requests`` on ``TexelFetch(ts)``.

    Returns a dict with ``cycles``, ``stall_cycles`` ({"output_backpressure", "one_port_straddle"}),
    ``straddles``, ``transfer`` (the transfer cycle of each request), ``occupancy`` (register name ->
    fraction, ``REGISTERS``, or None) and ``ready`` (the backpressure pattern over the counted cycles).
    """
    req = np.asarray(requests, dtype=np.int64).reshape(-1, 4)
    return run_flags(straddle_flags(ts, req), stall=stall, seed=seed, one_port=one_port,
                     occupancy=occupancy, latency=latency)


def run_flags(strad: np.ndarray, *, stall: float = 0.0, seed: int = 0, one_port: bool = False,
              occupancy: bool = True, latency: int = LATENCY) -> dict:
    """:func:`run_cycles` from the per-request straddle flags alone (what the timing depends on)."""
    strad = np.asarray(strad, dtype=bool)
    n = len(strad)
    bubbles = strad & bool(one_port)
    nbub = int(bubbles.sum())
    length = pattern_length(n + nbub, stall, latency)
    while True:
        ready = ready_pattern(seed, stall, length)
        T = transfer_cycles(bubbles, ready, latency)
        if T is not None:
            break
        length *= 2
    cycles = int(T[-1]) + 1 if n else 0
    ready = ready[:cycles]
    # Output register occupied on [arrive[n], T[n]].
    arrive = np.empty(n, np.int64)
    if n:
        arrive[0] = latency + int(bubbles[0])
        arrive[1:] = T[:-1] + 1 + bubbles[1:]
    ov_delta = np.zeros(cycles + 1, np.int64)
    np.add.at(ov_delta, arrive, 1)
    np.add.at(ov_delta, T + 1, -1)
    ov = np.cumsum(ov_delta)[:cycles].astype(bool)
    backpressure = int((ov & ~ready).sum())
    result = {
        "cycles": cycles,
        "stall_cycles": {"output_backpressure": backpressure, "one_port_straddle": nbub},
        "straddles": int(strad.sum()),
        "transfer": T,
        "ready": ready,
        "occupancy": None,
    }
    if occupancy and cycles:
        result["occupancy"] = _occupancy(n, bubbles, ov, ready, cycles, latency)
    return result


def _occupancy(n, bubbles, ov, ready, cycles, latency):
    """Per-register valid fractions, from the sequence of items entering R(UPSTREAM_STAGES + 1) (see the
    module doc)."""
    h = UPSTREAM_STAGES
    stall = ov & ~ready
    adv = np.concatenate([[True], ~stall[:-1]])          # the registered advance
    A = np.concatenate([[0], np.cumsum(adv)[:-1]])       # advances before cycle t
    # Sequence entering R(h+1), one entry per advance: h fill bubbles, then [bubble] item per request.
    pos_item = h + np.arange(n) + np.cumsum(bubbles)     # advance index at which item n enters R(h+1)
    seq_len = int(pos_item[-1]) + latency + 2 if n else latency + 2
    is_item = np.zeros(seq_len + cycles + 2, bool)
    is_item[pos_item] = True
    hold_adv = np.sort(pos_item[bubbles] - 1)            # advance indices that are one-port holds
    U = A - np.searchsorted(hold_adv, A, side="left")    # upstream advances before cycle t
    occ = {}
    for s, name in enumerate(STAGES, start=1):
        if s <= h:
            idx = U - s
            valid = (idx >= 0) & (idx < n)
        else:
            idx = A - 1 - (s - h - 1)
            valid = (idx >= 0) & is_item[np.clip(idx, 0, None)]
        occ[name] = float(valid.sum()) / cycles
    occ["skid"] = float((~adv).sum()) / cycles
    return occ


def run_cached(ts: TextureSet, requests: np.ndarray, config, *, stall: float = 0.0, seed: int = 0,
               zero_latency: bool = True, layout=None) -> dict:
    """The exact cycles of ``requests`` on the cached unit of ``config``
    (:class:`golden.memory.system.MemoryConfig`): this pipeline (``LATENCY``) behind the caches and
    memory of :mod:`golden.memory.timing`, with the shared backpressure pattern.

    Returns :func:`golden.memory.timing.run_requests`'s dict, plus ``texels_per_clock`` and, with
    ``zero_latency``, ``zero_latency_cycles`` (the same stream and backpressure with every reference a
    hit) and ``of_zero_latency`` (the ratio of texels per clock, cached against zero latency).
    ``layout``: where the set lies in external memory (:class:`golden.memory.system.Layout`; default
    ``Layout.of(ts)``, the baked unit's; the loadable cached unit's is its base registers')."""
    from vqtex.golden.memory.timing import run_requests

    def pattern(n):
        return ready_pattern(seed, stall, n)

    out = run_requests(ts, requests, config, LATENCY, pattern, layout=layout)
    n = out["requests"]
    out["texels_per_clock"] = n / out["cycles"] if out["cycles"] else 0.0
    if zero_latency:
        ideal = run_requests(ts, requests, config, LATENCY, pattern, ideal=True, layout=layout)
        out["zero_latency_cycles"] = ideal["cycles"]
        out["of_zero_latency"] = ideal["cycles"] / out["cycles"] if out["cycles"] else 1.0
    return out
