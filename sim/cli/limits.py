"""The one validator of the command line's numbers and addresses: ``argparse`` types that parse an
option's text and check it before any work.

Contract of every type here:

* **a number is finite** (``nan``, ``inf``, ``1e400`` are refused), **in its stated range** and, for
  an integer, **fits the integer width it is used at** (the range never reaches past it: a seed is at
  most 2^63 - 1, a cache tile side at most 4096);
* the range is stated once, on the type (:attr:`Number.range_text`), and shown by ``--help``
  (:func:`number_help`) and by the one-line error (``vqtex: error: sim: argument --stall: 'nan' is
  not a finite number in [0, 1)``): the same option means the same range in every command, because
  every command builds it from the same constant below;
* a bad value raises ``argparse.ArgumentTypeError``, which :class:`vqtex.sim.cli.common.Parser`
  turns into that one line and exit status 2, before the command starts.

Tests find the options to probe by their types (``tests/sim/cli/test_limits.py`` walks the parser):
an option whose text is a number must use one of these types (or ``int`` with ``choices``).

This module imports nothing of the project: :mod:`vqtex.sim.cli.common` and the subcommands import it.
"""

from __future__ import annotations

import argparse
import math
import re

__all__ = ["Number", "Pair", "ListOf", "Address", "number_help", "INT32_MAX", "INT63_MAX",
           "STALL", "SEED", "PLACER_SEED", "TAG_WIDTH", "CODEBOOK_SIZE", "INDEX_BITS", "BLOCK", "BLOCK_SIDE",
           "CACHE_TILE", "TEXTURE", "LEVEL", "FOVEA_RADIUS", "FOVEA_FALLOFF", "DIFF_SCALE", "FREQ", "TIMEOUT",
           "KEEP_MB", "THREADS", "WORKERS", "FRAME_STEP", "SCHEDULER", "BENCH_SIZES", "BENCH_BLOCKS",
           "CACHE_BYTES", "CACHE_LINE", "PREFETCH", "MEMORY_LATENCY", "MEMORY_BANDWIDTH", "BUS_BYTES",
           "DRAM_CLOCK", "CONTROLLER_CYCLES"]

INT32_MAX = 2**31 - 1
INT63_MAX = 2**63 - 1


def _show(v) -> str:
    """A bound as the user would type it: 4096, 0.5, 2^63 - 1."""
    if isinstance(v, float) and v.is_integer():
        v = int(v)
    if isinstance(v, int) and v >= 2**20 and not (v + 1) & v:
        return f"2^{(v + 1).bit_length() - 1} - 1"
    if isinstance(v, int) and v >= 2**20 and not v & (v - 1):
        return f"2^{v.bit_length() - 1}"
    return str(v)


