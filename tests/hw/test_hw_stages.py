"""Each hw stage against its golden.fetch twin: descriptor table, block address shifter, index reader,
codebook ROM; and the banked ROM behind the last two."""

import numpy as np
import pytest

from tests import support
from vqtex.golden.fetch import block_address, lookup_descriptor, read_codeword, read_index
from vqtex.golden.format import DESCRIPTOR_DTYPE, DESCRIPTOR_FIELDS, LAYOUT_CODES, MAX_LEVELS, pack_indices
from vqtex.hw import banked_rom, codebook_rom, index_reader
from vqtex.hw.address import BlockAddress
from vqtex.hw.banked_rom import BankedROM
from vqtex.hw.codebook_rom import CodebookROM
from vqtex.hw.descriptor import DescriptorTable, descriptor_widths
from vqtex.hw.index_reader import IndexReader
from tests.support import run_lockstep


def test_descriptor_table_every_row():
    ts = support.combined_set()
    tex, lev = np.divmod(np.arange(ts.n_textures * MAX_LEVELS), MAX_LEVELS)
    dut = DescriptorTable(ts)
    res = run_lockstep(dut, {"texture": tex.tolist(), "level": lev.tolist()}, ["row"], 1,
                       en_pattern=np.random.default_rng(0).random(400) > 0.3)
    want = lookup_descriptor(ts, tex, lev)
    for n, raw in enumerate(res["row"]):
        row = dut.layout.from_bits(raw)
        assert {f: int(getattr(row, f)) for f in DESCRIPTOR_FIELDS} == {f: int(want[n][f]) for f in DESCRIPTOR_FIELDS}


def _random_levels(rng, n):
    """``n`` descriptors of random levels (sides 1..4096, blocks 1..8 no larger) and a texel in each."""
    d = np.zeros(n, DESCRIPTOR_DTYPE)
    d["log2w"] = rng.integers(0, 13, n)
    d["log2h"] = rng.integers(0, 13, n)
    d["log2bw"] = np.minimum(rng.integers(0, 4, n), d["log2w"])
    d["log2bh"] = np.minimum(rng.integers(0, 4, n), d["log2h"])
    i = (rng.random(n) * (1 << d["log2w"].astype(np.int64))).astype(np.int64)
    j = (rng.random(n) * (1 << d["log2h"].astype(np.int64))).astype(np.int64)
    return d, i, j


def test_block_address_random_levels():
    rng = np.random.default_rng(3)
    n = 300
    d, i, j = _random_levels(rng, n)
    d["base"] = rng.integers(0, 1 << 20, n)
    i[:4], j[:4] = 0, 0
    i[4:8], j[4:8] = (1 << d["log2w"][4:8].astype(np.int64)) - 1, (1 << d["log2h"][4:8].astype(np.int64)) - 1
    dut = BlockAddress(base_bits=21, k_bits=24, raw_bits=26)
    inputs = {"i": i, "j": j, "log2w": d["log2w"], "log2bw": d["log2bw"], "log2bh": d["log2bh"], "base": d["base"]}
    res = run_lockstep(dut, {k: np.asarray(v).tolist() for k, v in inputs.items()}, ["k", "x", "y", "raw_addr"], 1,
                       en_pattern=rng.random(1000) > 0.2)
    k, x, y = block_address(d, i, j)
    assert res["k"] == k.tolist()
    assert res["x"] == x.tolist()
    assert res["y"] == y.tolist()
    assert res["raw_addr"] == (d["base"].astype(np.int64) + (j << d["log2w"].astype(np.int64)) + i).tolist()


@pytest.mark.parametrize("one_shifter", [False, True], ids=["baked", "one_shifter"])
@pytest.mark.parametrize("linear", [True, False], ids=["both_maps", "twiddled_only"])
def test_block_address_twiddled_random_levels(linear, one_shifter):
    """The PowerVR2 shifter (the formula's, and the loadable unit's one shifter) against golden's
    twiddled block numbers: random levels of every aspect
    (square, wide, tall: the squares along either side), block sides 1..8 no larger than the level,
    both maps with ``layout`` random (or every level twiddled), under random enables."""
    rng = np.random.default_rng(11)
    n = 400
    d, i, j = _random_levels(rng, n)
    d["layout"] = rng.integers(0, 2, n) if linear else LAYOUT_CODES["pvr2"]
    i[:4], j[:4] = (1 << d["log2w"][:4].astype(np.int64)) - 1, (1 << d["log2h"][:4].astype(np.int64)) - 1
    dut = BlockAddress(base_bits=21, k_bits=24, raw_bits=26, twiddle=True, linear=linear, one_shifter=one_shifter)
    inputs = {"i": i, "j": j, "log2w": d["log2w"], "log2h": d["log2h"], "log2bw": d["log2bw"],
              "log2bh": d["log2bh"], "layout": d["layout"], "base": d["base"]}
    res = run_lockstep(dut, {k: np.asarray(v).tolist() for k, v in inputs.items()}, ["k", "x", "y"], 1,
                       en_pattern=rng.random(1000) > 0.2)
    k, x, y = block_address(d, i, j)
    assert (d["layout"] == LAYOUT_CODES["pvr2"]).sum() > n // 3
    assert res["k"] == k.tolist()
    assert res["x"] == x.tolist()
    assert res["y"] == y.tolist()


