"""Every formal property of the hardware, in the order ``vqtex verify`` runs them
(docs/verification.md has the table). Each is proved on the small sets of :mod:`hw.formal.sets`."""

from __future__ import annotations

import fnmatch

from ..filter.texture_filter import LATENCY as FILTER_LATENCY
from ..texel_fetch import LATENCY, UPSTREAM_STAGES, TexelFetch
from . import address, features, index_reader, memory, texture_filter
from . import texel_fetch as fetch
from .harness import Property
from .sets import pvr2_set, rgb_set, yuv_set

__all__ = ["PROPERTIES", "select"]


def _unit(**kw):
    return lambda: TexelFetch(yuv_set(), **kw)


_STREAM = "the {}'s output keeps valid and payload until ready, under any requests and backpressure"
_ORDER = ("the {} never loses, duplicates or reorders a response, and each leaves after exactly LATENCY "
          "cycles of free output")
_INDEX = "the index reader{} equals golden's read_index for every k, b and base of an index in the memory"
#: The depths that follow the pipeline's latency: a seeded bug in the texel pipeline shows at its
#: output within LATENCY + 3 cycles of reset; the miters' induction depth and their bug's; the
#: filter's bug (its LATENCY + 2).
_FETCH_BUG = LATENCY + 3
_MITER_K, _MITER_BUG = LATENCY + 3, LATENCY + 1
_FILTER_BUG = FILTER_LATENCY + 2

