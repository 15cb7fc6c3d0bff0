"""The exact cycle count of the texture filter reading through the memory system (twin of
``hw.memory.filter.CachedTextureFilter``; the design: docs/memory.md, "The texture filter through
the memory system").

::

    footprint (5) -> sequencer -> lane k: address (2) -> cache k (tag check, FIFO, data read) --join-->
        texel pipelines (lock step, LATENCY) -> blend (4) -> o;   the caches' bursts -> arbiter -> memory

The groups (``lanes`` texel slots of a pixel's footprint, ``ceil(used / lanes)`` per pixel) reach
the lanes' address stages back to back from cycle ``FOOTPRINT_LATENCY`` (the footprint's five stages
move together and the sequencer offers a group every cycle while the pixels last). Lane ``k`` reads
its slots (``k + lanes g`` of every pixel's group ``g``) through its own index and raw caches
(:func:`golden.memory.timing.plan` of its stream: numpy), and the rules of
:mod:`golden.memory.timing` hold per group with the lanes joined:

- ``a[n]`` (group n enters the address stages) ``>= a[n-1] + 1``, ``>= b[n - ADDRESS_STAGES]``;
  ``a[0] = FOOTPRINT_LATENCY``;
- ``b[n]`` (every lane's cache block takes group n into its lookup's buffer, which holds three
  groups, its ready registered) ``>= a[n] + ADDRESS_STAGES``, ``>= b[n-1] + 1``, ``>= g[n-3] + 1``;
- ``g[n]`` (every lane's tag check, the same cycle): first tried in ``max(b[n] + LOOKUP_STAGES,
  g[n-1] + 1)``, then every ``REPLAY`` cycles (:func:`golden.memory.timing.attempt`), the first try
  ``>= g[n-1] + max_k misses_k[n-1]`` and, for every lane, ``>= p_k[n-Q] + fifo_slack(Q)`` and
  ``>= p_k[v_k] + VICTIM_READ`` (its victim rule);
- lane k's j-th burst of group n is offered in ``g[n] + 1 + j`` and issued by the arbiter's rule
  (:class:`golden.memory.arbiter.Arbiter`, offers in (cycle, lane) order) into one memory model;
  its line is readable ``FILL_READ`` cycles after its last beat;
- ``p_k[n]`` (lane k's data read) ``>= g[n] + 1``, ``>= p_k[n-1] + 1``, ``>= e[n-1]``, and ``>=``
  the fills of its lines;
- ``e[n]`` (the texel pipelines take group n): ``max(max_k p_k[n] + 1, e[n-1] + 1)`` (with
  ``o.ready`` high always every cycle advances; output backpressure: below);
- the lanes' outputs ``T[n] = e[n] + LATENCY`` (the texel pipeline's), and pixel m's colour
  transfers ``BLEND_LATENCY`` cycles after its last group's: ``cycles = T[last] + BLEND_LATENCY + 1``.

With every reference a hit: ``cycles = groups + FOOTPRINT_LATENCY + ADDRESS_STAGES + LOOKUP_STAGES
+ 2 + LATENCY + BLEND_LATENCY`` = ``groups + 30`` with the texel pipeline's ``LATENCY`` of 15 (the
on-chip filter: ``groups + 24``). ``LATENCY`` is an argument (``latency``: the caller passes
``hw.texel_fetch.LATENCY``; golden does not import hw), as in :mod:`golden.memory.timing`. With one lane the rules are
:func:`golden.memory.timing.run`'s exactly (the tests hold them equal).

Output backpressure (``run(..., ready_pattern=)``): ``o.ready`` low holds the blend (its output
register, then its stages: :class:`BlendStages`, stepped cycle by cycle), whose ``i.ready`` is the
texel pipelines' ``o.ready``; the texel pipelines then take group n as
:class:`golden.memory.timing.TexelPipeline` says (``e[n]``: the first advancing cycle; their
``advance`` is registered), the data read keeps ``p_k[n] >= e[n-1]``, and each colour transfers
when the blend's output register holds it and ``o.ready`` is high. With ``o.ready`` high always the
two give the same cycles (a test holds them equal). Why a loop over groups: as in
:mod:`golden.memory.timing`, each group's times chain to its predecessors' and to the memory's state.
"""

from __future__ import annotations

import numpy as np

from .. import filter as spec
from ..format import TextureSet
from .arbiter import Arbiter
from .system import Layout, MemoryConfig
from .timing import ADDRESS_STAGES, FILL_READ, LOOKUP_STAGES, VICTIM_READ, TexelPipeline, accept_and_lookup, attempt, fifo_slack, first_check, plan

