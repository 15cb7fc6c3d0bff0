"""The codebook on chip against the codebook behind a cache (issue 25, item 2): what a codebook cache
would read from memory on a built-in scene's frame, beside what the index and raw caches read.

The cached unit keeps the codebook on chip, loaded through the bus port (docs/memory.md). The other
choice the issue names puts the codebook in external memory too, behind a third cache. This bench
measures that choice on the golden side, with the memory system's own LRU
(:func:`golden.memory.cache.classify`), before any RTL is built for it:

* **Entry lines**: a line is one entry of the codebook memory (``entry_bytes``, every sub-level of
  an extended mipmap codeword, rounded up to a power of two), so a miss reads one entry, the unit
  DC_MiSTer streams from VRAM. Entry ``e`` (``cb_base + index`` of the request's descriptor) is
  line ``e``, in set ``e mod sets``; 4 ways, LRU.
* **Texel lines** (``--texel-line``, default 16 bytes): the codebook memory as one byte array of
  entries ``entry_bytes`` apart, and a request reads the line of its texel's bytes (both lines when
  they straddle one): a miss reads only the part of the entry near the texel. The texel's bytes are
  those :func:`golden.fetch.read_codeword` reads first (``texel_off`` plus the texel's offset); the
  U and V bytes of the YUV formats, elsewhere in the entry, are not counted (none of the built-in
  scenes uses them).
* The index and raw caches are the cached unit's (32-byte lines, 4 ways, both of the row's size), as
  in ``python -m vqtex.sim.bench.scenes.memory --claim``.
* Requests are the frame's trilinear texel requests (:func:`golden.render.frame.frame_requests`);
  each compressed request reads one entry, raw requests none.

Printed per cache size: the codebook cache's hit rate and memory bytes per textured pixel, the
index and raw caches' bytes per pixel, and the fraction the codebook cache adds; and the on-chip
codebook's size (what the cached unit holds in block RAM instead).

``python -m vqtex.sim.bench.scenes.codebook_cache [--scenes topspin,town] [--frame 0]
[--sizes 1,2,4,8,16,32,64] [--texel-line 16] [--json]``. Golden only; no RTL runs; no cycles (the bytes and hit rates
are the cache's classification, which the timing does not change).
"""

from __future__ import annotations

import argparse
import json

import numpy as np

__all__ = ["codebook_references", "texel_lines", "codebook_cache", "main"]


def _compressed_reads(ts, requests: np.ndarray):
    """The compressed requests of ``requests`` ((N, 4) texture, level, i, j), in request order: their
    descriptor rows, the codebook entry each reads (``cb_base + index``) and the texel's (x, y) in
    the block."""
    from vqtex.golden.fetch import block_address, lookup_descriptor, read_index

    req = np.asarray(requests, np.int64).reshape(-1, 4)
    d = lookup_descriptor(ts, req[:, 0], req[:, 1])
    comp = d["compressed"].astype(bool)
    dc = d[comp]
    k, x, y = block_address(dc, req[comp, 2], req[comp, 3])
    return dc, dc["cb_base"].astype(np.int64) + read_index(ts, dc, k), x, y


def codebook_references(ts, requests: np.ndarray) -> np.ndarray:
    """The codebook entry each compressed request of ``requests`` ((N, 4) texture, level, i, j)
    reads, in request order (int64 (M,), M the compressed requests): ``cb_base + index``."""
    return _compressed_reads(ts, requests)[1]


def texel_lines(ts, requests: np.ndarray, line: int) -> np.ndarray:
    """The ``line``-byte lines of the codebook memory (one byte array, entries ``entry_bytes``
    apart) each compressed request's texel bytes lie in, in request order, a straddling texel's two
    lines one after the other (int64)."""
    return _lines_of(ts, *_compressed_reads(ts, requests), line)


def _lines_of(ts, dc, entry, x, y, line: int) -> np.ndarray:
    """:func:`texel_lines` of the reads :func:`_compressed_reads` gives."""
    from vqtex.golden.format import COLORS, texel_bytes

    tb = np.array([texel_bytes(c) for c in COLORS], np.int64)[dc["color"].astype(np.int64)]
    t = (np.asarray(y, np.int64) << dc["log2bw"].astype(np.int64)) | np.asarray(x, np.int64)
    first = entry * ts.entry_bytes + dc["texel_off"].astype(np.int64) + tb * t
    a, b = first // line, (first + tb - 1) // line
    two = b != a
    count = 1 + two
    out = np.repeat(a, count)
    out[(np.cumsum(count) - 1)[two]] = b[two]
    return out


def _line_bytes(entry_bytes: int) -> int:
    return max(4, 1 << (int(entry_bytes) - 1).bit_length())


