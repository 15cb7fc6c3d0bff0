"""Mutated ``.vqt`` files, as an attacker would make them: the container's hostile-input test.

A mutation starts from a valid file (a few small texture sets covering the formats) and changes its
bytes or its JSON header, then **recomputes the header length and the CRC**, so the change reaches
the parser (anyone can make such a file). Each mutated file is loaded, and if it loads, used the way
``vqtex info`` and ``vqtex decode`` use it (every rate, every level's shape, every level decoded).

Outcomes (``try_file``):

- ``rejected``: :class:`vqtex.golden.format.FormatError` (the one documented exception);
- ``accepted``: loaded and used without error, within the time and memory bounds;
- ``crash:<Type>``: any other exception;
- ``hang``: took longer than ``timeout`` seconds (the worker process is killed);
- ``big-alloc``: allocated more than ``64 MiB + 16 x`` the file's size (tracemalloc's peak, which
  numpy reports to).

``run_mutations(n, seed)`` runs ``n`` mutations in worker processes (a fresh worker replaces one that
hangs) and returns the counts by outcome with one example of each. Deterministic for a seed.
"""

from __future__ import annotations

import json
import multiprocessing as mp
import struct
import time
import zlib

import numpy as np

__all__ = ["seed_files", "mutate_vqt", "try_file", "run_mutations", "ALLOC_BOUND", "split_vqt", "join_vqt"]

MAGIC_LEN = 8


def ALLOC_BOUND(size: int) -> int:
    """Most bytes a file of ``size`` bytes may make us allocate."""
    return (64 << 20) + 16 * size


def seed_files() -> list:
    """Small valid .vqt files covering the formats: rgb mipmapped 8-bit, yuv411 12-bit, rgba,
    intensity on 16-bit words with TSVQ, a raw-only set, the first three combined, and the first
    pruned to a few texels of two levels (``golden.need.prune``)."""
    from vqtex.golden.encode import encode
    from vqtex.golden.format import TextureSet
    rng = np.random.default_rng(0)

    def img(h, w, c):
        yy, xx = np.mgrid[0:h, 0:w]
        base = np.stack([xx * 7, yy * 5, (xx + yy) * 3, 255 - xx][:c], -1)
        return np.clip(base + rng.integers(0, 40, (h, w, c)), 0, 255).astype(np.uint8)

    sets = [
        encode([img(64, 64, 3)], codebook_size=16, mipmaps=True, index_bits=8),
        encode([img(32, 32, 3), img(32, 32, 3)], codebook_size=8, color="yuv411", block=(2, 2), index_bits=12),
        encode([img(32, 32, 4)], codebook_size=16, color="rgba", index_bits=5),
        encode([img(32, 32, 1)], codebook_size=8, color="intensity", block=(2, 2), encoder="tsvq", word_bits=16),
        encode([img(8, 8, 3)], codebook_size=4, mipmaps=True),
    ]
    sets.append(TextureSet.combine(sets[:3]))
    from vqtex.golden.need.analysis import analyse
    from vqtex.golden.need.prune import prune
    reqs = np.array([[0, 1, 0, 0], [0, 1, 9, 30], [0, 4, 3, 2]])   # pruned: absent levels, block presence bits
    sets.append(prune(sets[0], analyse(sets[0], [reqs])))
    return [s.to_bytes() for s in sets]


def split_vqt(data: bytes):
    """(magic and version, header bytes, memories) of a .vqt image."""
    hlen = struct.unpack_from("<I", data, MAGIC_LEN + 4)[0]
    start = MAGIC_LEN + 8
    return data[:MAGIC_LEN + 4], data[start:start + hlen], data[start + hlen:-4]


def join_vqt(prefix: bytes, header: bytes, body: bytes) -> bytes:
    """A .vqt image from its parts, with the header length and the CRC recomputed."""
    out = prefix + struct.pack("<I", len(header)) + header + body
    return out + struct.pack("<I", zlib.crc32(out))


_NASTY = [0, -1, 1, 2, 3, 7, 8, 12, 13, 15, 16, 17, 31, 32, 33, 63, 64, 65, 255, 256, 4095, 4096, 4097,
          65535, 65536, 2**31 - 1, 2**31, 2**32, 2**63, 10**30, -2**31, 1.5, -0.0, 1e308, True, False, None,
          "", "x", "<u4,<u4", "O", "<f8", "|V8", "descriptor", "rgb", "yuv411", "<u8", [], {}, [1], [1, 2],
          [[1, 2]], {"a": 1}]


def _paths(obj, prefix=()):
    """Every (path, value) in a JSON structure, iteratively."""
    out, stack = [], [(prefix, obj)]
    while stack:
        p, v = stack.pop()
        out.append((p, v))
        if isinstance(v, dict):
            stack += [(p + (k,), x) for k, x in v.items()]
        elif isinstance(v, list):
            stack += [(p + (k,), x) for k, x in enumerate(v)]
    return out