__all__ = ["FOOTPRINT_LATENCY", "BLEND_LATENCY", "lane_requests", "run", "run_pixels"]

#: The footprint's stages (``hw.filter.footprint.LATENCY``).
FOOTPRINT_LATENCY = 5
#: The blend's stages (``hw.filter.blend.LATENCY``).
BLEND_LATENCY = 4


def lane_requests(ts: TextureSet, pixels: dict, lanes: int, frac: int):
    """The lanes' texel requests, vectorised: ``(requests, last)`` with ``requests`` (lanes, G, 4)
    int64 (texture, level, i, j) of every group in order and ``last`` (G,) bool, the pixel's last
    group. ``pixels`` as for :func:`sim.backends.filter.simulate_filter` (checked)."""
    table = spec.LevelTable([ts.level_shapes(t) for t in range(ts.n_textures)])
    tex = np.asarray(pixels["texture"], np.int64)
    lv, i, j, _ = spec.footprint(table, tex, pixels["s"], pixels["t"], pixels["lod"], pixels["mode"],
                                 pixels["address_s"], pixels["address_t"], frac)
    used = np.array([1, 4, 8])[np.asarray(pixels["mode"], np.int64)]
    per = -(-used // lanes)
    pix = np.repeat(np.arange(len(tex)), per)
    start = np.cumsum(per) - per
    grp = np.arange(len(pix)) - np.repeat(start, per)
    slot = grp[None, :] * lanes + np.arange(lanes)[:, None]             # (lanes, G)
    req = np.stack([np.broadcast_to(tex[pix], slot.shape), lv[pix, slot], i[pix, slot], j[pix, slot]], -1)
    last = np.zeros(len(pix), bool)
    last[np.cumsum(per) - 1] = True
    return req, last


class BlendStages:
    """The blend's timing (``hw.filter.blend.Blend``: stages *group*, *weigh*, *sum* loading when
    empty or when their content moves on, *accumulate* taking the sum's group when ``~o.valid |
    o.ready``, ``o.valid`` set by a pixel's last group, cleared by a transfer), stepped cycle by cycle
    under the output's ``ready`` (a :class:`golden.memory.timing._Ready`-like pattern of ``o.ready``).

    ``__call__(t)``: the first cycle ``>= t`` in which the blend takes a group (its ``i.ready``, the
    texel pipelines' ``o.ready``), given the groups entered so far (the texel pipeline model asks in
    order); :meth:`enter` records that the pending cycle took a group; :meth:`finish` runs until
    every pixel's colour has transferred. ``transfer``: each colour's cycle; ``backpressure``:
    cycles with ``o.valid & ~o.ready``."""

    def __init__(self, ready_pattern, length: int):
        self._ready = ready_pattern(max(64, length)).tolist()
        self._pattern = ready_pattern
        self.t = 0                            # the next cycle to evaluate (registers at its start)
        self.stages = [None, None, None]      # group, weigh, sum: None or the group's last mark
        self.o_valid = False
        self.transfer = []
        self.backpressure = 0
        self.pixels = 0

    def _o_ready(self, t: int) -> bool:
        while t >= len(self._ready):
            self._ready = self._pattern(2 * len(self._ready)).tolist()
        return bool(self._ready[t])

    def _loads(self):
        g, p, w = self.stages
        r = self._o_ready(self.t)
        take = w is not None and (not self.o_valid or r)
        load_w = w is None or take
        load_p = p is None or load_w
        return r, take, load_w, load_p, g is None or load_p

    def _step(self, entering):
        """Cycle ``t``'s edge: ``entering`` is the last mark of the group the blend takes (None: none)."""
        g, p, w = self.stages
        r, take, load_w, load_p, load_g = self._loads()
        if self.o_valid:
            if r:
                self.transfer.append(self.t)
            else:
                self.backpressure += 1
        if r:
            self.o_valid = False
        if take and w:
            self.o_valid = True
        self.stages = [entering if load_g else g, g if load_p else p, p if load_w else w]
        self.t += 1

    def __call__(self, t: int) -> int:
        while self.t < t:
            self._step(None)
        while not self._loads()[4]:
            self._step(None)
        return self.t

    def enter(self, t: int, last: bool) -> None:
        assert t == self.t and self._loads()[4], "a group entered the blend when it could not take it"
        self._step(bool(last))
        self.pixels += bool(last)

    def finish(self) -> None:
        while len(self.transfer) < self.pixels:
            self._step(None)


def run(plans: list, config: MemoryConfig, last: np.ndarray, *, latency: int, start: int = FOOTPRINT_LATENCY,
        blend: int = BLEND_LATENCY, ready_pattern=None) -> dict:
    """Walk the rules of the module docstring over the lanes' :class:`golden.memory.timing.Plan`
    (one per lane, over the same G groups). ``last`` (G,) marks each pixel's last group.
    ``latency``: the texel pipeline's (``hw.texel_fetch.LATENCY``).
    ``ready_pattern(length)`` (bool array of ``o.ready`` for cycles ``0 .. length-1``, every length a
    prefix of one sequence; :func:`sim.streams.ready_pattern`): output backpressure. The texel
    pipelines then take group n as :class:`golden.memory.timing.TexelPipeline` says, their outputs
    taken by the blend (:class:`BlendStages`, ``blend`` must be its 4 stages), whose colours leave
    under ``o.ready``; ``stall_cycles["output_backpressure"]`` counts ``o.valid & ~o.ready``. None:
    ``o.ready`` high always (the rules above, closed form).

    Returns a dict: ``cycles``; ``transfer`` (int64 (M,), each colour's cycle); ``group_transfer``
    (int64 (G,), the lanes' outputs); ``stall_cycles``: ``miss`` and ``bandwidth`` (summed over the
    lanes: the cycles a lane's data read waited for a fill, split as in ``timing``; their sum is
    the sum of the readers' ``stall_fill`` strobes), ``join`` (cycles the texel pipelines waited
    for the slowest lane beyond the fastest), ``fifo_full``, ``victim`` (what held tag checks back),
    ``arbiter`` (cycles bursts waited for the master); ``bursts`` and ``memory_bytes`` (index, raw)
    over all lanes; the per-group ``accept``, ``tag``, ``enter``, and ``ar`` (int64 (B,), every
    burst's AR cycle in issue order, with ``ar_lane``)."""
    lanes = len(plans)
    n = len(last)
    La, Q, L = ADDRESS_STAGES, config.prefetch, int(latency)
    slack = fifo_slack(Q)
    mem = config.make_memory()
    d = mem.beat_interval
    arb = Arbiter()
    misses = [p.misses.tolist() for p in plans]
    victim = [p.victim.tolist() for p in plans]
    fa = [p.fills[:, 0].tolist() for p in plans]
    fb = [p.fills[:, 1].tolist() for p in plans]
    address = [p.address.tolist() for p in plans]
    beats = [p.beats.tolist() for p in plans]
    maxmiss = np.max(np.stack([p.misses for p in plans]), axis=0).tolist() if n else []
    filled = [[0] * len(x) for x in address]
    queued = [[0] * len(x) for x in address]
    burst = [0] * lanes
    a, lk, g, e = [0] * n, [0] * n, [0] * n, [0] * n
    pr = [[0] * n for _ in range(lanes)]
    ar, ar_lane = [], []
    miss_c = bw_c = fifo_c = victim_c = join_c = 0
    K = range(lanes)
    pipe = stages = None
    lastl = np.asarray(last, bool).tolist()
    if ready_pattern is not None:
        if blend != BLEND_LATENCY:
            raise ValueError(f"the blend's backpressure model is of its {BLEND_LATENCY} stages")
        stages = BlendStages(ready_pattern, 2 * n + L + 64)
        pipe = TexelPipeline(L, ready_pattern, max(64, 2 * n + L + 64))
        pipe.ready = stages
    for i in range(n):
        ai, bi = accept_and_lookup(i, a, lk, g, La, start)
        lk[i] = bi
        gi = first_check(i, bi, g)
        if i:
            gi = attempt(gi, g[i - 1] + maxmiss[i - 1])
        if i >= Q:
            t = attempt(gi, max(pr[k][i - Q] for k in K) + slack)
            fifo_c += t - gi
            gi = t
        vt = -1
        for k in K:
            v = victim[k][i]
            if v >= 0 and pr[k][v] + VICTIM_READ > vt:
                vt = pr[k][v] + VICTIM_READ
        t = attempt(gi, vt)
        victim_c += t - gi
        gi = t
        g[i] = gi
        a[i] = ai
        for j in range(maxmiss[i]):
            for k in K:
                if misses[k][i] > j:
                    b = burst[k]
                    t = arb.issue(gi + 1 + j)
                    f = mem.read(t, address[k][b], beats[k][b])
                    queued[k][b] = mem.queued
                    filled[k][b] = f + (beats[k][b] - 1) * d + FILL_READ
                    ar.append(t)
                    ar_lane.append(k)
                    burst[k] = b + 1
        lo, hi = None, 0
        for k in K:
            pi = gi + 1
            if i:
                pi = max(pi, pr[k][i - 1] + 1, e[i - 1])
            fk = filled[k]
            wait_b = -1
            for fbst in (fa[k][i], fb[k][i]):
                if fbst >= 0 and fk[fbst] > pi and (wait_b < 0 or fk[fbst] > fk[wait_b]):
                    wait_b = fbst
            if wait_b >= 0:
                wait = fk[wait_b] - pi
                bw = min(wait, queued[k][wait_b])
                bw_c += bw
                miss_c += wait - bw
                pi = fk[wait_b]
            pr[k][i] = pi
            lo = pi if lo is None or pi < lo else lo
            hi = pi if pi > hi else hi
        join_c += hi - lo
        if pipe is None:
            e[i] = max(hi + 1, e[i - 1] + 1) if i else hi + 1
        else:
            e[i] = pipe.take(max(hi + 1, e[i - 1] + 1) if i else hi + 1)
            stages.enter(pipe.transfer[-1], lastl[i])
    if pipe is None:
        T = np.array(e, np.int64) + L
        colour = T[np.asarray(last, bool)] + blend
        backpressure = 0
    else:
        stages.finish()
        T = np.array(pipe.transfer, np.int64)
        colour = np.array(stages.transfer, np.int64)
        backpressure = stages.backpressure
    line = (config.index_cache.line, config.raw_cache.line)
    per_cache = np.zeros(2, np.int64)
    for p in plans:
        per_cache += np.bincount(p.cache, minlength=2) if len(p.cache) else 0
    return {
        "cycles": int(colour[-1]) + 1 if n else 0,
        "transfer": colour, "group_transfer": T,
        "stall_cycles": {"miss": miss_c, "bandwidth": bw_c, "join": join_c, "fifo_full": fifo_c,
                         "victim": victim_c, "arbiter": arb.waited, "output_backpressure": backpressure},
        "bursts": int(per_cache.sum()),
        "memory_bytes": {"index": int(per_cache[0]) * line[0], "raw": int(per_cache[1]) * line[1]},
        "accept": np.array(a, np.int64), "lookup": np.array(lk, np.int64), "tag": np.array(g, np.int64), "enter": np.array(e, np.int64),
        "ar": np.array(ar, np.int64), "ar_lane": np.array(ar_lane, np.int64),
    }


def run_pixels(ts: TextureSet, pixels: dict, config: MemoryConfig, lanes: int, frac: int,
               ideal: bool = False, layout: Layout | None = None, ready_pattern=None, *, latency: int) -> dict:
    """:func:`lane_requests`, a :func:`golden.memory.timing.plan` per lane (``layout``: where the set
    lies in external memory, default ``Layout.of(ts)``; the loadable filter's base registers), then
    :func:`run` (``ready_pattern``: output backpressure, as there; ``latency``: the texel pipeline's,
    ``hw.texel_fetch.LATENCY``); adds
    ``pixels``, ``groups``, ``pixels_per_clock``, ``on_chip_cycles`` (the on-chip filter's ``groups +
    FOOTPRINT_LATENCY + latency + BLEND_LATENCY``, ``groups + 24``), ``references``/``hit_rate`` per cache (over all lanes), ``bytes_per_pixel`` and
    ``bytes_per_texel`` (per texel slot fetched). ``ideal``: every reference hits."""
    req, last = lane_requests(ts, pixels, lanes, frac)
    plans = [plan(ts, req[k], config, ideal=ideal, layout=layout) for k in range(lanes)]
    out = run(plans, config, last, latency=latency, ready_pattern=ready_pattern)
    m, groups = int(last.sum()), len(last)
    refs = [sum(p.references[c] for p in plans) for c in (0, 1)]
    hits = [sum(p.hits[c] for p in plans) for c in (0, 1)]
    total = sum(out["memory_bytes"].values())
    out.update({
        "pixels": m, "groups": groups, "lanes": lanes,
        "pixels_per_clock": m / out["cycles"] if out["cycles"] else 0.0,
        "on_chip_cycles": groups + FOOTPRINT_LATENCY + int(latency) + BLEND_LATENCY if groups else 0,
        "references": {"index": refs[0], "raw": refs[1]},
        "hit_rate": {name: (hits[c] / refs[c] if refs[c] else None) for c, name in enumerate(("index", "raw"))},
        "bytes_per_pixel": total / m if m else 0.0,
        "bytes_per_texel": total / (groups * lanes) if groups else 0.0,
    })
    return out