class _Words:
    def __init__(self, words, word_bits):
        self.index_words, self.word_bits = words, word_bits


def _index_memory(word_bits, rng):
    """Maps of every width b = 1..16, full-range random indices, each long enough for every bit
    offset in a word, at odd base words; returns (words, [(base, b, n)])."""
    parts, maps, w = [rng.integers(0, 1 << 16, 3).astype(np.uint64)], [], 3
    for b in range(1, 17):
        n = word_bits + 1
        idx = rng.integers(0, 1 << b, n)
        words = pack_indices(idx, b, word_bits).astype(np.uint64)
        maps.append((w, b, n))
        parts.append(words)
        w += len(words)
        junk = rng.integers(0, 1 << 16, 1 + b % 2).astype(np.uint64)   # shifts later maps' parity
        parts.append(junk)
        w += len(junk)
    parts.append(np.zeros(1, np.uint64))
    return np.concatenate(parts).astype(f"<u{word_bits // 8}"), maps


def _index_requests(word_bits, rng):
    """An index memory of every width's maps, a request for every index of each in random order
    (``(base, b, k)`` rows), and golden's indices: ``(words, reqs, want)``."""
    words, maps = _index_memory(word_bits, rng)
    reqs = np.array([(base, b, k) for base, b, n in maps for k in range(n)], dtype=np.int64)
    reqs = reqs[rng.permutation(len(reqs))]
    d = np.zeros(len(reqs), DESCRIPTOR_DTYPE)
    d["base"], d["index_bits"] = reqs[:, 0], reqs[:, 1]
    return words, reqs, read_index(_Words(words, word_bits), d, reqs[:, 2])


@pytest.mark.parametrize("bank_depth", [512, 16])
@pytest.mark.parametrize("one_port", [False, True], ids=["two_bank", "one_port"])
@pytest.mark.parametrize("word_bits", [16, 32, 64])
def test_index_reader_every_width_and_offset(word_bits, one_port, bank_depth):
    rng = np.random.default_rng(word_bits + one_port)
    words, reqs, want = _index_requests(word_bits, rng)
    dut = IndexReader(words, word_bits=word_bits, k_bits=7, base_bits=12, one_port=one_port,
                      bank_depth=bank_depth)
    en = rng.random(4 * len(reqs)) > 0.15 if word_bits == 32 else None
    res = run_lockstep(dut, {"base": reqs[:, 0].tolist(), "b": reqs[:, 1].tolist(), "k": reqs[:, 2].tolist(),
                             "valid": [1] * len(reqs)}, ["index"], index_reader.LATENCY,
                       en_pattern=en, hold="hold" if one_port else None)
    assert res["index"] == want.tolist()


@pytest.mark.parametrize("word_bits", [16, 32, 64])
def test_loadable_index_reader_every_width_and_offset(word_bits):
    """The loadable reader (its contents the initial value, no bus write), every width 1..16 at every
    offset: the word pair shifted by whole bytes in stage 4 and within the byte in stage 5
    (``hw.index_reader.COARSE_SHIFT``), under random enables."""
    from amaranth.lib import data as _data
    from vqtex.hw.bus_port import DATA_WIDTH, REGION_BITS
    rng = np.random.default_rng(100 + word_bits)
    words, reqs, want = _index_requests(word_bits, rng)
    load = _data.StructLayout({"write": 1, "read": 1, "region": REGION_BITS, "offset": 16, "data": DATA_WIDTH})
    dut = IndexReader(words, word_bits=word_bits, k_bits=7, base_bits=12, bank_depth=16,
                      widths=tuple(range(1, 17)), load=load)
    res = run_lockstep(dut, {"base": reqs[:, 0].tolist(), "b": reqs[:, 1].tolist(), "k": reqs[:, 2].tolist(),
                             "valid": [1] * len(reqs)}, ["index"], index_reader.LATENCY,
                       en_pattern=rng.random(4 * len(reqs)) > 0.15)
    assert res["index"] == want.tolist()