class Number:
    """An ``argparse`` type: ``kind`` (``int`` or ``float``) from text, finite, in ``[lo, hi]`` (an end
    is open with ``lo_open`` / ``hi_open``, absent when None), and with ``powers_of_two`` a power of
    two. Integers are read in base 10 (``1_000`` too), never from a float's text (``2.0``)."""

    def __init__(self, kind, lo=None, hi=None, *, lo_open=False, hi_open=False, powers_of_two=False, unit=""):
        if kind not in (int, float):
            raise TypeError("kind is int or float")
        if kind is int and (lo is None or hi is None):
            raise ValueError("an integer option states both ends (the width it is used at)")
        self.kind, self.lo, self.hi, self.lo_open, self.hi_open = kind, lo, hi, lo_open, hi_open
        self.powers_of_two, self.unit = powers_of_two, unit
        self.__name__ = "integer" if kind is int else "number"      # argparse's "invalid ... value"

    @property
    def range_text(self) -> str:
        """The range as help and errors show it: ``0..16``, ``[0, 1)``, ``powers of two 1..8``."""
        unit = f" {self.unit}" if self.unit else ""
        if self.kind is int:
            text = f"{_show(self.lo)}..{_show(self.hi)}{unit}"
            return f"powers of two {text}" if self.powers_of_two else text
        if self.hi is None:
            return f"{'>' if self.lo_open else '>='} {_show(self.lo)}{unit}"
        if self.lo is None:
            return f"{'<' if self.hi_open else '<='} {_show(self.hi)}{unit}"
        return f"{'(' if self.lo_open else '['}{_show(self.lo)}, {_show(self.hi)}{')' if self.hi_open else ']'}{unit}"

    def check(self, value):
        """``value`` (already a number) if it is in range, else ValueError naming the range."""
        if isinstance(value, float) and not math.isfinite(value):
            raise ValueError(f"{value} is not a finite number")
        lo_bad = self.lo is not None and (value <= self.lo if self.lo_open else value < self.lo)
        hi_bad = self.hi is not None and (value >= self.hi if self.hi_open else value > self.hi)
        pow_bad = self.powers_of_two and (value < 1 or value & (value - 1))
        if lo_bad or hi_bad or pow_bad:
            raise ValueError(f"{value} is not in {self.range_text}")
        return value

    def parse(self, text: str):
        """The number in ``text``, checked; ValueError with a one-line message otherwise."""
        s = str(text).strip()
        what = "an integer" if self.kind is int else "a finite number"
        if self.kind is int:
            if not re.fullmatch(r"[+-]?\d+(_\d+)*", s):
                raise ValueError(f"{text!r} is not {what} in {self.range_text}")
            value = int(s)
        else:
            try:
                value = float(s)
            except ValueError:
                raise ValueError(f"{text!r} is not {what} in {self.range_text}") from None
            if not math.isfinite(value):
                raise ValueError(f"{text!r} is not {what} in {self.range_text}")
        try:
            return self.check(value)
        except ValueError:
            raise ValueError(f"{text!r} is not in {self.range_text}") from None

    def __call__(self, text: str):
        try:
            return self.parse(text)
        except ValueError as e:
            raise argparse.ArgumentTypeError(str(e)) from None

    def __repr__(self) -> str:
        return f"Number({self.kind.__name__}, {self.range_text})"


class Pair:
    """An ``argparse`` type: ``WxH`` (``4x4``), each side a :class:`Number` ``side``."""

    def __init__(self, side: Number, what: str = "block"):
        self.side, self.what = side, what
        self.__name__ = "WxH"

    @property
    def range_text(self) -> str:
        return f"WxH, sides {self.side.range_text}"

    def parse(self, text: str) -> tuple:
        parts = str(text).lower().split("x")
        if len(parts) != 2:
            raise ValueError(f"{self.what} {text!r} is not WxH (e.g. 4x4; sides {self.side.range_text})")
        try:
            return tuple(self.side.parse(p) for p in parts)
        except ValueError:
            raise ValueError(f"{self.what} {text!r}: sides must be {self.side.range_text}") from None

    def __call__(self, text: str) -> tuple:
        try:
            return self.parse(text)
        except ValueError as e:
            raise argparse.ArgumentTypeError(str(e)) from None


class ListOf:
    """An ``argparse`` type: a comma-separated list of ``item`` values (a :class:`Number` or :class:`Pair`),
    at least one, at most ``most``."""

    def __init__(self, item, most: int = 64):
        self.item, self.most = item, most
        self.__name__ = "list"

    @property
    def range_text(self) -> str:
        return f"comma-separated, each {self.item.range_text}"

    def __call__(self, text: str) -> tuple:
        parts = [p for p in str(text).split(",")]
        if not 1 <= len(parts) <= self.most:
            raise argparse.ArgumentTypeError(f"{text!r}: 1..{self.most} values, {self.range_text}")
        try:
            return tuple(self.item.parse(p) for p in parts)
        except ValueError as e:
            raise argparse.ArgumentTypeError(str(e)) from None


