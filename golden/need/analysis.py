"""Need analysis: what a scene's request streams touch in a texture set, vectorised.

From a :class:`~vqtex.golden.format.TextureSet` and the request streams of some frames (each an (N, 4) int64
array of (texture, level, i, j), as ``golden.render``'s sampler issues them), :func:`analyse`
reports

* which **textures**, **levels**, **level groups** and **blocks** are touched. A block of a compressed
  level is a block of its level group's index map (block ``k`` of :func:`~vqtex.golden.fetch.block_address`:
  levels ``n, n+1, n+2`` of a group share one block grid); a "block" of a raw level is one texel
  (one raw word). Counts of requests per block are kept per (texture, level): :meth:`Need.blocks`.
* which **codewords** the touched blocks use, per codebook (the indices the touched blocks' maps hold);
* the **colour formats**, **index widths** and **sub-levels** of the touched levels;
* per frame, the **distinct words** of each memory a frame reads against what is stored: index
  memory words (word ``w``, and ``w+1`` when the index straddles), codebook entries, raw words;
* per frame, how many of its reads **repeat the previous request's block** (a one-entry block
  buffer: same level group and block, or same raw texel) and how many **hit a small block cache**.

The cache (:class:`CacheSpec`, default 64 sets x 2 ways = 128 blocks, LRU): a block's set is
``(by mod 8) * 8 + (bx mod 8)`` of its block coordinates (an 8x8 tile of blocks maps onto the 64
sets, the usual texture-cache tiling; different textures and levels share the sets). It starts empty
at every frame. The LRU itself is the memory system's (:func:`golden.memory.cache.classify`, the
one cache model of the project): this module chooses only what a "line" is here (a block, or a raw
texel) and its set; the cycle-exact caches of the cached unit (:mod:`golden.memory.timing`) use the
same classification over memory lines.

Requests must be valid for ``ts`` (:func:`~vqtex.golden.fetch.check_requests`).

Public API::

    analyse(ts, streams, frames=None, cache=CacheSpec(), per_frame=True) -> Need
    NeedCounter(ts, cache=CacheSpec(), per_frame=True): .add(frame, reqs) -> FrameNeed | None, .result() -> Need
    heat_image(need, tex, level, min_side=256) -> (H, W, 4) uint8 picture of the blocks touched
    Need.textures, .levels, .groups, .blocks(t, L), .touched_blocks(t, L), .group_blocks(t, top), .codewords,
        .frames, .formats(), .summary(per_frame=True)
    scene_streams(scene, source, frames, mode="trilinear", **options) -> iterator of (frame, requests)
    scene_level_shapes(scene) -> [[(w, h), ...] per texture]
    distinct_requests(streams) -> (M, 4) int64, the union of several streams' requests
    request_blocks(ts, reqs) -> RequestBlocks     buffer_hits(keys) -> bool    cache_hits(keys, sets, ways) -> bool
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..constants import COLORS, MAX_LEVELS
from ..fetch import block_address, read_index, straddles
from ..format import TextureSet
from ..memory.cache import classify

__all__ = ["CacheSpec", "FrameNeed", "Need", "RequestBlocks", "analyse", "request_blocks", "buffer_hits",
           "cache_hits", "scene_streams", "scene_level_shapes", "row_grids", "NeedCounter", "heat_image",
           "distinct_requests"]


@dataclass(frozen=True)
class CacheSpec:
    """A small set-associative block cache with LRU replacement: ``tile[0] * tile[1]`` sets, each of
    ``ways`` blocks (1: direct-mapped; a power of two up to 16). A block at block coordinates (bx,
    by) is in set ``(by mod tile[1]) * tile[0] + (bx mod tile[0])``; ``tile`` sides are powers of two."""
    tile: tuple = (8, 8)
    ways: int = 2

    def __post_init__(self):
        tx, ty = self.tile
        if self.ways not in (1, 2, 4, 8, 16):
            raise ValueError(f"cache ways must be 1, 2, 4, 8 or 16, not {self.ways}")
        if tx < 1 or ty < 1 or tx & (tx - 1) or ty & (ty - 1):
            raise ValueError(f"cache tile {tx}x{ty}: sides must be powers of two")

    @property
    def sets(self) -> int:
        return self.tile[0] * self.tile[1]

    @property
    def blocks(self) -> int:
        return self.sets * self.ways

    def describe(self) -> str:
        return (f"{self.blocks} blocks: {self.sets} sets x {self.ways} way{'s' if self.ways > 1 else ''}, "
                f"{'LRU' if self.ways > 1 else 'direct-mapped'}, set = {self.tile[0]}x{self.tile[1]} tile of "
                f"block coordinates, empty at each frame")


def row_grids(ts: TextureSet):
    """Per (texture, level) row: the grid of its "blocks" and where its counts sit in one flat array.

    Returns (nbx, nby, offset), each (n_textures, MAX_LEVELS) int64: a compressed row's grid is its
    level group's block grid, a raw row's grid is its texels; rows that are not stored have 0 x 0.
    ``offset`` is each row's first element in a flat array of ``offset.max() + nbx*nby`` counts.
    """
    d = ts.descriptors
    valid = d["valid"].astype(bool)
    comp = d["compressed"].astype(bool) & valid
    lw, lh = d["log2w"].astype(np.int64), d["log2h"].astype(np.int64)
    nbx = np.where(comp, 1 << np.maximum(lw - d["log2bw"].astype(np.int64), 0), 1 << lw) * valid
    nby = np.where(comp, 1 << np.maximum(lh - d["log2bh"].astype(np.int64), 0), 1 << lh) * valid
    size = (nbx * nby).ravel()
    offset = (np.cumsum(size) - size).reshape(nbx.shape)
    return nbx, nby, offset


@dataclass
class RequestBlocks:
    """What each request of a stream touches (all (N,) int64 unless said otherwise).

    ``row``: texture * MAX_LEVELS + level; ``group_row``: the row of the level group's top level
    (the request's own row for raw levels); ``bx``, ``by``: block coordinates in the row's grid
    (:func:`row_grids`); ``cell``: the block's index in the flat per-row count array; ``key``: one
    number per distinct block of the set (a group block is the same key from every level of its
    group), the unit of the block buffer and cache; ``compressed``: bool; ``index_word``: word ``w``
    of the index (-1 for raw); ``straddle``: bool, the index also reads ``w+1``; ``entry``: codebook
    memory entry read (-1 for raw); ``codeword``: the index, codeword number in its codebook (-1 for
    raw); ``raw_word``: raw memory word (-1 for compressed).
    """
    row: np.ndarray
    group_row: np.ndarray
    bx: np.ndarray
    by: np.ndarray
    cell: np.ndarray
    key: np.ndarray
    compressed: np.ndarray
    index_word: np.ndarray
    straddle: np.ndarray
    entry: np.ndarray
    codeword: np.ndarray
    raw_word: np.ndarray


def request_blocks(ts: TextureSet, reqs: np.ndarray, grids=None) -> RequestBlocks:
    """The blocks, words and entries each request of ``reqs`` (N, 4) reads (see :class:`RequestBlocks`).

    The descriptor fields are gathered per request from the (texture, level) row, every request
    computed as if compressed and as if raw, and the two merged (no boolean subsetting of
    structured arrays: the cost is a few passes over N int64)."""
    reqs = np.asarray(reqs, np.int64).reshape(-1, 4)
    tex, level, i, j = reqs.T
    nbx, nby, offset = row_grids(ts) if grids is None else grids
    row = tex * MAX_LEVELS + level
    fields = ("compressed", "sublevel", "log2w", "log2h", "log2bw", "log2bh", "index_bits", "base", "cb_base", "layout")
    d = {name: ts.descriptors[name].ravel().astype(np.int64)[row] for name in fields}
    comp = d["compressed"].astype(bool)
    d["index_bits"] = np.where(comp, d["index_bits"], 1)      # raw rows: any width; their results are dropped
    sub = np.where(comp, d["sublevel"], 0)
    group_row = row - sub
    lbw, lbh = np.where(comp, d["log2bw"], 0), np.where(comp, d["log2bh"], 0)
    d["log2bw"], d["log2bh"] = lbw, lbh
    k, _, _ = block_address(d, i, j)
    bx, by = i >> lbw, j >> lbh
    index_word = np.where(comp, d["base"] + (k * d["index_bits"]) // ts.word_bits, -1)
    straddle = straddles(d, k, ts.word_bits) & comp
    codeword = np.where(comp, read_index(ts, d, np.where(comp, k, 0)), -1)
    entry = np.where(comp, d["cb_base"] + codeword, -1)
    raw_word = np.where(comp, -1, d["base"] + (j << d["log2w"]) + i)
    own_nbx = nbx.ravel()[row]
    cell = offset.ravel()[row] + by * own_nbx + bx
    # A group block's key names the group's top row and the block (the same grid for every level of
    # the group); a raw texel's, its own row and texel. Rows have at most 2^24 blocks or texels.
    key = (group_row << 24) | (by * own_nbx + bx)
    return RequestBlocks(row, group_row, bx, by, cell, key, comp, index_word, straddle, entry, codeword, raw_word)


def buffer_hits(keys: np.ndarray) -> np.ndarray:
    """True where a request reads the same block as the request before it (a one-entry block buffer)."""
    keys = np.asarray(keys)
    hit = np.zeros(len(keys), bool)
    hit[1:] = keys[1:] == keys[:-1]
    return hit


def cache_hits(keys: np.ndarray, sets: np.ndarray, ways: int = 2) -> np.ndarray:
    """True where a request hits a ``ways``-way LRU cache, initially empty, whose set for each
    request is ``sets`` (a function of the key): :func:`golden.memory.cache.classify`."""
    keys = np.asarray(keys, np.int64)
    sets = np.asarray(sets, np.int64)
    if ways < 1 or ways & (ways - 1):
        raise ValueError(f"ways must be a power of two, not {ways}")
    if not len(keys):
        return np.zeros(0, bool)
    return classify(keys, sets, int(sets.max()) + 1, ways).hit


@dataclass
class FrameNeed:
    """One frame's figures (all ints): requests; distinct index words, codebook entries and raw words
    read; distinct blocks; index reads that straddle; block buffer and cache hits."""
    frame: int
    requests: int
    index_words: int
    codebook_entries: int
    raw_words: int
    blocks: int
    straddling_reads: int
    buffer_hits: int
    cache_hits: int

    def to_dict(self) -> dict:
        return dict(self.__dict__)


@dataclass
class Need:
    """What the analysed frames touch in ``ts``.

    Members
    -------
    counts : int64 flat array, requests per block of every row (:func:`row_grids` layout)
    codewords : list of bool arrays, per codebook, the codewords touched blocks use
    index_words, codebook_entries, raw_words : bool arrays over each memory, touched by any frame
    frames : list of :class:`FrameNeed`
    """
    ts: TextureSet
    cache: CacheSpec
    counts: np.ndarray
    grids: tuple
    codewords: list
    index_words: np.ndarray
    codebook_entries: np.ndarray
    raw_words: np.ndarray
    frames: list = field(default_factory=list)

    # -- what is touched -------------------------------------------------------------------------
    @property
    def levels(self) -> np.ndarray:
        """bool (n_textures, MAX_LEVELS): levels with at least one request."""
        nbx, nby, offset = self.grids
        size = (nbx * nby).ravel()
        off = offset.ravel()
        out = np.zeros(size.shape, bool)
        for r in np.flatnonzero(size):                   # a loop over levels; no copy of the counts
            out[r] = bool(self.counts[off[r]: off[r] + size[r]].any())
        return out.reshape(nbx.shape)

    @property
    def textures(self) -> np.ndarray:
        """bool (n_textures,): textures with at least one request."""
        return self.levels.any(axis=1)

    def blocks(self, tex: int, level: int) -> np.ndarray:
        """Requests per block of (tex, level), (nby, nbx) int64 (a raw level: per texel)."""
        nbx, nby, offset = self.grids
        w, h, o = int(nbx[tex, level]), int(nby[tex, level]), int(offset[tex, level])
        return self.counts[o: o + w * h].reshape(h, w)

    def touched_blocks(self, tex: int, level: int) -> np.ndarray:
        """bool (nby, nbx): blocks of (tex, level) with a request."""
        return self.blocks(tex, level) > 0

    def group_blocks(self, tex: int, top: int) -> np.ndarray:
        """bool (nby, nbx): blocks of the level group starting at ``top`` touched from any of its levels."""
        d = self.ts.descriptors[tex]
        out = None
        for L in range(top, min(self.ts.textures[tex].levels, top + 3)):     # at most 3 levels a group
            if d["valid"][L] and d["compressed"][L] and L - int(d["sublevel"][L]) == top:
                b = self.touched_blocks(tex, L)
                out = b if out is None else out | b
        return out

    @property
    def groups(self) -> list[tuple[int, int, list[int]]]:
        """Touched level groups: (texture, top level, [touched levels of the group]); a raw level is a
        group of its own."""
        d = self.ts.descriptors
        lv = self.levels
        out = {}
        for t, L in zip(*np.nonzero(lv)):
            t, L = int(t), int(L)
            top = L - int(d["sublevel"][t, L]) if d["compressed"][t, L] else L
            out.setdefault((t, top), []).append(L)
        return [(t, top, levels) for (t, top), levels in sorted(out.items())]

    def formats(self) -> dict:
        """Colour formats ("raw" for raw levels), index widths and sub-levels of the touched levels."""
        d = self.ts.descriptors[self.levels]
        comp = d["compressed"].astype(bool)
        colors = sorted({COLORS[int(c)] for c in d["color"][comp]}) + (["raw"] if (~comp).any() else [])
        return {"colors": colors, "index_bits": sorted({int(b) for b in d["index_bits"][comp]}),
                "sublevels": sorted({int(s) for s in d["sublevel"][comp]})}

    # -- the report -------------------------------------------------------------------------------
    def summary(self, per_frame: bool = True) -> dict:
        """The report as plain JSON values: touched against stored, per texture, totals and frames."""
        ts = self.ts
        lv = self.levels
        d = ts.descriptors
        valid = d["valid"].astype(bool)
        comp = d["compressed"].astype(bool) & valid
        textures = []
        for t, info in enumerate(ts.textures):
            rows = []
            for L in range(info.levels):
                if not valid[t, L]:
                    continue
                b = self.blocks(t, L)
                rows.append({"level": L, "touched": bool(lv[t, L]), "kind": "compressed" if comp[t, L] else "raw",
                             "blocks": int(b.size), "blocks_touched": int((b > 0).sum()), "requests": int(b.sum())})
            textures.append({"texture": t, "name": info.name, "touched": bool(lv[t].any()),
                             "levels": info.levels, "levels_touched": [int(L) for L in np.flatnonzero(lv[t])],
                             "level_rows": rows})
        codebooks = [{"codebook": c, "size": cb.size, "used": int(self.codewords[c].sum())}
                     for c, cb in enumerate(ts.codebooks)]
        groups = self.groups
        stored_groups = {}                            # (texture, top) -> blocks of its map (0: a raw level)
        for t, L in zip(*np.nonzero(valid)):
            t, L = int(t), int(L)
            top = L - int(d["sublevel"][t, L]) if comp[t, L] else L
            stored_groups[(t, top)] = int(self.grids[0][t, L] * self.grids[1][t, L]) if comp[t, L] else 0
        n_groups = len(stored_groups)
        group_blocks = sum(int(self.group_blocks(t, top).sum()) for t, top, _ in groups if stored_groups[(t, top)])
        fr = self.frames
        total = {
            "frames": len(fr), "requests": sum(f.requests for f in fr),
            "buffer_hits": sum(f.buffer_hits for f in fr), "cache_hits": sum(f.cache_hits for f in fr),
            "straddling_reads": sum(f.straddling_reads for f in fr),
        }
        stored = {"index_words": int(len(ts.index_words)), "codebook_entries": int(len(ts.codebook)),
                  "raw_words": int(len(ts.raw_words)), "index_word_bytes": ts.word_bits // 8,
                  "entry_bytes": ts.entry_bytes, "raw_word_bytes": 4}
        touched = {"index_words": int(self.index_words.sum()), "codebook_entries": int(self.codebook_entries.sum()),
                   "raw_words": int(self.raw_words.sum())}
        out = {
            "textures": {"stored": int(valid.any(axis=1).sum()), "touched": int(self.textures.sum())},
            "levels": {"stored": int(valid.sum()), "touched": int(lv.sum())},
            "level_groups": {"stored": n_groups, "touched": len(groups)},
            "compressed_blocks": {"stored": sum(stored_groups.values()), "touched": group_blocks},
            "codewords": {"stored": int(sum(cb.size for cb in ts.codebooks)),
                          "used": int(sum(int(c.sum()) for c in self.codewords))},
            "formats": self.formats(),
            "memory_stored": stored, "memory_touched": touched,
            "cache": {"sets": self.cache.sets, "ways": self.cache.ways, "blocks": self.cache.blocks,
                      "policy": self.cache.describe()},
            "totals": total,
            "texture_detail": textures, "codebook_detail": codebooks,
        }
        if per_frame:
            out["per_frame"] = [f.to_dict() for f in fr]
        return out


class NeedCounter:
    """:func:`analyse` one frame at a time (a renderer feeds each frame's requests as it goes, so no
    frame's stream is kept): ``add(frame, reqs)`` for each frame, then ``result()``. With
    ``per_frame=False`` only what is touched is counted (no per-frame figures: faster, for pruning)."""

    def __init__(self, ts: TextureSet, cache: CacheSpec = CacheSpec(), per_frame: bool = True):
        self.ts, self.cache, self.per_frame = ts, cache, per_frame
        self.grids = row_grids(ts)
        nbx, nby, offset = self.grids
        self.counts = np.zeros(int((offset + nbx * nby).max(initial=0)), np.int64)
        self.idx_seen = np.zeros(len(ts.index_words), bool)
        self.ent_seen = np.zeros(len(ts.codebook), bool)
        self.raw_seen = np.zeros(len(ts.raw_words), bool)
        self.frames: list[FrameNeed] = []
        d = ts.descriptors
        self._comp = (d["compressed"].astype(bool) & d["valid"].astype(bool)).ravel()
        self._sub = d["sublevel"].astype(np.int64).ravel()
        self._lbw = np.where(self._comp, d["log2bw"].astype(np.int64).ravel(), 0)
        self._lbh = np.where(self._comp, d["log2bh"].astype(np.int64).ravel(), 0)
        self._nbx, self._offset = nbx.ravel(), offset.ravel()

    def add(self, frame: int, reqs: np.ndarray) -> FrameNeed:
        """Count one frame's requests (valid for the set); returns its :class:`FrameNeed` (None
        without ``per_frame``).

        Per request only its block is computed (a few shifts); the index, codeword and memory words
        are read once per distinct block of the frame (:func:`request_blocks` on one request of
        each), which gives the same distinct words and entries."""
        cache = self.cache
        reqs = np.asarray(reqs, np.int64).reshape(-1, 4)
        tex, level, i, j = reqs.T
        row = tex * MAX_LEVELS + level
        comp = self._comp[row]
        lbw, lbh = self._lbw[row], self._lbh[row]
        bx, by = i >> lbw, j >> lbh
        own_nbx = self._nbx[row]
        cell = self._offset[row] + by * own_nbx + bx
        frame_counts = np.bincount(cell, minlength=len(self.counts))
        self.counts += frame_counts
        touched = np.flatnonzero(frame_counts)
        rep = np.zeros(len(self.counts), np.int64)
        rep[cell] = np.arange(len(cell))                 # one request of each touched block
        rb = request_blocks(self.ts, reqs[rep[touched]], self.grids)
        c = rb.compressed
        words = np.unique(np.concatenate([rb.index_word[c], rb.index_word[c & rb.straddle] + 1]))
        entries = np.unique(rb.entry[c])
        raws = rb.raw_word[~c]                           # one texel per raw "block": already distinct
        self.idx_seen[words] = True
        self.ent_seen[entries] = True
        self.raw_seen[raws] = True
        if not self.per_frame:
            return None
        key = ((row - np.where(comp, self._sub[row], 0)) << 24) | (by * own_nbx + bx)
        sets = (by & (cache.tile[1] - 1)) * cache.tile[0] + (bx & (cache.tile[0] - 1))
        fn = FrameNeed(
            frame=int(frame), requests=int(len(reqs)), index_words=int(len(words)),
            codebook_entries=int(len(entries)), raw_words=int(len(raws)), blocks=int(len(np.unique(rb.key))),
            straddling_reads=int((frame_counts[touched] * (rb.straddle & c)).sum()),
            buffer_hits=int(buffer_hits(key).sum()), cache_hits=int(cache_hits(key, sets, cache.ways).sum()))
        self.frames.append(fn)
        return fn

    def result(self) -> Need:
        codewords = [self.ent_seen[cb.base: cb.base + cb.size].copy() for cb in self.ts.codebooks]
        return Need(self.ts, self.cache, self.counts.copy(), self.grids, codewords, self.idx_seen.copy(),
                    self.ent_seen.copy(), self.raw_seen.copy(), list(self.frames))


def analyse(ts: TextureSet, streams, frames=None, cache: CacheSpec = CacheSpec(), per_frame: bool = True) -> Need:
    """The :class:`Need` of the request ``streams`` (an iterable of (N, 4) arrays, one per frame, or
    of (frame number, array) pairs) in ``ts``. ``frames`` numbers the streams (default 0, 1, ...);
    ``per_frame=False`` skips the per-frame figures (:class:`NeedCounter`)."""
    counter = NeedCounter(ts, cache, per_frame)
    frames = iter(frames) if frames is not None else None
    for n, item in enumerate(streams):
        if isinstance(item, tuple):
            f, reqs = item
        else:
            f, reqs = (next(frames) if frames is not None else n), item
        counter.add(f, reqs)
    return counter.result()


def heat_image(need: Need, tex: int, level: int, min_side: int = 256) -> np.ndarray:
    """A picture (H, W, 4) uint8 of the blocks of (tex, level): one square of pixels per block (per
    texel for a raw level), enlarged by a whole factor until the longer side is at least
    ``min_side``. Untouched blocks are dark blue-grey; touched ones go from red (one request) through
    yellow to white (the level's most requested block), on a log scale."""
    counts = need.blocks(tex, level)
    h, w = counts.shape
    out = np.empty((h, w, 4), np.uint8)
    out[...] = (32, 36, 52, 255)
    touched = counts > 0
    if touched.any():
        top = np.log1p(counts.max())
        x = np.log1p(counts[touched]) / top if top > 0 else np.ones(int(touched.sum()))
        ramp = np.array([[120, 0, 0], [230, 40, 20], [255, 200, 0], [255, 255, 255]], np.float64)
        pos = x * (len(ramp) - 1)
        lo = np.minimum(np.floor(pos).astype(np.int64), len(ramp) - 2)
        frac = (pos - lo)[:, None]
        out[touched, :3] = np.clip(np.rint(ramp[lo] * (1 - frac) + ramp[lo + 1] * frac), 0, 255).astype(np.uint8)
    scale = max(1, -(-min_side // max(h, w, 1)))
    return np.repeat(np.repeat(out, scale, axis=0), scale, axis=1)


def distinct_requests(streams) -> np.ndarray:
    """The distinct requests (M, 4) int64 of several request streams (each (N, 4), valid: sizes up to
    4096 and at most 4096 textures), sorted by (texture, level, j, i): what a set must hold to answer
    them all. Per stream one sort; the union is kept as 40-bit keys."""
    acc = np.zeros(0, np.int64)
    for reqs in streams:
        r = np.asarray(reqs, np.int64).reshape(-1, 4)
        key = ((((r[:, 0] * MAX_LEVELS + r[:, 1]) << 12) | r[:, 3]) << 12) | r[:, 2]
        acc = np.union1d(acc, key)
    mask = (1 << 12) - 1
    row = acc >> 24
    return np.stack([row // MAX_LEVELS, row % MAX_LEVELS, acc & mask, (acc >> 12) & mask], 1)


def scene_level_shapes(scene) -> list[list[tuple[int, int]]]:
    """Per scene texture, the (width, height) of every level the scene's encoding gives it (a full
    pyramid down to 1x1 with mipmaps, else level 0 only): enough to issue the scene's requests
    before anything is encoded."""
    out = []
    for t in scene.textures:
        w, h = (int(v) for v in t.size)
        levels = 1 + max(w.bit_length() - 1, h.bit_length() - 1) if t.encoding.get("mipmaps", True) else 1
        out.append([(max(1, w >> L), max(1, h >> L)) for L in range(levels)])
    return out


def scene_streams(scene, source, frames, mode: str = "trilinear", **options):
    """Yield (frame, requests (N, 4) int64) of ``frames`` of ``scene``; ``source`` is a TextureSet,
    any texture source with ``level_shapes``, or the list of level shapes per texture; ``options``
    are ``golden.render.frame.frame_requests``'s (``stream="sparse"`` or ``"fixed"``, ``fovea``)."""
    from ..render.frame import frame_requests
    for f in frames:
        reqs, _ = frame_requests(scene, f, source, mode, **options)
        yield f, reqs
