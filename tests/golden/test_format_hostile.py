"""The .vqt container against hostile files (issue: numerical stability and hostile input).

Every file here has a correct checksum (anyone can make one), so each change reaches the parser.
Loading must raise the one documented FormatError, quickly and without allocating much more than
the file holds; anything it accepts must be safe to use (info's rates, every level decoded)."""

import time
import tracemalloc

import numpy as np
import pytest

from vqtex.golden.fetch import decode
from vqtex.golden.format import FormatError, TextureSet
from tests.support import HOSTILE_CASES as CASES
from tests.support import edit_descriptor, edit_header, hostile_files, set_key
from vqtex.sim.bench.robustness.fuzz import ALLOC_BOUND, mutate_vqt, run_mutations, try_file

FILES = hostile_files()


@pytest.mark.parametrize("name", sorted(CASES))
def test_hostile_header_is_one_format_error(name):
    data = CASES[name](FILES[0])                  # rgb, 64x64, mipmapped: extended codewords
    tracemalloc.start()
    t0 = time.perf_counter()
    with pytest.raises(FormatError) as e:
        TextureSet.from_bytes(data)
    seconds = time.perf_counter() - t0
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert "\n" not in str(e.value)
    assert seconds < 1.0 and peak < ALLOC_BOUND(len(data)), (seconds, peak)


def test_the_seed_files_load_and_decode():
    """The cases above start from files that are fine: what is rejected is the change."""
    for data in FILES:
        assert try_file(data) == ("accepted", "")


def test_fuzz_two_thousand_mutations():
    """Mutated files (bytes and JSON structure, checksum recomputed): only FormatError, no hang over
    2 s, no allocation over 64 MiB + 16x the file; deterministic seed."""
    rep = run_mutations(2000, seed=12)
    bad = {k: v for k, v in rep["counts"].items() if k not in ("accepted", "rejected")}
    assert not bad, (bad, rep["examples"])
    assert rep["counts"].get("rejected", 0) > 1000          # the mutations do reach the checks


def test_accepted_mutations_decode_to_their_sizes():
    rng = np.random.default_rng(3)
    seen = 0
    for _ in range(300):
        data = mutate_vqt(FILES[int(rng.integers(len(FILES)))], rng)
        try:
            ts = TextureSet.from_bytes(data)
        except FormatError:
            continue
        seen += 1
        for t in range(ts.n_textures):
            assert ts.rates(t)["overall"] > 0
            for L, (w, h) in enumerate(ts.level_shapes(t)):
                if ts.textures[t].stored(L):
                    assert decode(ts, t, L).shape[:2] == (h, w)
    assert seen > 30


# -- pruned sets (golden.need.prune): absent levels and block presence bits --------------------------------

def _pruned_seed() -> bytes:
    """FILES[0] (64x64 rgb, mipmapped, 4x4 blocks) pruned to a few texels of level 1 (sub-level 1
    of the first group, whose top level 0 is then absent) and of raw level 4."""
    from vqtex.golden.need.analysis import analyse
    from vqtex.golden.need.prune import prune
    ts = TextureSet.from_bytes(FILES[0])
    reqs = np.array([[0, 1, 0, 0], [0, 1, 9, 30], [0, 4, 3, 2]])
    return prune(ts, analyse(ts, [reqs])).to_bytes()


PRUNED = _pruned_seed()

PRUNED_CASES = {
    "absent levels not a list": lambda d: edit_header(d, lambda h: set_key(h, ["textures", 0, "absent_levels"], 3)),
    "absent level past the levels": lambda d: edit_header(d, lambda h: set_key(h, ["textures", 0, "absent_levels"], [0, 99])),
    "absent levels out of order": lambda d: edit_header(d, lambda h: h["textures"][0]["absent_levels"].reverse()),
    "absent levels repeated": lambda d: edit_header(d, lambda h: h["textures"][0]["absent_levels"].insert(0, 0)),
    "empty absent list": lambda d: edit_header(d, lambda h: set_key(h, ["textures", 0, "absent_levels"], [])),
    "absent level as a bool": lambda d: edit_header(d, lambda h: set_key(h, ["textures", 0, "absent_levels"], [True])),
    "stored level listed absent": lambda d: edit_header(d, lambda h: h["textures"][0]["absent_levels"].append(6)),
    "absent level not listed": lambda d: edit_header(d, lambda h: h["textures"][0]["absent_levels"].remove(0)),
    "presence bits one byte short": lambda d: edit_header(d, lambda h: (set_key(h, ["arrays", "present_blocks", "shape"], [h["arrays"]["present_blocks"]["shape"][0] - 1]),
                                                                  set_key(h, ["arrays", "present_blocks", "nbytes"], h["arrays"]["present_blocks"]["nbytes"] - 1))),
    "presence bits of rank 2": lambda d: edit_header(d, lambda h: set_key(h, ["arrays", "present_blocks", "shape"], [1, h["arrays"]["present_blocks"]["shape"][0]])),
    "presence bits as words": lambda d: edit_header(d, lambda h: set_key(h, ["arrays", "present_blocks", "dtype"], "<u4")),
    "presence bits past the end": lambda d: edit_header(d, lambda h: set_key(h, ["arrays", "present_blocks", "offset"], 10**9)),
    "unknown array": lambda d: edit_header(d, lambda h: set_key(h, ["arrays", "extra"], h["arrays"]["present_blocks"])),
    "absent level marked compressed": lambda d: edit_descriptor(d, "compressed", 1, level=0),
    "sub-level of an absent top elsewhere": lambda d: edit_descriptor(d, "base", 7, level=1),
}


@pytest.mark.parametrize("name", sorted(PRUNED_CASES))
def test_hostile_pruned_header_is_one_format_error(name):
    data = PRUNED_CASES[name](PRUNED)
    with pytest.raises(FormatError) as e:
        TextureSet.from_bytes(data)
    assert "\n" not in str(e.value)


def test_the_pruned_seed_loads_and_refuses_what_it_lost():
    from vqtex.golden.fetch import RequestError, check_requests, fetch
    ts, p = TextureSet.from_bytes(FILES[0]), TextureSet.from_bytes(PRUNED)
    assert p.textures[0].absent_levels == [0, 2, 3, 5, 6] and p.present_blocks is not None
    kept = np.array([[0, 1, 0, 0], [0, 1, 9, 30], [0, 4, 3, 2], [0, 4, 0, 0], [0, 1, 1, 1]])
    check_requests(p, *kept.T)
    assert np.array_equal(fetch(p, *kept.T), fetch(ts, *kept.T))
    for bad in ([0, 0, 0, 0], [0, 2, 1, 1], [0, 1, 31, 31], [0, 1, 2, 0], [0, 6, 0, 0]):
        with pytest.raises(RequestError, match="pruned from this texture set"):
            check_requests(p, *np.array([bad]).T)
    with pytest.raises(RequestError):
        decode(p, 0, 0)
    level1, full = decode(p, 0, 1), decode(ts, 0, 1)             # 32x32, blocks of 2x2 at sub-level 1
    stored = np.zeros((32, 32), bool)
    stored[0:2, 0:2] = stored[30:32, 8:10] = True                  # the blocks of (0, 0) and (9, 30)
    assert np.array_equal(level1[stored], full[stored]) and not level1[~stored].any()