def codebook_cache(scene_name="topspin", frame: int = 0, sizes=(1, 2, 4, 8, 16, 32, 64), ways: int = 4,
                   line: int = 32, texel_line: int = 16) -> dict:
    """Rows of (cache_kb, codebook hit rate, codebook / index+raw bytes per textured pixel) for one
    scene's frame (module docstring). A size too small for ``ways`` entries of the codebook has no
    codebook figures (``None``)."""
    from vqtex.golden.memory.cache import CacheShape, classify
    from vqtex.golden.memory.system import MemoryConfig
    from vqtex.golden.memory.timing import plan
    from vqtex.golden.render.frame import frame_requests
    from vqtex.golden.render.scene import build_texture_set, load_scene

    scene = load_scene(scene_name) if isinstance(scene_name, str) else scene_name     # a name, or a Scene
    scene_name = scene_name if isinstance(scene_name, str) else str(scene.path)
    ts = build_texture_set(scene, [img for img, _ in scene.load_textures()])
    req, sampler = frame_requests(scene, frame, ts, "trilinear")
    pixels = len(sampler.fragments)
    reads = _compressed_reads(ts, req)          # once: the entries and the texel lines both come from it
    entries = reads[1]
    cb_line = _line_bytes(ts.entry_bytes)
    fine = _lines_of(ts, *reads, texel_line)
    rows = []
    for kb in sizes:
        size = kb * 1024
        row = {"cache_kb": kb, "codebook_line": cb_line, "texel_line": texel_line}
        for key, refs, ln in (("codebook", entries, cb_line), ("texel_line", fine, texel_line)):
            if size >= ln * ways and len(refs):
                shape = CacheShape(size, ln, ways)
                cl = classify(refs, refs % shape.sets, shape.sets, ways)
                row[f"{key}_hit_rate"] = float(cl.hit.mean())
                row[f"{key}_bytes_per_pixel"] = cl.misses * ln / pixels
            else:
                row[f"{key}_hit_rate"] = row[f"{key}_bytes_per_pixel"] = None
        shape = CacheShape(size, line, ways)
        p = plan(ts, req, MemoryConfig(index_cache=shape, raw_cache=shape))
        row["index_raw_bytes_per_pixel"] = len(p.cache) * line / pixels
        for key in ("codebook", "texel_line"):
            if row[f"{key}_bytes_per_pixel"] is not None and row["index_raw_bytes_per_pixel"]:
                row[f"{key}_adds"] = row[f"{key}_bytes_per_pixel"] / row["index_raw_bytes_per_pixel"]
        rows.append(row)
    return {"scene": scene_name, "frame": frame, "requests": int(len(req)), "pixels": int(pixels),
            "compressed_requests": int(len(entries)), "entry_bytes": int(ts.entry_bytes),
            "codebook_entries": int(len(ts.codebook)), "codebook_bytes": int(ts.codebook.size),
            "distinct_entries": int(len(np.unique(entries))), "rows": rows}


def _print(r: dict) -> None:
    print(f"{r['scene']} frame {r['frame']}: {r['requests']} requests ({r['compressed_requests']} compressed), "
          f"{r['pixels']} textured pixels; codebook memory {r['codebook_entries']} entries of "
          f"{r['entry_bytes']} bytes = {r['codebook_bytes']} bytes on chip, {r['distinct_entries']} entries "
          f"read by this frame")
    x0 = r["rows"][0]
    print(f"codebook cache lines: entry lines of {x0['codebook_line']} bytes, texel lines of "
          f"{x0['texel_line']} bytes; index and raw caches: 32-byte lines; all 4 ways, LRU")
    print(f"{'cache':>6} {'idx+raw B/pixel':>15} | {'entry hit':>9} {'B/pixel':>8} {'adds':>6} | "
          f"{'texel hit':>9} {'B/pixel':>8} {'adds':>6}")

    def cols(x, key):
        if x[f"{key}_hit_rate"] is None:
            return f"{'-':>9} {'-':>8} {'-':>6}"
        return (f"{100 * x[f'{key}_hit_rate']:>8.2f}% {x[f'{key}_bytes_per_pixel']:>8.3f} "
                f"{100 * x[f'{key}_adds']:>5.0f}%")
    for x in r["rows"]:
        print(f"{x['cache_kb']:>4}KB {x['index_raw_bytes_per_pixel']:>15.3f} | {cols(x, 'codebook')} | "
              f"{cols(x, 'texel_line')}")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", default="topspin,town")
    ap.add_argument("--frame", type=int, default=0)
    ap.add_argument("--sizes", default="1,2,4,8,16,32,64", help="cache sizes in KB, comma-separated")
    ap.add_argument("--texel-line", type=int, default=16, help="bytes per line of the texel-line codebook cache")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    results = [codebook_cache(name, a.frame, tuple(int(s) for s in a.sizes.split(",")), texel_line=a.texel_line)
               for name in a.scenes.split(",")]
    if a.json:
        print(json.dumps(results, indent=1))
        return
    for r in results:
        _print(r)


if __name__ == "__main__":
    main()