@pytest.mark.parametrize("name,bank_depth", [("combined", 512), ("combined", 8), ("yuv_2x4_b12_mip_w64", 512),
                                             ("rgba_2x2_b7_mip_w16", 4)])
def test_codebook_rom_every_level(name, bank_depth):
    ts = support.combined_set() if name == "combined" else support.texture_set(name)
    rng = np.random.default_rng(5)
    req = np.concatenate([support.random_requests(ts, 150, 6), support.adversarial_requests(ts, 7)])
    d = lookup_descriptor(ts, req[:, 0], req[:, 1])
    comp = d["compressed"].astype(bool)
    k, x, y = block_address(d, req[:, 2], req[:, 3])
    index = np.zeros(len(req), np.int64)
    index[comp] = rng.integers(0, [ts.codebooks[ts.textures[t].codebook].size for t in req[comp, 0]])
    raw_addr = d["base"].astype(np.int64) + (req[:, 3] << d["log2w"].astype(np.int64)) + req[:, 2]
    raw_addr[comp] = rng.integers(0, max(1, len(ts.raw_words)), comp.sum())   # ignored, must stay in range
    want = np.zeros((len(req), 4), np.uint8)
    want[comp] = read_codeword(ts, d[comp], index[comp], x[comp], y[comp])
    want[~comp] = ts.raw_words[raw_addr[~comp]].astype("<u4").view(np.uint8).reshape(-1, 4)
    w = descriptor_widths(ts)
    dut = CodebookROM(ts.codebook, ts.raw_words, cb_bits=w["cb_base"], raw_bits=16, off_bits=w["texel_off"],
                      bank_depth=bank_depth)
    fields = {"index": index, "cb_base": d["cb_base"], "raw_addr": raw_addr, "compressed": d["compressed"],
              "x": x, "y": y, "log2bw": d["log2bw"], "color": d["color"],
              "texel_off": d["texel_off"], "u_off": d["u_off"], "v_off": d["v_off"]}
    res = run_lockstep(dut, {k: np.asarray(v).astype(np.int64).tolist() for k, v in fields.items()},
                       ["samples", "color_out"], codebook_rom.LATENCY, en_pattern=rng.random(2000) > 0.2)
    got = ((np.array(res["samples"], dtype=np.int64)[:, None] >> (8 * np.arange(4))) & 0xFF).astype(np.uint8)
    assert np.array_equal(got, want)
    assert res["color_out"] == np.where(comp, d["color"], 1).tolist()


@pytest.mark.parametrize("depth,bank_depth", [(37, 8), (16, 8), (5, 512), (1, 4)])
def test_banked_rom_reads_every_word(depth, bank_depth):
    rng = np.random.default_rng(depth)
    init = rng.integers(0, 1 << 20, depth).tolist()
    dut = BankedROM(init, width=20, bank_depth=bank_depth)
    assert dut.banks == -(-depth // bank_depth)
    addr = np.concatenate([np.arange(depth), rng.integers(0, depth, 100)])
    res = run_lockstep(dut, {"addr": addr.tolist()}, ["word"], banked_rom.LATENCY,
                       en_pattern=rng.random(1000) > 0.3)
    assert res["word"] == [init[a] for a in addr]


@pytest.mark.parametrize("depth,bank_depth", [(37, 8), (5, 512), (161, 512)])
def test_banked_rom_every_address_decodes(depth, bank_depth):
    """A read-only bank is as deep as its read address reaches (a power of two), the rows past the
    contents zero: an address past the last word reads 0 (one indexed load in a simulator, no
    bounds check); the contents and the bank count are unchanged."""
    from vqtex.hw.memories import elaborate, memories
    init = list(range(1, depth + 1))
    dut = BankedROM(init, width=12, bank_depth=bank_depth)
    mems = memories(elaborate(dut))
    assert len(mems) == -(-depth // bank_depth)
    for k, mem in enumerate(mems):
        part = init[k * bank_depth:(k + 1) * bank_depth]
        assert mem.depth == 1 << (len(part) - 1).bit_length()
        assert mem.words[:len(part)] == part and not any(mem.words[len(part):])
    top = (1 << len(dut.addr)) if len(mems) == 1 else (len(mems) - 1) * bank_depth + mems[-1].depth
    addr = list(range(depth, top)) + [depth - 1, 0]
    res = run_lockstep(dut, {"addr": addr}, ["word"], banked_rom.LATENCY)
    assert res["word"] == [0] * (top - depth) + [init[-1], init[0]]


def test_banked_rom_rejects_bad_bank_depth():
    with pytest.raises(ValueError):
        BankedROM([1, 2, 3], width=8, bank_depth=12)
    with pytest.raises(TypeError):
        BankedROM([1, 2, 3], width=0)
