"""golden.index_banks: the index memory banked by block parity holds every index once, reads back
what golden.fetch reads, and no footprint of golden.filter needs two blocks of one bank."""

import numpy as np
import pytest

from tests import support
from vqtex.golden import filter as spec
from vqtex.golden import index_banks as ib
from vqtex.golden.fetch import block_address, lookup_descriptor, read_index, twiddled_block
from vqtex.golden.format import TextureSet


def _sets():
    pvr2 = support.pvr2_small_sets()
    return {"rgb12_yuv411_mixed": support.combined_set(), "pvr2_rectangles_mip8": pvr2["rectangles_and_mip8"],
            "w16": support.texture_sets()["w16"], "mixed": support.texture_sets()["mixed"],
            "paper_and_pvr2": TextureSet.combine([support.texture_sets()["rgb12"], pvr2["rectangles_and_mip8"]])}


SETS = _sets()


@pytest.mark.parametrize("banks", ib.BANK_COUNTS)
@pytest.mark.parametrize("name", sorted(SETS))
def test_banked_reads_equal_the_index_map(name, banks):
    ts = SETS[name]
    req = np.concatenate([support.random_requests(ts, 3000, seed=banks), support.adversarial_requests(ts, seed=2)])
    t, lv, i, j = req.T
    d = lookup_descriptor(ts, t, lv)
    comp = d["compressed"] != 0
    k, _, _ = block_address(d, i, j)
    bi = ib.banked_index(ts, banks)
    got = ib.read_banked_index(ts, bi, t[comp], lv[comp], i[comp], j[comp])
    assert (got == read_index(ts, d[comp], k[comp])).all()
    assert len({len(w) for w in bi.words}) == 1 and all(w[-1] == 0 for w in bi.words)
    bi.view(ts).validate()                      # the lanes' descriptor view is a valid set
    # one copy: the banks together hold the map, plus at most a word per bank and level group
    groups = len(np.unique(ts.descriptors["base"][(ts.descriptors["valid"] != 0) & (ts.descriptors["compressed"] != 0)]))
    assert sum(len(w) for w in bi.words) <= len(ts.index_words) + banks * (groups + 1)


@pytest.mark.parametrize("banks", [2, 4])
def test_bank_address_is_block_parity_and_one_to_one(banks):
    """Every grid shape up to 16x16 blocks, row-major and twiddled: (bank, k') names each block once,
    k' is dense, and the bank is the block's column (and row) parity."""
    for gw in range(5):
        for gh in range(5):
            bx, by = np.meshgrid(np.arange(1 << gw), np.arange(1 << gh))
            bx, by = bx.ravel(), by.ravel()
            for tw in (False, True):
                k = twiddled_block(bx, by, gw, gh) if tw else (by << gw) | bx
                bank, kq = ib.bank_address(k, gw, gh, tw, banks)
                parity = (bx & 1) | ((by & 1) << 1) if banks == 4 else bx & 1
                assert (bank == parity).all(), (gw, gh, tw)
                pairs = set(zip(bank.tolist(), kq.tolist()))
                assert len(pairs) == len(k)
                quarter = (1 << max(gw - 1, 0)) * ((1 << max(gh - 1, 0)) if banks == 4 else (1 << gh))
                assert kq.max() < quarter


@pytest.mark.parametrize("lanes", [2, 4, 8])
@pytest.mark.parametrize("name", sorted(SETS))
def test_no_footprint_has_a_bank_conflict(name, lanes):
    from tests.support import edge_pixels
    ts = SETS[name]
    table = spec.LevelTable([ts.level_shapes(t) for t in range(ts.n_textures)])
    frac = spec.coordinate_frac_bits(table.max_log2)
    px = edge_pixels(table, frac, 20000, lanes)
    level, i, j, _ = spec.footprint(table, px["texture"], px["s"], px["t"], px["lod"], px["mode"],
                                    px["address_s"], px["address_t"], frac)
    assert ib.conflicts(ts, px["texture"], level, i, j, lanes) == 0


def test_conflicts_are_counted_when_slots_are_not_a_footprint():
    """Negative control: slots two blocks apart in one row (same parity, different blocks) conflict."""
    ts = support.texture_sets()["rgb12"]
    lw = int(ts.descriptors[0, 0]["log2bw"])
    i = np.array([[0, 2 << lw, 0, 0, 0, 0, 0, 0], [0, 1 << lw, 0, 0, 0, 0, 0, 0]])
    z = np.zeros_like(i)
    assert ib.conflicts(ts, np.zeros(2, np.int64), z, i, z, 4) == 1
    assert ib.conflicts(ts, np.zeros(2, np.int64), z, i, z, 1) == 0


def test_bad_bank_count():
    with pytest.raises(ValueError):
        ib.bank_address(np.arange(4), 1, 1, False, 3)
    with pytest.raises(ValueError):
        ib.banked_index(support.combined_set(), 8)
