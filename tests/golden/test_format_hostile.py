"""The .vqt container against hostile files (issue: numerical stability and hostile input).

Every file here has a correct checksum (anyone can make one), so each change reaches the parser.
Loading must raise the one documented FormatError, quickly and without allocating much more than
the file holds; anything it accepts must be safe to use (info's rates, every level decoded)."""

import json
import time
import tracemalloc

import numpy as np
import pytest

from vqtex.golden.fetch import decode
from vqtex.golden.format import FormatError, TextureSet
from vqtex.sim.bench.fuzz import ALLOC_BOUND, join_vqt, mutate_vqt, run_mutations, seed_files, split_vqt, try_file

FILES = seed_files()


def _edit(data: bytes, change) -> bytes:
    """``data`` with its JSON header changed by ``change(header_dict)`` (or text), checksum recomputed."""
    prefix, header, body = split_vqt(data)
    obj = json.loads(header)
    out = change(obj)
    text = out if isinstance(out, str) else json.dumps(obj)
    return join_vqt(prefix, text.encode(), body)


def _descriptor_edit(data: bytes, field: str, value: int, tex: int = 0, level: int = 1) -> bytes:
    ts = TextureSet.from_bytes(data)
    ts.descriptors[tex, level][field] = value
    return ts.to_bytes()


def _set(obj, path, value):
    for k in path[:-1]:
        obj = obj[k]
    obj[path[-1]] = value


CASES = {
    "dtype with a comma": lambda d: _edit(d, lambda h: _set(h, ["arrays", "raw_words", "dtype"], "<u4,<u4")),
    "object dtype": lambda d: _edit(d, lambda h: _set(h, ["arrays", "codebook", "dtype"], "O")),
    "word width of infinity": lambda d: _edit(d, lambda h: json.dumps(h).replace('"word_bits": 32', '"word_bits": Infinity')),
    "word width 1e999": lambda d: _edit(d, lambda h: json.dumps(h).replace('"word_bits": 32', '"word_bits": 1e999')),
    "deeply nested JSON": lambda d: _edit(d, lambda h: json.dumps(h).replace('"params": {', '"deep": ' + "[" * 100000 + "]" * 100000 + ', "params": {', 1)),
    "sub-level count 10^9": lambda d: _edit(d, lambda h: _set(h, ["codebooks", 0, "nsub"], 10**9)),
    "codebook of size 0": lambda d: _edit(d, lambda h: _set(h, ["codebooks", 0, "size"], 0)),
    "missing key": lambda d: _edit(d, lambda h: h["textures"][0].pop("levels")),
    "bool as an integer": lambda d: _edit(d, lambda h: _set(h, ["textures", 0, "index_bits"], True)),
    "index words of rank 2": lambda d: _edit(d, lambda h: _set(h, ["arrays", "index_words", "shape"],
                                                               [1, h["arrays"]["index_words"]["shape"][0]])),
    "1 GiB level 0": lambda d: _descriptor_edit(d, "log2w", 31, level=0),
    "level wider than the texture": lambda d: _descriptor_edit(d, "log2w", 12, level=0),
    "sub-level base elsewhere": lambda d: _descriptor_edit(d, "base", 1, level=1),
    "index width elsewhere": lambda d: _descriptor_edit(d, "index_bits", 9, level=0),
    "plane offset elsewhere": lambda d: _descriptor_edit(d, "texel_off", 3, level=1),
    "decode of the wrong size": lambda d: _edit(d, lambda h: _set(h, ["textures", 0, "width"], 128)),
    "array past the end": lambda d: _edit(d, lambda h: _set(h, ["arrays", "raw_words", "offset"], 10**12)),
    "huge integer": lambda d: _edit(d, lambda h: json.dumps(h).replace('"word_bits": 32', '"word_bits": ' + "9" * 5000)),
    "levels past 1x1": lambda d: _edit(d, lambda h: _set(h, ["textures", 0, "levels"], 16)),
}


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
                assert decode(ts, t, L).shape[:2] == (h, w)
    assert seen > 30
