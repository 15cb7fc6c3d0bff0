"""The ``.vqt`` header as untrusted input: parsed and checked before anything is built from it.

``parse_header(raw, body_size)`` turns the header bytes of a ``.vqt`` file into plain Python values
or raises :class:`~.format.FormatError` with one line. Contract:

- The header is at most ``MAX_HEADER_BYTES``; its JSON nests at most ``MAX_DEPTH`` deep (checked on
  the bytes before parsing, so the parser never recurses deeper); ``NaN``, ``Infinity`` and numbers
  that overflow a float are refused.
- Every key is present and no other key is; every value has its type (``bool`` is not an ``int``)
  and its range: word width 16/32/64, sizes powers of two up to ``MAX_SIZE``, at most ``MAX_LEVELS``
  levels, block sides 1..8 (powers of two), index widths 1..16, codebooks of 1..65536 codewords with
  1..3 sub-levels, at most ``MAX_TEXTURES`` textures and codebooks, names of at most 256 characters,
  encoder parameters a flat dictionary of scalars, a colour matrix the hardware can build.
- Each array is described by a dtype from a fixed list for that array (no structured, object or
  comma dtypes), a shape of the right rank, and an offset and byte count that lie inside the
  ``body_size`` bytes that follow the header: the caller allocates at most what the file holds.
- A pruned set (``golden.need.prune``) may also hold, per texture, ``absent_levels`` (distinct increasing
  level numbers below its level count, at least one) and the array ``present_blocks`` (bytes).
"""

from __future__ import annotations

import json
import math

import numpy as np

from .constants import (COLORS, DESCRIPTOR_DTYPE, DESCRIPTOR_FIELDS, LEGACY_DESCRIPTOR_DTYPE, LEGACY_DESCRIPTOR_FIELDS, MAX_LEVELS, MAX_SIZE, WORD_BITS_ALLOWED,
                        FormatError)

__all__ = ["parse_header", "MAX_HEADER_BYTES", "MAX_DEPTH", "MAX_TEXTURES", "ARRAY_DTYPES", "OPTIONAL_ARRAYS"]

MAX_HEADER_BYTES = 16 << 20
MAX_DEPTH = 16
MAX_TEXTURES = 4096
#: array -> (allowed dtype strings, rank). The index words' dtype must also match the word width.
ARRAY_DTYPES = {
    "index_words": (("<u2", "<u4", "<u8"), 1),
    "codebook": (("|u1",), 2),
    "raw_words": (("<u4",), 1),
    "descriptors": (("descriptor",), 2),
    "present_blocks": (("|u1",), 1),
}
#: Arrays only a pruned set holds (``golden.need.prune``); every other array is in every file.
OPTIONAL_ARRAYS = ("present_blocks",)
_TEXTURE_KEYS = {"name", "width", "height", "levels", "color", "block", "codebook", "index_bits", "mipmapped", "params"}
_CODEBOOK_KEYS = {"color", "block", "nsub", "size", "base"}
_HEADER_KEYS = {"word_bits", "entry_bytes", "descriptor_fields", "matrix", "textures", "codebooks", "arrays"}


def _fail(msg: str):
    raise FormatError(f"malformed .vqt header: {msg}")


def _depth_ok(raw: bytes) -> bool:
    """Bracket nesting of the JSON text (brackets inside strings count too: a conservative bound)."""
    b = np.frombuffer(raw, np.uint8)
    step = (np.isin(b, (ord("["), ord("{"))).astype(np.int32) - np.isin(b, (ord("]"), ord("}"))))
    return not len(step) or int(np.cumsum(step).max()) <= MAX_DEPTH


def _refuse_constant(name):
    _fail(f"{name} is not a number a .vqt may hold")


def _finite_float(text):
    v = float(text)
    if not math.isfinite(v):
        _fail(f"{text} is not a finite number")
    return v


