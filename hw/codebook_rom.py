"""Codebook ROM: (codebook base + index, offset in the block) -> the texel's raw samples.

Twin of :func:`golden.fetch.read_codeword`, and of the raw-level read in :func:`golden.fetch.fetch`.
The codebook memory holds one wide entry per codeword (``entry_bytes * 8`` bits, byte ``n`` of the
entry in bits ``[8n, 8n+8)``); an extended (mipmap) codeword holds every sub-level, and the
descriptor's plane offsets say where this level's texels (or Y, U, V planes) start. Raw levels read a
32-bit RGBA word from the raw memory through the same four stages. Both memories are banked
(:class:`hw.banked_rom.BankedROM`: 512-entry block RAM banks, each read registered).
"""

from __future__ import annotations

import numpy as np
from amaranth import *
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from vqtex.golden.format import COLOR_CODES

from vqtex.golden.geometry import entry_lanes
from vqtex.golden.register_map import REGIONS

from .banked_rom import BANK_DEPTH, BankedROM
from .pick import pick, pick_group
from .bus_port import DATA_WIDTH, LoadTarget, or_all
from .features import Features
from .copies import register_copies
from .registers import enabled_register

__all__ = ["CodebookROM", "SamplesLayout", "LATENCY", "expand_texel"]

#: Cycles from the index to the samples.
LATENCY = 4
#: The loadable ROM's entries of more 4-byte words than this (``max``'s 336-byte entries: 85 words,
#: against ``paper``'s 22) have their word picks over two stages: a group of ``PICK_GROUP`` words
#: picked in stage 3, the word in the group in stage 4 (docs/area.md, "Block by block").
SPLIT_PICK_WORDS = 32
#: Words per group of a split pick (a power of two).
PICK_GROUP = 4

#: Four 8-bit samples: (R,G,B,A), (R,G,B,-), (I,-,-,-) or (Y,U,V,-) as in ``read_codeword``.
SamplesLayout = data.ArrayLayout(unsigned(8), 4)

_RGB, _RGBA, _YUV = (COLOR_CODES[c] for c in ("rgb", "rgba", "yuv411"))
_ARGB1555, _RGB565, _ARGB4444, _YUV422 = (COLOR_CODES[c] for c in ("argb1555", "rgb565", "argb4444", "yuv422"))
#: Bytes per texel of each colour format (1 for intensity and yuv411's Y; PowerVR2's are 16-bit).
_BYTES_PER_TEXEL = {_RGB: 3, _RGBA: 4, _ARGB1555: 2, _RGB565: 2, _ARGB4444: 2, _YUV422: 2}


def _widen(field: Value) -> Value:
    """A 4-, 5- or 6-bit colour field widened to 8 bits by bit replication (``v << (8-n) | v >> (2n-8)``):
    wiring only."""
    n = len(field)
    return Cat(field, field)[2 * n - 8:] if n < 8 else field


def expand_texel(texel: Value, color: Value, codes=None) -> Value:
    """The 16-bit PowerVR2 texel as R, G, B, A bytes (combinational; twin of
    :func:`golden.fetch.expand_texels`): argb1555 (A = bit 15 replicated), rgb565 (A = 255),
    argb4444. ``codes``: the colour codes that can arrive (default all three; one needs no
    multiplexer)."""
    t = texel
    formats = {
        _ARGB1555: Cat(_widen(t[10:15]), _widen(t[5:10]), _widen(t[0:5]), t[15].replicate(8)),
        _RGB565: Cat(_widen(t[11:16]), _widen(t[5:11]), _widen(t[0:5]), C(255, 8)),
        _ARGB4444: Cat(_widen(t[8:12]), _widen(t[4:8]), _widen(t[0:4]), _widen(t[12:16])),
    }
    present = [c for c in formats if codes is None or c in codes]
    out = formats[present[-1]]
    for code in reversed(present[:-1]):
        out = Mux(color == code, formats[code], out)
    return out


def _entry_ints(codebook: np.ndarray) -> list:
    """Codebook rows -> little-endian integers (byte n in bits 8n..8n+7)."""
    return [int.from_bytes(bytes(row), "little") for row in np.asarray(codebook, dtype=np.uint8)]


