"""Hostile .vqt files for tests (not a test module): valid seed files and changes to their JSON
header or descriptors, each with a correct checksum (``HOSTILE_CASES``, ``hostile_files``)."""

from __future__ import annotations

import functools
import json

from vqtex.golden.format import TextureSet
from vqtex.sim.bench.robustness.fuzz import join_vqt, seed_files, split_vqt

__all__ = ["hostile_files", "edit_header", "edit_descriptor", "set_key", "HOSTILE_CASES"]


@functools.lru_cache(maxsize=None)
def hostile_files() -> tuple:
    """The seed files the cases start from (``fuzz.seed_files``: rgb 64x64 mipmapped first)."""
    return tuple(seed_files())


def edit_header(data: bytes, change) -> bytes:
    """``data`` with its JSON header changed by ``change(header_dict)`` (or text), checksum recomputed."""
    prefix, header, body = split_vqt(data)
    obj = json.loads(header)
    out = change(obj)
    text = out if isinstance(out, str) else json.dumps(obj)
    return join_vqt(prefix, text.encode(), body)


def edit_descriptor(data: bytes, field: str, value: int, tex: int = 0, level: int = 1) -> bytes:
    """``data`` with one descriptor field of texture ``tex``, level ``level`` set to ``value``."""
    ts = TextureSet.from_bytes(data)
    ts.descriptors[tex, level][field] = value
    return ts.to_bytes()


def set_key(obj, path, value):
    """``obj[path[0]][path[1]]... = value``."""
    for k in path[:-1]:
        obj = obj[k]
    obj[path[-1]] = value


#: name -> a change of a valid file that loading must refuse with one FormatError.
HOSTILE_CASES = {
    "dtype with a comma": lambda d: edit_header(d, lambda h: set_key(h, ["arrays", "raw_words", "dtype"], "<u4,<u4")),
    "object dtype": lambda d: edit_header(d, lambda h: set_key(h, ["arrays", "codebook", "dtype"], "O")),
    "word width of infinity": lambda d: edit_header(d, lambda h: json.dumps(h).replace('"word_bits": 32', '"word_bits": Infinity')),
    "word width 1e999": lambda d: edit_header(d, lambda h: json.dumps(h).replace('"word_bits": 32', '"word_bits": 1e999')),
    "deeply nested JSON": lambda d: edit_header(d, lambda h: json.dumps(h).replace('"params": {', '"deep": ' + "[" * 100000 + "]" * 100000 + ', "params": {', 1)),
    "sub-level count 10^9": lambda d: edit_header(d, lambda h: set_key(h, ["codebooks", 0, "nsub"], 10**9)),
    "codebook of size 0": lambda d: edit_header(d, lambda h: set_key(h, ["codebooks", 0, "size"], 0)),
    "missing key": lambda d: edit_header(d, lambda h: h["textures"][0].pop("levels")),
    "bool as an integer": lambda d: edit_header(d, lambda h: set_key(h, ["textures", 0, "index_bits"], True)),
    "index words of rank 2": lambda d: edit_header(d, lambda h: set_key(h, ["arrays", "index_words", "shape"],
                                                               [1, h["arrays"]["index_words"]["shape"][0]])),
    "1 GiB level 0": lambda d: edit_descriptor(d, "log2w", 31, level=0),
    "level wider than the texture": lambda d: edit_descriptor(d, "log2w", 12, level=0),
    "sub-level base elsewhere": lambda d: edit_descriptor(d, "base", 1, level=1),
    "index width elsewhere": lambda d: edit_descriptor(d, "index_bits", 9, level=0),
    "plane offset elsewhere": lambda d: edit_descriptor(d, "texel_off", 3, level=1),
    "decode of the wrong size": lambda d: edit_header(d, lambda h: set_key(h, ["textures", 0, "width"], 128)),
    "array past the end": lambda d: edit_header(d, lambda h: set_key(h, ["arrays", "raw_words", "offset"], 10**12)),
    "huge integer": lambda d: edit_header(d, lambda h: json.dumps(h).replace('"word_bits": 32', '"word_bits": ' + "9" * 5000)),
    "levels past 1x1": lambda d: edit_header(d, lambda h: set_key(h, ["textures", 0, "levels"], 16)),
}