def _int(v, what, lo, hi):
    if type(v) is not int or not lo <= v <= hi:
        _fail(f"{what} must be an integer in {lo}..{hi}, not {v!r:.40}")
    return v


def _pow2(v, what, hi):
    _int(v, what, 1, hi)
    if v & (v - 1):
        _fail(f"{what} {v} is not a power of two")
    return v


def _dict(v, what, keys, optional=()):
    if type(v) is not dict:
        _fail(f"{what} must be an object")
    missing = keys - v.keys()
    extra = v.keys() - keys - set(optional)
    if missing or extra:
        _fail(f"{what}: missing {sorted(missing)}" if missing else f"{what}: unknown keys {sorted(extra)}")
    return v


def _list(v, what, lo, hi):
    if type(v) is not list or not lo <= len(v) <= hi:
        _fail(f"{what} must be a list of {lo}..{hi} items")
    return v


def _block(v, what):
    _list(v, what, 2, 2)
    return [_pow2(x, f"{what} side", 8) for x in v]


def _color(v, what):
    if v not in COLORS:
        _fail(f"{what} colour {v!r:.40} is not one of {COLORS}")
    return v


def _matrix(m):
    _dict(m, "matrix", {"coeffs", "offsets", "frac_bits", "rounding"}, optional=("reference_coeffs",))
    rows = _list(m["coeffs"], "matrix coeffs", 3, 3)
    for r in rows:
        for x in _list(r, "matrix coeffs row", 3, 3):
            _int(x, "matrix coefficient", -(1 << 17), (1 << 17) - 1)
    for x in _list(m["offsets"], "matrix offsets", 3, 3):
        _int(x, "matrix offset", 0, 255)
    _int(m["frac_bits"], "matrix frac_bits", 0, 16)
    if type(m["rounding"]) is not bool:
        _fail("matrix rounding must be true or false")
    if "reference_coeffs" in m and m["reference_coeffs"] is not None:
        for r in _list(m["reference_coeffs"], "matrix reference", 3, 3):
            for x in _list(r, "matrix reference row", 3, 3):
                if type(x) not in (int, float):
                    _fail("matrix reference coefficients must be numbers")
    return m


def _texture(t, k):
    what = f"texture {k}"
    _dict(t, what, _TEXTURE_KEYS, optional=("absent_levels",))
    if type(t["name"]) is not str or len(t["name"]) > 256:
        _fail(f"{what} name must be a string of at most 256 characters")
    _pow2(t["width"], f"{what} width", MAX_SIZE)
    _pow2(t["height"], f"{what} height", MAX_SIZE)
    _int(t["levels"], f"{what} levels", 1, MAX_LEVELS)
    _color(t["color"], what)
    _block(t["block"], f"{what} block")
    _int(t["codebook"], f"{what} codebook", -1, MAX_TEXTURES - 1)
    _int(t["index_bits"], f"{what} index_bits", 1, 16)
    if type(t["mipmapped"]) is not bool:
        _fail(f"{what} mipmapped must be true or false")
    params = t["params"]
    if type(params) is not dict or len(params) > 64 or any(
            type(key) is not str or type(v) not in (str, int, float, bool, type(None)) for key, v in params.items()):
        _fail(f"{what} params must be a flat object of at most 64 scalars")
    if "absent_levels" in t:
        absent = [_int(L, f"{what} absent level", 0, t["levels"] - 1)
                  for L in _list(t["absent_levels"], f"{what} absent_levels", 1, t["levels"])]
        if absent != sorted(set(absent)):
            _fail(f"{what} absent_levels must be distinct and increasing")
    return t


def _codebook(c, k):
    what = f"codebook {k}"
    _dict(c, what, _CODEBOOK_KEYS)
    _color(c["color"], what)
    _block(c["block"], f"{what} block")
    _int(c["nsub"], f"{what} nsub", 1, 3)
    _int(c["size"], f"{what} size", 1, 1 << 16)
    _int(c["base"], f"{what} base", 0, 1 << 40)
    return c