def _mutate_header(header: bytes, rng) -> bytes:
    obj = json.loads(header)
    paths = _paths(obj)
    path, value = paths[int(rng.integers(len(paths)))]
    if not path:
        return header
    parent = obj
    for k in path[:-1]:
        parent = parent[k]
    key = path[-1]
    r = rng.random()
    if r < 0.12 and isinstance(parent, dict):
        del parent[key]
    elif r < 0.18:                               # deep nesting (spliced in as text: no recursion here)
        parent[key] = "__NESTED__"
    elif r < 0.5 and isinstance(value, (int, float)) and not isinstance(value, bool):
        parent[key] = type(value)(value + int(rng.integers(-3, 4))) if rng.random() < 0.5 else value * int(rng.integers(2, 1 << 20))
    elif r < 0.56 and isinstance(value, list) and value:
        parent[key] = value[:-1] if rng.random() < 0.5 else value + [value[-1]]
    else:
        parent[key] = _NASTY[int(rng.integers(len(_NASTY)))]
    text = json.dumps(obj, sort_keys=True, allow_nan=True)
    depth = int(rng.integers(50, 5000))
    text = text.replace('"__NESTED__"', "[" * depth + "0" + "]" * depth)
    if rng.random() < 0.05:                      # JSON's non-standard constants, as Python writes them
        text = text.replace("1e+308", "Infinity", 1)
    return text.encode()


def mutate_vqt(data: bytes, rng) -> bytes:
    """One mutation of a valid .vqt image (header length and CRC recomputed)."""
    prefix, header, body = split_vqt(data)
    r = rng.random()
    if r < 0.5:
        header = _mutate_header(header, rng)
    elif r < 0.85 and body:                       # the memories: flip bytes (descriptors are at the end)
        b = bytearray(body)
        for _ in range(int(rng.integers(1, 9))):
            pos = len(b) - 1 - int(rng.integers(0, min(len(b), 4096))) if rng.random() < 0.7 else int(rng.integers(len(b)))
            b[pos] = int(rng.integers(256))
        body = bytes(b)
    elif r < 0.95:                                 # the header's bytes
        h = bytearray(header)
        for _ in range(int(rng.integers(1, 5))):
            h[int(rng.integers(len(h)))] = int(rng.choice(list(b'{}[]",:0123456789-eE.x ')))
        header = bytes(h)
    else:                                          # truncated or extended memories
        body = body[: int(rng.integers(len(body) + 1))] if rng.random() < 0.5 else body + bytes(int(rng.integers(1, 64)))
    return join_vqt(prefix, header, body)


def _use(data: bytes) -> None:
    """Load, then do what ``vqtex info`` and ``vqtex decode`` do."""
    from vqtex.golden.fetch import decode
    from vqtex.golden.format import TextureSet
    ts = TextureSet.from_bytes(data)
    ts.rates()
    for t in range(ts.n_textures):
        ts.rates(t)
        for L, (w, h) in enumerate(ts.level_shapes(t)):
            if not ts.textures[t].stored(L):
                continue                            # pruned away: decode refuses it (RequestError)
            img = decode(ts, t, L)
            assert img.shape[:2] == (h, w), f"decode of texture {t} level {L} gave {img.shape}, expected {(h, w)}"


def _classify(data: bytes) -> tuple[str, str]:
    import tracemalloc
    from vqtex.golden.format import FormatError
    tracemalloc.start()
    try:
        _use(data)
        outcome, detail = "accepted", ""
    except FormatError as e:
        outcome, detail = "rejected", str(e)[:200]
    except Exception as e:                          # noqa: BLE001 -- every other type is the finding
        outcome, detail = f"crash:{type(e).__name__}", str(e)[:200]
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    if peak > ALLOC_BOUND(len(data)):
        outcome, detail = "big-alloc", f"{peak >> 20} MiB for a file of {len(data)} bytes"
    return outcome, detail


def try_file(data: bytes) -> tuple[str, str]:
    """(outcome, detail) of one file, in this process (no hang protection: see ``run_mutations``)."""
    return _classify(data)


def _worker(conn):
    while True:
        data = conn.recv()
        if data is None:
            return
        conn.send(_classify(data))


class _Worker:
    def __init__(self, ctx):
        self.conn, child = ctx.Pipe()
        self.proc = ctx.Process(target=_worker, args=(child,), daemon=True)
        self.proc.start()

    def stop(self, kill=False):
        if kill:
            self.proc.kill()
        else:
            self.conn.send(None)
        self.proc.join()


def run_mutations(n: int, seed: int = 0, *, timeout: float = 2.0, workers: int | None = None,
                  files: list | None = None) -> dict:
    """``n`` mutated files through ``try_file`` in worker processes; counts by outcome."""
    import os
    ctx = mp.get_context("fork" if "fork" in mp.get_all_start_methods() else "spawn")
    files = files or seed_files()
    rng = np.random.default_rng(seed)
    nworkers = workers or min(2, os.cpu_count() or 1)
    pool = [_Worker(ctx) for _ in range(nworkers)]
    counts: dict = {}
    examples: dict = {}
    t0 = time.perf_counter()
    pending = {}                                  # worker index -> (data, sent time)
    made = 0
    try:
        while made < n or pending:
            for k, w in enumerate(pool):
                if k not in pending and made < n:
                    data = mutate_vqt(files[int(rng.integers(len(files)))], rng)
                    w.conn.send(data)
                    pending[k] = (data, time.monotonic())
                    made += 1
            for k in list(pending):
                w = pool[k]
                data, sent = pending[k]
                if w.conn.poll(0.001):
                    outcome, detail = w.conn.recv()
                elif time.monotonic() - sent > timeout:
                    w.stop(kill=True)
                    pool[k] = _Worker(ctx)
                    outcome, detail = "hang", f"over {timeout} s"
                else:
                    continue
                del pending[k]
                counts[outcome] = counts.get(outcome, 0) + 1
                if outcome not in examples:
                    examples[outcome] = {"detail": detail, "bytes": len(data)}
    finally:
        for w in pool:
            w.stop(kill=True)
    return {"mutations": n, "seed": seed, "counts": dict(sorted(counts.items())), "examples": examples,
            "seconds": round(time.perf_counter() - t0, 1), "timeout_seconds": timeout}
