"""Peak memory of ``vqtex decode`` on the largest valid level: a 4096x4096 texture of 1x1 blocks.

Contract
--------
``big_set(side, seed)`` builds a valid texture set holding one ``side x side`` rgb texture of 1x1
blocks, 1-bit indices and a codebook of two codewords, no mipmaps: its index map is ``side**2`` random
bits (2 MiB at 4096), so the file is about 2 MB while its picture is 48 MiB of RGB (64 MiB as the
RGBA :func:`golden.fetch.decode` returns). It is the most texels per byte of file the format allows.

``measure(side, seed)`` writes that set to a temporary folder, runs ``python -m vqtex.sim.cli --help``
(the baseline: interpreter, numpy, the command line's imports) and then the command a user would run,
``vqtex decode SET.vqt -o OUT.png``, each in its own process (``load.run_command``), and reports
each process's peak resident set size (``ru_maxrss``, what ``/usr/bin/time -v`` calls maximum resident
set size), the decode's peak above the baseline, and that figure as a ratio to the decoded picture
(``side**2`` times the channels written: 3 for rgb and yuv411, 4 for rgba, 1 for intensity). The figures are measured and printed, never asserted.

Run: ``python -m vqtex.sim.bench.robustness.decode_memory [--side 4096] [--seed 0]``; prints JSON.
docs/stability.md holds the latest figures.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile

import numpy as np

from .load import run_command

__all__ = ["big_set", "measure", "main"]


#: Channels of the image ``vqtex decode`` writes, per colour format.
CHANNELS = {"rgb": 3, "rgba": 4, "intensity": 1, "yuv411": 3}


def big_set(side: int = 4096, seed: int = 0, color: str = "rgb", entry_bytes: int = 0):
    """A valid :class:`~golden.format.TextureSet`: one ``side x side`` texture of ``color`` (rgb, rgba,
    intensity or yuv411), 1x1 blocks, 1-bit indices (seeded random), two codewords (all bytes 0, all
    bytes 255), 32-bit index words. ``entry_bytes`` wider than the codeword (3 bytes for rgb) pads the
    codebook memory with zeros, as a set holding a texture of wider codewords besides has it (48: a
    4x4 rgb codeword); the loader accepts either."""
    from vqtex.golden.format import (COLOR_CODES, DESCRIPTOR_DTYPE, MAX_LEVELS, CodebookInfo, TextureInfo,
                                     TextureSet, entry_layout, log2)
    layout = entry_layout(color, 1, 1)
    n = side * side
    rng = np.random.default_rng(seed)
    words = np.concatenate([rng.integers(0, 1 << 32, -(-n // 32), dtype=np.uint64).astype("<u4"),
                            np.zeros(1, "<u4")])                       # the map, then the guard word
    d = np.zeros((1, MAX_LEVELS), DESCRIPTOR_DTYPE)
    row = d[0, 0]
    row["valid"] = row["compressed"] = 1
    row["log2w"] = row["log2h"] = log2(side)
    row["index_bits"] = 1
    row["color"] = COLOR_CODES[color]
    row["texel_off"], row["u_off"], row["v_off"] = layout.planes[0]
    codebook = np.zeros((2, max(layout.size, entry_bytes)), np.uint8)
    codebook[1, : layout.size] = 255
    ts = TextureSet(word_bits=32, index_words=words, codebook=codebook,
                    raw_words=np.zeros(0, "<u4"), descriptors=d,
                    textures=[TextureInfo("big", side, side, 1, color, (1, 1), 0, 1, False)],
                    codebooks=[CodebookInfo(color, (1, 1), 1, 2, 0)])
    ts.validate()
    ts.check_consistency()
    return ts


def measure(side: int = 4096, seed: int = 0, color: str = "rgb", entry_bytes: int = 0) -> dict:
    """Build the set, run ``vqtex --help`` and ``vqtex decode``; the figures described above."""
    picture = side * side * CHANNELS[color]
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "big.vqt")
        ts = big_set(side, seed, color, entry_bytes)
        ts.save(path)
        base = run_command(["--help"])
        if base["returncode"] != 0:
            raise RuntimeError(f"vqtex --help failed ({base['returncode']}): {base['stderr'].strip()}")
        out = os.path.join(tmp, "big.png")
        r = run_command(["decode", path, "-o", out])
        ok = r["returncode"] == 0
        file_bytes = os.path.getsize(path)
    above = r["peak_mib"] - base["peak_mib"]
    return {"side": side, "seed": seed, "color": color, "entry_bytes": ts.entry_bytes, "file_bytes": file_bytes, "picture_mib": round(picture / 2**20, 1),
            "command": "vqtex decode big.vqt -o big.png",
            "returncode": r["returncode"], "stderr": "" if ok else r["stderr"].strip().splitlines()[-1:],
            "baseline_mib": round(base["peak_mib"], 1), "peak_mib": round(r["peak_mib"], 1),
            "above_baseline_mib": round(above, 1),
            "ratio_to_picture": round(above * 2**20 / picture, 2),
            "bytes_per_texel_above_baseline": round(above * 2**20 / (side * side), 1),
            "wall_s": round(r["seconds"], 2), "cpu_s": round(r["cpu_seconds"], 2)}


def main(argv=None) -> None:
    p = argparse.ArgumentParser(prog="python -m vqtex.sim.bench.robustness.decode_memory",
                                description=__doc__.split("\n")[0])
    p.add_argument("--side", type=int, default=4096, help="texture side, a power of two (default: %(default)s)")
    p.add_argument("--seed", type=int, default=0, help="seed of the random index map (default: %(default)s)")
    p.add_argument("--color", default="rgb", choices=sorted(CHANNELS),
                   help="colour format of the texture (default: %(default)s)")
    p.add_argument("--entry-bytes", type=int, default=0,
                   help="codebook memory width in bytes, at least the codeword's (default: the codeword's)")
    a = p.parse_args(argv)
    print(json.dumps(measure(a.side, a.seed, a.color, a.entry_bytes), indent=1))


if __name__ == "__main__":
    main()