class _RawPort(wiring.Component):
    """The raw word of a unit whose raw memory is outside it (``raw_port``): ``data`` registered
    twice on ``en``, the latency of the raw memory it replaces (``word``, as
    :class:`hw.banked_rom.BankedROM` gives it)."""

    def __init__(self):
        super().__init__({"data": In(32), "en": In(1), "word": Out(32)})

    def elaborate(self, platform):
        m = Module()
        first = Signal(32)
        with m.If(self.en):
            m.d.sync += [first.eq(self.data), self.word.eq(first)]
        return m


class CodebookROM(wiring.Component):
    """Codebook memory and raw memory, with the texel select.

    The texel's bytes start at ``start = texel_off + tb * t`` with ``t = (y << log2bw) | x`` and
    ``tb`` = 3, 4, 1, 1 bytes per texel for rgb, rgba, intensity, yuv411 (a byte past the entry
    reads the entry's last byte, as the golden model clamps); for yuv411, samples 1 and 2 are the
    bytes at ``u_off + ct`` and ``v_off + ct`` with ``ct = ((y >> 1) << max(log2bw - 1, 0)) | (x >> 1)``.
    A raw level's samples are the raw word's bytes and its ``color_out`` is rgba. PowerVR2's
    formats (a set with PowerVR2 textures): 16-bit texels (``tb`` = 2); argb1555, rgb565, argb4444
    expanded here to R, G, B, A (:func:`expand_texel`, ``color_out`` rgba); yuv422 as (Y, U, V) with
    Y the texel's high byte and U, V the low bytes of the row's left and right texels at
    ``u_off + 2x``, ``v_off + 2x`` (``color_out`` yuv411: through the colour matrix). Four stages:

    1. *read*: the codebook memory at ``cb_base + index`` and the raw memory at ``raw_addr``; the
       byte addresses ``start``, ``u_off + ct``, ``v_off + ct`` (``tb * t`` as shifts and an add),
       registered beside the block RAMs' read registers (loadable, ``load``: their parts, ``tb * t``,
       ``ct`` and the offsets, are registered here and added in stage 2).
    2. *data*: the read data, registered per 512-entry bank (loadable: and the byte addresses).
    3. *window*: in every codebook bank, the two 4-byte-aligned words of the entry that hold the
       texel's bytes (a 64-bit window) and the words holding U and V; the raw word of the selected
       raw bank. Registered.
    4. *select*: the bank's windows selected, then the bytes inside them; registered as ``samples``.

    A loadable ROM whose entries have more than ``SPLIT_PICK_WORDS`` 4-byte words picks each of
    its words over stages 3 and 4: stage 3 registers the ``PICK_GROUP`` candidates of the word's
    aligned group (:func:`hw.pick.pick_group`), stage 4 picks the word among them. Same
    values, same latency.

    Latency 4 (every stage advances when ``en`` is high). Throughput: one texel per cycle.

    Arguments
    ---------
    codebook : ndarray uint8 (entries, entry_bytes)
        The codebook memory image.
    raw_words : ndarray uint32
        The raw memory image.
    cb_bits, raw_bits, off_bits : int
        Widths of the codebook base, the raw address and the plane offsets.
    bank_depth : int
        Entries per block RAM bank of each memory (:class:`hw.banked_rom.BankedROM`).
    features : hw.features.Features, optional
        What the texture set needs (default: everything, the full ROM). Specialised: no codebook
        memory without compressed levels, no raw memory or raw select without raw levels, the
        texel select only for the colour formats present (``tb * t`` without a multiplexer for one
        bytes-per-texel), U and V only with yuv411, and every descriptor field in
        ``features.constants`` a constant (its input ignored; ``texel_off`` = 0 needs no adder,
        ``cb_base`` = 0 none either). PowerVR2's paths only for its formats in ``features.colors``.
    color_bits : int
        Width of the colour code: 2 (the paper's formats) or 3 (a set with PowerVR2 textures).
    entries, entry_bytes, raw_depth : int, optional
        The memories' depths and the entry width when they differ from the images' (a geometry's;
        the images are then the initial contents).
    load : data.StructLayout, optional
        The bus port's load command (:func:`hw.bus_port.load_layout`): both memories are loadable
        (regions ``codebook`` and ``raw``); members ``load`` and ``load_data``.
    data_copies : int
        With ``n`` > 0 (the loadable unit): the codebook and raw memories' data registers (stage 2)
        are enabled by ``en_data``, ``n`` copies of ``en`` (:class:`hw.banked_rom.BankedROM`
        ``data_copies``): a quarter of them (at least one) the raw memory's, the rest the
        codebook's (all of them the one memory's when the other is absent). Default 0.
    index_bits : int, optional
        ``index`` is the codebook address ``cb_base + index`` of this width, summed upstream (the
        loadable unit's index reader, :class:`hw.pipeline.LinkLayout` ``summed``): the memory is
        read at ``index``, ``cb_base`` is not read. Default None: ``index`` is the index.

    Members
    -------
    index : In(features.index_bits)
        The block's index (16 bits in the full ROM).
    cb_base : In(cb_bits)
        Entry of codeword 0 of the texture's codebook.
    raw_addr : In(raw_bits)
        Raw memory word (raw levels).
    compressed : In(1)
        0: read the raw memory instead.
    x, y : In(3)
        Offset inside the block.
    log2bw : In(2)
        log2 of the block width at this level.
    color : In(color_bits)
        Colour format code.
    texel_off, u_off, v_off : In(off_bits)
        Byte offsets of this sub-level's planes in the entry.
    en : In(1)
        Pipeline advance.
    en_data : In(data_copies)
        Only with ``data_copies``: copies of ``en``, the enables of the memories' data registers.
    samples : Out(SamplesLayout)
        Registered raw samples.
    color_out : Out(2)
        Registered colour format of the samples (rgba for raw levels).
    """

    def __init__(self, codebook, raw_words, *, cb_bits: int, raw_bits: int, off_bits: int,
                 bank_depth: int = BANK_DEPTH, features: Features | None = None, color_bits: int = 2,
                 entries: int | None = None, entry_bytes: int | None = None, raw_depth: int | None = None,
                 load=None, raw_port: bool = False, index_bits: int | None = None, data_copies: int = 0):
        codebook = np.asarray(codebook, dtype=np.uint8)
        if codebook.ndim != 2:
            raise ValueError("codebook memory must be a 2-D uint8 array")
        self._entry_bytes = max(1, codebook.shape[1] if entry_bytes is None else entry_bytes)
        if codebook.shape[1] > self._entry_bytes:
            raise ValueError(f"codebook entries of {codebook.shape[1]} bytes exceed {self._entry_bytes}")
        self._entries = _entry_ints(codebook) or [0]
        self._raw = [int(v) for v in np.asarray(raw_words, dtype=np.uint32).tolist()] or [0]
        self._depths = (entries, raw_depth)
        self._load = load
        # External memory (hw.memory): the raw word comes in on ``raw_in`` beside ``raw_addr``.
        self._raw_port = bool(raw_port)
        self._bank_depth = bank_depth
        if color_bits not in (2, 3):
            raise ValueError(f"color_bits must be 2 (the paper's formats) or 3 (with PowerVR2's), not {color_bits!r}")
        self._features = features if features is not None else Features.full(pvr2=color_bits == 3)
        if color_bits == 2 and max(self._features.color_codes, default=0) > 3:
            raise ValueError("PowerVR2 colour formats need color_bits=3")
        self._summed = index_bits is not None
        self._data_copies = int(data_copies)
        super().__init__({
            "index": In(index_bits if self._summed else self._features.index_bits),
            "cb_base": In(cb_bits),
            "raw_addr": In(raw_bits),
            "compressed": In(1),
            "x": In(3),
            "y": In(3),
            "log2bw": In(2),
            "color": In(color_bits),
            "texel_off": In(off_bits),
            "u_off": In(off_bits),
            "v_off": In(off_bits),
            "en": In(1),
            "samples": Out(SamplesLayout),
            "color_out": Out(2),
            **({} if load is None else {"load": In(load), "load_data": Out(DATA_WIDTH)}),
            **({"raw_in": In(32)} if self._raw_port else {}),
            **({"en_data": In(self._data_copies)} if self._data_copies else {}),
        })

    @property
    def latency(self) -> int:
        return LATENCY

    def _input(self, name: str):
        """The input ``name``, or its constant when the features make it one (a descriptor field
        with one value in every row that reads it)."""
        port = getattr(self, name)
        if name in self._features.constants:
            return C(self._features.constants[name], len(port))
        return port

    def elaborate(self, platform):
        m = Module()
        feat = self._features
        nbytes = self._entry_bytes
        cb_base, log2bw, color_in = self._input("cb_base"), self._input("log2bw"), self._input("color")
        texel_off, u_off, v_off = self._input("texel_off"), self._input("u_off"), self._input("v_off")
        compressed_in = self._input("compressed")
        yuv = feat.matrix                   # U and V selects (yuv411 or yuv422 levels present)
        codes = feat.color_codes
        yuv422 = _YUV422 in codes
        expand = {c for c in codes if _BYTES_PER_TEXEL.get(c) == 2 and c != _YUV422}
        load = self._load
        answers = []

        def target(region, lanes):
            return None if load is None else LoadTarget(load, REGIONS[region], lanes=lanes)

        # the data registers' copies of ``en``: a quarter the raw memory's, the rest the codebook's
        n = self._data_copies
        own_raw = feat.raw and not self._raw_port
        n_raw = (n if not feat.compressed else max(1, n // 4)) if own_raw and n else 0
        copies = {"codebook": (self.en_data[n_raw:] if n else None), "raw": (self.en_data[:n_raw] if n_raw else None)}

        def data_copies(name):
            return {} if copies[name] is None or not len(copies[name]) else {"data_copies": len(copies[name])}

        def connect(rom, name):
            if data_copies(name):
                m.d.comb += rom.en_data.eq(copies[name])

        if feat.compressed:
            lanes = entry_lanes(nbytes)
            m.submodules.codebook = codebook = BankedROM(
                self._entries, width=nbytes * 8, bank_depth=self._bank_depth, depth=self._depths[0],
                load=target("codebook", lanes), **data_copies("codebook"))
            connect(codebook, "codebook")
            m.d.comb += [codebook.addr.eq(self.index if self._summed or _is_zero(cb_base) else cb_base + self.index),
                         codebook.en.eq(self.en)]
            if load is not None:
                m.d.comb += codebook.load.eq(self.load)
                answers.append(codebook.load_data)
        if feat.raw and self._raw_port:     # the raw word from outside, as late as the memory's
            m.submodules.raw = raw = _RawPort()
            m.d.comb += [raw.data.eq(self.raw_in), raw.en.eq(self.en)]
        elif feat.raw:
            m.submodules.raw = raw = BankedROM(self._raw, width=32, bank_depth=self._bank_depth,
                                               depth=self._depths[1], load=target("raw", 1), **data_copies("raw"))
            connect(raw, "raw")
            m.d.comb += [raw.addr.eq(self.raw_addr), raw.en.eq(self.en)]
            if load is not None:
                m.d.comb += raw.load.eq(self.load)
                answers.append(raw.load_data)
        if load is not None:
            m.d.comb += self.load_data.eq(or_all(answers))

        def reg(value, name):
            return enabled_register(m, self.en, value, name)

        # Stage 1: byte addresses of the texel and of its U and V, beside the memory reads.
        t = Signal(6)
        tbt = Signal(8)                     # tb * t
        lcw = Signal(2)
        ct = Signal(6)
        m.d.comb += t.eq((self.y << log2bw) | self.x)
        if _YUV in codes:
            m.d.comb += [
                lcw.eq(Mux(log2bw > 0, log2bw - 1, 0)),
                ct.eq(((self.y >> 1) << lcw) | (self.x >> 1)),
            ]
        per_texel = {code: _BYTES_PER_TEXEL.get(code, 1) for code in codes}
        times = {3: (t << 1) + t, 4: t << 2, 2: t << 1, 1: t}
        if len(set(per_texel.values())) <= 1:
            m.d.comb += tbt.eq(times[next(iter(per_texel.values()), 1)])
        else:
            groups = {tb: [c for c in sorted(per_texel) if per_texel[c] == tb] for tb in (3, 4, 2, 1)}
            groups = {tb: cs for tb, cs in groups.items() if cs}
            default = 1 if 1 in groups else list(groups)[-1]
            # (multiplexers, not a case statement of several values a case: Yosys writes that as a
            # comparison vector assigned bit by bit, which CXXRTL's in-place cycle cannot take)
            product = times[default]
            for tb, cs in groups.items():
                if tb != default:
                    product = Mux(Cat(*(color_in == c for c in cs)).any(), times[tb], product)
            m.d.comb += tbt.eq(product)
        if yuv422:
            # yuv422: U and V are the low bytes of the row's left and right texels, at u_off + 2x
            # and v_off + 2x (``x`` is the row: PowerVR2 offsets come transposed)
            ct_pair = Signal(6)
            m.d.comb += ct_pair.eq(Mux(color_in == _YUV422, self.x << 1, ct) if _YUV in codes else self.x << 1)
            ct = ct_pair
        nwords = -(-(nbytes + 3) // 4) + 1     # 4-byte words of the padded entry (see stage 3)
        addr_bits = (4 * nwords - 1).bit_length()
        # The fields that ride beside the memories, one register per stage (assigned in one piece:
        # one register update per stage in a simulator instead of five). Constants ride nowhere.
        ride = {"start": addr_bits}
        if yuv:
            ride.update(ustart=addr_bits, vstart=addr_bits)
        if feat.variable("compressed"):
            ride["compressed"] = 1
        if feat.variable("color"):
            ride["color"] = len(self.color)
        carried = data.StructLayout(ride)

        def sums(p):
            """The byte addresses from their parts (``p``: name -> value)."""
            return {"start": (p["tbt"] if _is_zero(p["texel_off"]) else p["texel_off"] + p["tbt"])[:addr_bits],
                    "ustart": (p["u_off"] + p["ct"])[:addr_bits], "vstart": (p["v_off"] + p["ct"])[:addr_bits],
                    "compressed": p["compressed"], "color": p["color"]}

        parts = {"tbt": tbt, "texel_off": texel_off, "ct": ct, "u_off": u_off, "v_off": v_off,
                 "compressed": compressed_in, "color": color_in}
        values = sums(parts)
        if load is None:
            f1 = Signal(carried, name="fields_read")
            with m.If(self.en):
                m.d.sync += f1.eq(Cat(*(values[name] for name in ride)))
            # Stage 2: the banks' data registers (in BankedROM); the fields follow.
            f2 = reg(f1, "fields_data")
        else:
            # The loadable unit: stage 1 registers the sums' parts (``tb * t``, ``ct`` and the
            # offsets), stage 2 adds them beside the banks' data registers, so the request's
            # ``x, y -> t -> tb * t -> + texel_off`` is not one cycle (the codebook ROM's own
            # critical path out of context, docs/area.md "Block by block"). Same values, same stage 3.
            names = ["tbt"] + (["texel_off"] if not isinstance(texel_off, Const) else [])
            if yuv:
                names += ["ct"] + [n for n in ("u_off", "v_off") if not isinstance(parts[n], Const)]
            names += [n for n in ("compressed", "color") if n in ride]
            f1 = Signal(data.StructLayout({n: len(parts[n]) for n in names}), name="fields_read")
            with m.If(self.en):
                m.d.sync += f1.eq(Cat(*(parts[n] for n in names)))
            # Stage 2: the banks' data registers (in BankedROM); the byte addresses beside them.
            registered = sums({n: getattr(f1, n) if n in names else parts[n] for n in parts})
            f2 = Signal(carried, name="fields_data")
            with m.If(self.en):
                m.d.sync += f2.eq(Cat(*(registered[name] for name in ride)))

        def field(view, name):
            return getattr(view, name) if name in ride else values[name]

        start = f2.start
        ustart, vstart = (f2.ustart, f2.vstart) if yuv else (None, None)

        # Stage 3: per codebook bank, the 4-byte words holding the texel (two: a 64-bit window) and
        # U and V, each picked from a list of words by the word number (a multiplexer of whole
        # words; no shifter). The entry is padded with three copies of its last byte, so that every
        # byte address up to last + 3 reads what the golden model's clamp reads, then with zeros.
        # A loadable ROM of wide entries: each pick over two stages (the word's group here, the word
        # in stage 4), ``fine`` bits of the word number carried to stage 4.
        split = load is not None and feat.compressed and nwords - 1 > SPLIT_PICK_WORDS
        fine = PICK_GROUP.bit_length() - 1 if split else 0

        def word_pick(values, index, name):
            """Stage 3's pick of ``values`` by ``index`` (registered): one value, or the group's."""
            if not split:
                return reg(pick(values, index), name)
            return [reg(v, f"{name}_{lo}") for lo, v in enumerate(pick_group(values, index, PICK_GROUP))]

        banks = codebook.banks if feat.compressed else 0
        # The loadable ROM of several banks: the picks' selects (stage 2's word numbers) in a copy of
        # their own per bank (hw.copies: equal to ``fields_data``'s, kept apart), where one
        # register's bit drove the picks of every bank (1,022 loads on ``paper``: docs/area.md "The
        # paths between blocks"). Not per value of a split pick's group: the group's candidates
        # overlap (a window is two words), and with selects of their own abc9 no longer shares
        # their multiplexers (``max``: 1,300 LUT4 more).
        selects = {}
        for name in ("start", "ustart", "vstart") if load is not None and banks > 1 else ():
            if name in ride:
                selects[name] = register_copies(m, registered[name][2:], banks, name=f"{name}_pick",
                                                enable=self.en)

        def select_of(name, value, k):
            return selects[name][k] if name in selects else value[2:]

        windows, u_words, v_words = [], [], []
        for k in range(banks):
            entry = codebook.data[k]
            last = entry[(nbytes - 1) * 8:]
            padded = Cat(entry, last, last, last)
            words = [Cat(padded[32 * n:32 * n + 32], C(0, max(0, 32 * n + 32 - len(padded))))
                     for n in range(nwords - 1)] + [C(0, 32)]
            windows.append(word_pick([Cat(words[n], words[n + 1]) for n in range(nwords - 1)],
                                     select_of("start", start, k), f"window{k}"))
            if yuv:
                u_words.append(word_pick(words, select_of("ustart", ustart, k), f"u_word{k}"))
                v_words.append(word_pick(words, select_of("vstart", vstart, k), f"v_word{k}"))
        bank = reg(codebook.bank, "bank_window") if feat.compressed else None
        raw_word = reg(raw.word, "raw_window") if feat.raw else None
        def low_bits(address):
            """What stage 4 needs of a byte address: the byte in the word (and the word in its group)."""
            return Cat(address, C(0, fine))[:2 + fine] if split else address[:2]

        low = {"start": low_bits(start)}
        if yuv:
            low.update(ustart=low_bits(ustart), vstart=low_bits(vstart))
        low.update({name: getattr(f2, name) for name in ("compressed", "color") if name in ride})
        f3 = reg(Cat(*low.values()), "fields_window")
        f3 = data.StructLayout({name: len(v) for name, v in low.items()})(f3)
        compressed = field(f3, "compressed")
        color = field(f3, "color")

        # Stage 4: the bank's words, then the bytes.
        out = Signal(32)
        if feat.compressed:
            def select(words, at, width):
                """The bank's word (split: the word in its group first), then ``width`` bits at
                byte ``at % 4``."""
                if split:
                    words, at = [pick(group, at[2:]) for group in words], at[:2]
                return pick(words, bank).bit_select(at << 3, width)

            texel = Signal(32)
            m.d.comb += texel.eq(select(windows, f3.start, 32))
            if yuv:
                u = Signal(8)
                v = Signal(8)
                m.d.comb += [u.eq(select(u_words, f3.ustart, 8)), v.eq(select(v_words, f3.vstart, 8))]
        # (condition, samples, colour out or None for the level's own), first match; the last
        # unconditional. The colour matrix is told the paper's codes only.
        branches = []
        if feat.raw:
            branches.append((~compressed, raw_word, None))      # the default colour out: rgba
        if feat.compressed and _YUV in codes:
            branches.append((color == _YUV, Cat(texel[:8], u, v, texel[24:]), None))
        if feat.compressed and yuv422:
            branches.append((color == _YUV422, Cat(texel[8:16], u, v, texel[24:]), _YUV))
        if feat.compressed and expand:
            # codes 4-6 (yuv422, 7, is matched above): bit 2 of the code
            branches.append((color[2], expand_texel(texel[:16], color, expand), _RGBA))
        if feat.compressed and codes & {_RGB, _RGBA, COLOR_CODES["intensity"]}:
            branches.append((None, texel, None))
        pvr2 = len(self.color) > 2
        if pvr2:
            color_out = Signal(2)           # what the colour matrix is told
            m.d.comb += color_out.eq(Mux(compressed, color[:2], _RGBA))
        else:                               # the paper's formats: the level's own code, as it was
            color_out = Mux(compressed, color, _RGBA)
        if len(branches) == 1:
            m.d.comb += out.eq(branches[0][1])
        else:
            for n, (cond, value, cout) in enumerate(branches):
                with (m.If(cond) if n == 0 else m.Elif(cond) if n < len(branches) - 1 else m.Else()):
                    m.d.comb += out.eq(value)
                    if pvr2 and cout is not None:
                        m.d.comb += color_out.eq(cout)
        if pvr2 and len(branches) == 1 and branches[0][2] is not None:
            m.d.comb += color_out.eq(branches[0][2])
        with m.If(self.en):
            m.d.sync += [
                self.samples.as_value().eq(out),
                self.color_out.eq(color_out),
            ]
        return m


def _is_zero(value) -> bool:
    """``value`` is the constant 0 (a field the features made constant)."""
    return isinstance(value, Const) and value.value == 0