class Address:
    """An ``argparse`` type: ``serial``, or a dask scheduler address ``[tcp|tls|ws|wss|ucx://]HOST:PORT``
    (port 1..65535; an IPv6 host in brackets). Only the form is checked here; whether a scheduler
    answers there is known when the command connects."""

    SCHEMES = ("tcp", "tls", "ws", "wss", "ucx")

    def __init__(self, special=("serial",)):
        self.special = tuple(special)
        self.__name__ = "address"

    @property
    def range_text(self) -> str:
        return " or ".join(repr(s) for s in self.special) + " or tcp://HOST:PORT (port 1..65535)"

    def parse(self, text: str) -> str:
        s = str(text).strip()
        if s in self.special:
            return s
        m = re.fullmatch(r"(?:([a-z]+)://)?(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.-]+):([0-9]+)/?", s)
        if not m or (m.group(1) is not None and m.group(1) not in self.SCHEMES):
            raise ValueError(f"{text!r} is not {self.range_text}")
        _PORT.parse(m.group(3))
        return s if m.group(1) else f"tcp://{s}"

    def __call__(self, text: str) -> str:
        try:
            return self.parse(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not {self.range_text}") from None


_PORT = Number(int, 1, 65535)


def number_help(text: str, kind, default) -> str:
    """Help text stating the option's range and ending with its default: ``TEXT, RANGE (default D)``."""
    return f"{text}; {kind.range_text} (default {default})"


# -- The ranges: one constant per option, shared by every command that has the option. ------------

#: ``--stall``: the probability the consumer holds ready low in a cycle.
STALL = Number(float, 0.0, 1.0, hi_open=True)
#: Seeds of numpy's generators (``--stall-seed``, ``--encoder-seed``): one int64's non-negative range.
SEED = Number(int, 0, INT63_MAX)
#: nextpnr's ``--seed`` (a C++ int).
PLACER_SEED = Number(int, 0, INT32_MAX)
#: ``--tag-width``: bits of the request tag.
TAG_WIDTH = Number(int, 0, 16)
#: ``-k``: codewords (the paper's layout takes 2..4096, PowerVR2 1..256).
CODEBOOK_SIZE = Number(int, 1, 4096)
#: ``--index-bits``.
INDEX_BITS = Number(int, 1, 16)
#: A block side.
BLOCK_SIDE = Number(int, 1, 8, powers_of_two=True)
#: ``--block``.
BLOCK = Pair(BLOCK_SIDE)
#: ``need --cache-tile``: the cache's sets as a tile of block coordinates (at most 2^24 sets).
CACHE_TILE = Pair(Number(int, 1, 4096, powers_of_two=True), "cache tile")
#: ``decode --texture``, ``--level``: numbers in a file (int32); the file says which exist.
TEXTURE = Number(int, 0, INT32_MAX)
LEVEL = Number(int, 0, INT32_MAX)
#: ``--memory external`` (docs/memory.md): a cache's bytes and its line (its ways: ``--cache-ways``, a
#: choice, as ``vqtex need`` has it); the reference FIFO's
#: depth (1: blocking); the fixed memory's latency and bandwidth; the AXI data width; the DRAM
#: controller's clock and its own latency.
CACHE_BYTES = Number(int, 64, 2**24, powers_of_two=True, unit="bytes")
CACHE_LINE = Number(int, 4, 4096, powers_of_two=True, unit="bytes")
PREFETCH = Number(int, 1, 4096)
MEMORY_LATENCY = Number(int, 1, 100000, unit="cycles")
MEMORY_BANDWIDTH = Number(int, 1, 1024, unit="bytes/clock")
BUS_BYTES = Number(int, 1, 128, powers_of_two=True, unit="bytes")
DRAM_CLOCK = Number(float, 1.0, 2000.0, unit="MHz")
CONTROLLER_CYCLES = Number(int, 0, 1000, unit="cycles")
#: ``render --fovea-radius`` (pixels) and ``--fovea-falloff`` (levels per radius).
FOVEA_RADIUS = Number(float, 0.0, 1e9, lo_open=True, unit="pixels")
FOVEA_FALLOFF = Number(float, 0.0, 1e9)
#: ``render --diff-scale``: levels of an 8-bit difference.
DIFF_SCALE = Number(int, 1, 255)
#: ``report area --freq`` (MHz) and ``--timeout`` (seconds).
FREQ = Number(float, 1.0, 1000.0, unit="MHz")
TIMEOUT = Number(float, 0.0, 1e6, lo_open=True, unit="s")
#: ``cache clean --keep-mb``: bytes fit an int64.
KEEP_MB = Number(float, 0.0, float(2**43), unit="MB")
#: ``bench --threads`` (0: the libraries' defaults) and ``--workers``.
THREADS = Number(int, 0, 1024)
WORKERS = Number(int, 1, 1024)
#: ``experiments --frame-step``.
FRAME_STEP = Number(int, 1, INT32_MAX)
#: ``--scheduler``.
SCHEDULER = Address()
#: ``bench tradeoff --sizes`` and ``--blocks``.
BENCH_SIZES = ListOf(Number(int, 2, 4096))
BENCH_BLOCKS = ListOf(BLOCK)