def _arrays(a, body_size, descriptor_dtype=DESCRIPTOR_DTYPE):
    _dict(a, "arrays", set(ARRAY_DTYPES) - set(OPTIONAL_ARRAYS), optional=OPTIONAL_ARRAYS)
    out = {}
    for name, (dtypes, rank) in ARRAY_DTYPES.items():
        if name not in a:
            continue
        spec = _dict(a[name], f"array {name}", {"shape", "offset", "nbytes", "dtype"})
        if spec["dtype"] not in dtypes:
            _fail(f"array {name} has dtype {spec['dtype']!r:.40}, not one of {dtypes}")
        shape = [_int(x, f"array {name} dimension", 0, body_size) for x in _list(spec["shape"], f"array {name} shape", rank, rank)]
        off = _int(spec["offset"], f"array {name} offset", 0, body_size)
        nbytes = _int(spec["nbytes"], f"array {name} nbytes", 0, body_size)
        item = descriptor_dtype.itemsize if spec["dtype"] == "descriptor" else np.dtype(spec["dtype"]).itemsize
        if math.prod(shape) * item != nbytes or off + nbytes > body_size:
            _fail(f"array {name} of shape {shape} does not fit its {nbytes} bytes inside the file")
        out[name] = (spec["dtype"], tuple(shape), off, nbytes)
    return out


def parse_header(raw: bytes, body_size: int) -> dict:
    """The checked header: ``word_bits``, ``entry_bytes``, ``matrix`` (dict), ``textures``,
    ``codebooks`` (lists of dicts), ``arrays`` (name -> (dtype string, shape, offset, nbytes)),
    ``descriptor_dtype`` (the descriptor rows' dtype: the current fields, or those of files written
    before the ``layout`` field, which the caller widens with layout 0)."""
    if len(raw) > MAX_HEADER_BYTES:
        _fail(f"{len(raw)} bytes (at most {MAX_HEADER_BYTES})")
    if not _depth_ok(raw):
        _fail(f"nested deeper than {MAX_DEPTH}")
    try:
        h = json.loads(raw.decode("utf-8"), parse_constant=_refuse_constant, parse_float=_finite_float)
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as e:
        _fail(f"not JSON ({str(e).splitlines()[0][:80]})")
    except ValueError as e:                      # e.g. an integer of more digits than Python parses
        _fail(str(e).splitlines()[0][:80])
    _dict(h, "header", _HEADER_KEYS)
    if h["word_bits"] not in WORD_BITS_ALLOWED or type(h["word_bits"]) is not int:
        _fail(f"word_bits {h['word_bits']!r:.40} is not one of {WORD_BITS_ALLOWED}")
    _int(h["entry_bytes"], "entry_bytes", 0, 1 << 16)
    if h["descriptor_fields"] == list(DESCRIPTOR_FIELDS):
        descriptor_dtype = DESCRIPTOR_DTYPE
    elif h["descriptor_fields"] == list(LEGACY_DESCRIPTOR_FIELDS):     # written before ``layout``
        descriptor_dtype = LEGACY_DESCRIPTOR_DTYPE
    else:
        _fail("descriptor fields differ from this reader's")
    _matrix(h["matrix"])
    textures = [_texture(t, k) for k, t in enumerate(_list(h["textures"], "textures", 0, MAX_TEXTURES))]
    codebooks = [_codebook(c, k) for k, c in enumerate(_list(h["codebooks"], "codebooks", 0, MAX_TEXTURES))]
    arrays = _arrays(h["arrays"], body_size, descriptor_dtype)
    if arrays["index_words"][0] != f"<u{h['word_bits'] // 8}":
        _fail("index memory dtype does not match the word width")
    return {"word_bits": h["word_bits"], "entry_bytes": h["entry_bytes"], "matrix": h["matrix"],
            "textures": textures, "codebooks": codebooks, "arrays": arrays,
            "descriptor_dtype": descriptor_dtype}
