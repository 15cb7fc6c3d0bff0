"""The cached unit's memory configuration, and the references a request stream makes.

Where textures live (the layout)
--------------------------------
With external memory the index memory and the raw memory of a texture set are two regions of one
byte-addressed memory: the index memory's word ``w`` (``word_bits / 8`` bytes, little-endian, as
``golden.format`` packs it) at byte ``index_base + w * word_bytes``, the raw memory's word ``r`` (one
RGBA8888 texel, 4 bytes) at ``raw_base + 4 * r``. ``index_base`` is 0 and ``raw_base`` the index
memory's size rounded up to 4 KB. The codebook stays on chip (loaded through the bus port): it is
small (at most a few tens of KB) and read by every texel, so a cache in front of it would hit almost
always and cost a third tag path.

What a request reads
--------------------
A request of a compressed level reads index word ``w`` (and ``w + 1`` when its index straddles a word
boundary): one reference to the index cache, two when the two words lie in different lines. A
request of a raw level reads raw word ``r``: one reference to the raw cache. References are made in
request order, ``w`` before ``w + 1``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..fetch import block_address, lookup_descriptor, straddles
from ..format import TextureSet
from .cache import CacheShape
from .dram import PARTS, DramMemory
from .external import FixedMemory, beat_interval

__all__ = ["MemoryConfig", "Layout", "References", "references", "request_words", "MEMORY_KINDS", "RAW_WORD_BYTES"]

#: ``--memory-model``: a fixed latency and bandwidth, or a DRAM part.
MEMORY_KINDS = ("fixed", "dram")
#: Bytes per raw word (one RGBA8888 texel).
RAW_WORD_BYTES = 4


@dataclass(frozen=True)
class MemoryConfig:
    """How the cached unit reaches its textures.

    Arguments
    ---------
    index_cache, raw_cache : CacheShape
        The two caches (default 16 KB and 4 KB, 32-byte lines, 4 ways).
    prefetch : int
        Depth of the FIFO of references between the tag check and the data read (Igehy et al.'s
        prefetching); 1 is the blocking cache (a miss stalls the next tag check until its data is
        read). At least 1. The default, 128, is the default latency (100 cycles) rounded up to a
        power of two: Igehy et al. size the FIFO to the memory's latency, and at that depth a miss
        is hidden behind the references queued after it (docs/memory.md, "Town's 0.927").
    kind : str
        ``"fixed"`` (:class:`golden.memory.external.FixedMemory`) or ``"dram"``
        (:class:`golden.memory.dram.DramMemory`).
    latency, bandwidth : int
        The fixed memory's cycles from AR to the first beat (>= 1) and bytes per clock.
    bus_bytes : int
        The AXI data width in bytes (a power of two, at most every cache line).
    dram_part, clock_mhz, controller_cycles
        The DRAM's part (a name in ``golden.memory.dram.PARTS``), the controller's clock and its own
        latency in cycles.

    Raises ValueError on anything out of range (one line, naming the value).
    """
    index_cache: CacheShape = field(default_factory=lambda: CacheShape(16384, 32, 4))
    raw_cache: CacheShape = field(default_factory=lambda: CacheShape(4096, 32, 4))
    prefetch: int = 128
    kind: str = "fixed"
    latency: int = 100
    bandwidth: int = 16
    bus_bytes: int = 16
    dram_part: str = "MT41K256M16-125"
    clock_mhz: float = 200.0
    controller_cycles: int = 0

    def __post_init__(self):
        if not isinstance(self.index_cache, CacheShape) or not isinstance(self.raw_cache, CacheShape):
            raise ValueError("caches must be CacheShape values")
        if not isinstance(self.prefetch, int) or isinstance(self.prefetch, bool) or not 1 <= self.prefetch <= 4096:
            raise ValueError(f"prefetch FIFO depth must be 1 (blocking) to 4096, not {self.prefetch!r}")
        if self.kind not in MEMORY_KINDS:
            raise ValueError(f"memory model {self.kind!r}: choose {', '.join(MEMORY_KINDS)}")
        b = self.bus_bytes
        if not isinstance(b, int) or b < 1 or b & (b - 1) or b > 128:
            raise ValueError(f"AXI data width {b!r} bytes must be a power of two up to 128")
        for name, c in (("index", self.index_cache), ("raw", self.raw_cache)):
            if c.line < b:
                raise ValueError(f"{name} cache line {c.line} bytes is narrower than the {b}-byte bus")
            if c.line // b > 256:
                raise ValueError(f"{name} cache line {c.line} bytes is more than 256 beats of {b} bytes")
        if self.index_cache.sets < 2:
            raise ValueError("the index cache needs at least two sets: the two lines of a straddling index "
                             "are looked up together, in two sets")
        if self.kind == "fixed":
            if not isinstance(self.latency, int) or not 1 <= self.latency <= 100000:
                raise ValueError(f"memory latency {self.latency!r} must be 1 to 100000 cycles")
            beat_interval(b, self.bandwidth)
        else:
            if self.dram_part not in PARTS:
                raise ValueError(f"DRAM part {self.dram_part!r}: choose {', '.join(PARTS)}")
            self.make_memory()

    def make_memory(self):
        """A fresh memory model of this configuration (the read contract of ``external``)."""
        if self.kind == "fixed":
            return FixedMemory(self.latency, self.bandwidth, self.bus_bytes)
        return DramMemory(PARTS[self.dram_part], bus_bytes=self.bus_bytes, clock_mhz=self.clock_mhz,
                          controller_cycles=self.controller_cycles)

    def describe(self) -> str:
        mode = "blocking" if self.prefetch == 1 else f"prefetching, {self.prefetch}-entry reference FIFO"
        return (f"index cache {self.index_cache.describe()}; raw cache {self.raw_cache.describe()}; {mode}; "
                f"memory {self.make_memory().describe()}")


@dataclass(frozen=True)
class Layout:
    """Byte addresses of a texture set's index and raw memories in external memory."""
    index_base: int
    raw_base: int
    word_bytes: int
    end: int

    def image(self, ts: TextureSet) -> bytes:
        """The external memory's bytes for ``ts``: what a host writes there, zero-padded to a whole
        number of 4 KB pages (a cache line past ``end`` reads zeros)."""
        img = bytearray(-(-self.end // 4096) * 4096)
        idx = np.asarray(ts.index_words).astype(f"<u{self.word_bytes}").tobytes()
        img[self.index_base: self.index_base + len(idx)] = idx
        raw = np.asarray(ts.raw_words).astype("<u4").tobytes()
        img[self.raw_base: self.raw_base + len(raw)] = raw
        return bytes(img)

    @classmethod
    def of(cls, ts: TextureSet) -> "Layout":
        wb = ts.word_bits // 8
        index_bytes = len(ts.index_words) * wb
        raw_base = -(-index_bytes // 4096) * 4096
        return cls(0, raw_base, wb, raw_base + len(ts.raw_words) * RAW_WORD_BYTES)

    @classmethod
    def at(cls, ts: TextureSet, index_base: int, raw_base: int | None = None) -> "Layout":
        """``ts`` placed by a host at byte ``index_base`` (a multiple of the index word's bytes) and
        ``raw_base`` (a multiple of 4; default: the first 4 KB boundary after the index memory), as the
        loadable cached unit's ``INDEX_BASE`` and ``RAW_BASE`` registers say (:mod:`golden.register_map`).
        The index memory must lie below the raw memory and both inside the AXI master's 4 GB.

        Raises ValueError (one line) on a misaligned or overlapping placement."""
        wb = ts.word_bits // 8
        index_bytes = len(ts.index_words) * wb
        if not isinstance(index_base, int) or index_base < 0 or index_base % wb:
            raise ValueError(f"index base {index_base!r} must be a non-negative multiple of {wb} bytes")
        if raw_base is None:
            raw_base = -(-(index_base + index_bytes) // 4096) * 4096
        if not isinstance(raw_base, int) or raw_base % RAW_WORD_BYTES or raw_base < index_base + index_bytes:
            raise ValueError(f"raw base {raw_base!r} must be a multiple of 4 at or above the index memory's end "
                             f"({index_base + index_bytes:#x})")
        end = raw_base + len(ts.raw_words) * RAW_WORD_BYTES
        if -(-end // 4096) * 4096 > 1 << 32:
            raise ValueError(f"the texture set ends at byte {end:#x}, past the AXI master's 4 GB")
        return cls(index_base, raw_base, wb, end)

    def raw_bursts(self, addresses) -> np.ndarray:
        """Which of the bursts at byte ``addresses`` read the raw memory (bool array; else the index)."""
        return np.asarray(addresses, np.int64) >= self.raw_base


@dataclass
class References:
    """The cache references of a request stream, in order (all (M,) int64 but ``cache``).

    ``request``: the request making it; ``cache``: 0 index, 1 raw (int8); ``line``: the line number
    (byte address / that cache's line size)."""
    request: np.ndarray
    cache: np.ndarray
    line: np.ndarray


def request_words(ts: TextureSet, requests: np.ndarray):
    """What each request reads, vectorised: (compressed bool, index word ``w``, straddle bool, raw
    word ``r``), all (N,); ``w`` and ``straddle`` are 0 for raw requests, ``r`` is 0 for compressed."""
    req = np.asarray(requests, np.int64).reshape(-1, 4)
    n = len(req)
    comp = np.zeros(n, bool)
    word = np.zeros(n, np.int64)
    strad = np.zeros(n, bool)
    raw = np.zeros(n, np.int64)
    if n:
        d = lookup_descriptor(ts, req[:, 0], req[:, 1])
        comp = d["compressed"].astype(bool)
        if comp.any():
            dc = d[comp]
            k, _, _ = block_address(dc, req[comp, 2], req[comp, 3])
            b = dc["index_bits"].astype(np.int64)
            word[comp] = dc["base"].astype(np.int64) + (k * b) // ts.word_bits
            strad[comp] = straddles(dc, k, ts.word_bits)
        r = ~comp
        if r.any():
            dr = d[r]
            raw[r] = dr["base"].astype(np.int64) + (req[r, 3] << dr["log2w"].astype(np.int64)) + req[r, 2]
    return comp, word, strad, raw


def references(ts: TextureSet, requests: np.ndarray, config: MemoryConfig, layout: Layout | None = None) -> References:
    """The references ``requests`` ((N, 4) texture, level, i, j; valid for ``ts``) make, vectorised."""
    layout = layout or Layout.of(ts)
    comp, word, strad, raw = request_words(ts, requests)
    n = len(comp)
    il, rl = config.index_cache.line, config.raw_cache.line
    first = np.where(comp, (layout.index_base + word * layout.word_bytes) // il,
                     (layout.raw_base + raw * RAW_WORD_BYTES) // rl)
    second_line = (layout.index_base + (word + 1) * layout.word_bytes) // il
    two = comp & strad & (second_line != first)
    count = 1 + two
    request = np.repeat(np.arange(n), count)
    pos = np.cumsum(count) - count                        # each request's first reference
    line = np.empty(int(count.sum()), np.int64)
    line[pos] = first
    line[pos[two] + 1] = second_line[two]
    cache = np.repeat(np.where(comp, 0, 1).astype(np.int8), count)
    return References(request, cache, line)