PROPERTIES = (
    Property("texel_fetch.stream.specialised", "texel_fetch", _STREAM.format("specialised unit"),
             lambda bug: fetch.StreamHarness(_unit(), bug), "induction", 3, fetch.SKID_NEVER_SHOWS, _FETCH_BUG, quick=True),
    Property("texel_fetch.stream.full", "texel_fetch", _STREAM.format("full unit"),
             lambda bug: fetch.StreamHarness(_unit(specialise=False), bug), "induction", 3, fetch.SKID_NEVER_SHOWS, _FETCH_BUG),
    Property("texel_fetch.stream.one_port", "texel_fetch", _STREAM.format("one-port unit"),
             lambda bug: fetch.StreamHarness(_unit(one_port=True), bug), "induction", 3, fetch.SKID_NEVER_SHOWS, _FETCH_BUG),
    Property("texel_fetch.stream.loadable", "texel_fetch",
             _STREAM.format("loadable unit") + ", and any traffic on its bus port",
             lambda bug: fetch.StreamHarness(_unit(loadable=True), bug), "induction", 3, fetch.SKID_NEVER_SHOWS, _FETCH_BUG),
    Property("texel_fetch.order.specialised", "texel_fetch", _ORDER.format("specialised unit"),
             lambda bug: fetch.OrderHarness(_unit(), bug), "induction", 3, fetch.SKID_SHOWS_TWICE, _FETCH_BUG, quick=True),
    Property("texel_fetch.order.full", "texel_fetch", _ORDER.format("full unit"),
             lambda bug: fetch.OrderHarness(_unit(specialise=False), bug), "induction", 3, fetch.SKID_NEVER_SHOWS, _FETCH_BUG),
    Property("texel_fetch.order.one_port", "texel_fetch",
             "the one-port unit never loses, duplicates or reorders a response, and each leaves after exactly "
             f"LATENCY cycles of free output plus one per one-port bubble it waited behind (at most {UPSTREAM_STAGES})",
             lambda bug: fetch.OrderHarness(_unit(one_port=True), bug), "induction", 3, fetch.HOLD_IGNORED, _FETCH_BUG),
    Property("texel_fetch.order.loadable", "texel_fetch", _ORDER.format("loadable unit") + ", whatever its bus port does",
             lambda bug: fetch.OrderHarness(_unit(loadable=True), bug), "induction", 3, fetch.SKID_NEVER_SHOWS, _FETCH_BUG,
             quick_control=False),
    Property("address.formula", "address",
             "the block address shifter equals golden's block_address (k, x, y, raw address) for every valid request",
             lambda bug: address.AddressHarness(False, bug), "induction", 1, address.ROW_SHIFT_USES_HEIGHT, 2,
             quick=True),
    Property("address.twiddled", "address",
             "the PowerVR2 shifter equals golden's block_address with twiddled_block, both layouts, every valid request",
             lambda bug: address.AddressHarness(True, bug), "induction", 1, address.TWIDDLE_LARGER_SIDE, 2),
    Property("index_reader.formula.w32", "index_reader", _INDEX.format(" (full, 32-bit words)"),
             lambda bug: index_reader.IndexReaderHarness(32, None, bug), "induction", 6,
             index_reader.MASK_ONE_BIT_WIDE, 6, quick=True),
    Property("index_reader.formula.w64", "index_reader", _INDEX.format(" (full, 64-bit words)"),
             lambda bug: index_reader.IndexReaderHarness(64, None, bug), "induction", 6,
             index_reader.PAIR_NOT_ORDERED, 6),
    Property("index_reader.formula.w16_b3_5_12", "index_reader",
             _INDEX.format(" (specialised to b = 3, 5, 12, 16-bit words)"),
             lambda bug: index_reader.IndexReaderHarness(16, (3, 5, 12), bug), "induction", 6,
             index_reader.PAIR_NOT_ORDERED, 6),
    Property("features.miter.yuv", "features",
             "the specialised unit answers every valid request as the full unit does (a yuv411 set with straddling "
             "12-bit indices, mipmaps and raw levels; output always ready)",
             lambda bug: features.MiterHarness(yuv_set, False, bug), "induction", _MITER_K, features.MATRIX_SHIFT_SHORT,
             _MITER_BUG),
    Property("features.miter.rgb", "features",
             "the same for a set of two rgb textures with 8-bit indices (constant descriptor fields, no colour "
             "matrix, one index bank; output always ready)",
             lambda bug: features.MiterHarness(rgb_set, False, bug), "induction", _MITER_K, features.TEXEL_STRIDE_SHORT,
             _MITER_BUG, quick_control=False),
    Property("features.miter.pvr2", "features",
             "the same for a PowerVR2 set (argb1555 8x8 and yuv422 16x8: twiddled maps, texel expansion, the "
             "Dreamcast matrix) against the PowerVR2 unit (output always ready)",
             lambda bug: features.MiterHarness(pvr2_set, False, bug), "induction", _MITER_K, features.TWIDDLE_SQUARE_LARGER,
             _MITER_BUG, quick_control=False),
    Property("features.miter.yuv_backpressure", "features",
             "the specialised unit answers every valid request as the full unit does, under any backpressure",
             lambda bug: features.MiterHarness(yuv_set, True, bug), "bmc", LATENCY + 6, features.MATRIX_SHIFT_SHORT, _MITER_BUG,
             quick_control=False),
    Property("texture_filter.stream.lanes1", "texture_filter",
             "every stream of the one-lane texture filter (output, footprint, lane requests and responses) keeps "
             "valid and payload until ready, under any requests and backpressure",
             lambda bug: texture_filter.FilterStreamHarness(yuv_set, 1, bug), "induction", 3,
             texture_filter.BLEND_IGNORES_READY, _FILTER_BUG),
    Property("texture_filter.stream.lanes2", "texture_filter",
             "every stream of the two-lane texture filter (the lanes sharing the index memory's parity banks) "
             "keeps valid and payload until ready, under any requests and backpressure",
             lambda bug: texture_filter.FilterStreamHarness(yuv_set, 2, bug), "induction", 3,
             texture_filter.BLEND_IGNORES_READY, _FILTER_BUG, quick_control=False),
    Property("memory.reader.prefetch", "memory",
             "every word the cached reader (2-entry FIFO) hands on is the memory's word at its request's address, "
             "and no line is read twice while its burst is in flight, under any requests, backpressure and memory "
             "timing (a free AXI slave)",
             lambda bug: memory.ReaderHarness(2, 16, bug), "bmc", 15, memory.DATA_READ_EARLY, 15),
    Property("memory.reader.blocking", "memory",
             "the same for the blocking cached reader (one reference waits at a time)",
             lambda bug: memory.ReaderHarness(1, 16, bug), "bmc", 20, memory.wrong_lane(4, 16), 20),
)


def select(patterns=None, quick: bool = False) -> list:
    """The properties whose names match any of the shell-style ``patterns`` (all when None), only
    the quick ones with ``quick``; raises ``KeyError`` naming a pattern that matches none."""
    chosen = list(PROPERTIES)
    if patterns:
        for pat in patterns:
            if not any(fnmatch.fnmatchcase(p.name, pat) for p in PROPERTIES):
                raise KeyError(pat)
        chosen = [p for p in chosen if any(fnmatch.fnmatchcase(p.name, pat) for pat in patterns)]
    return [p for p in chosen if p.quick or not quick]
