"""How encoding grows with the texture: time and peak memory of ``vqtex encode`` at several sizes.

Contract
--------
``measure(sizes) -> dict`` encodes one square RGB texture per size (``texture``: the bundled
astronaut tiled to n x n, every texel moved by a little seeded noise so no two tiles are alike),
each in its own process, as a user would: ``python -m vqtex.sim.cli encode IMAGE --block WxH
-k K --color C --encoder-seed S -o OUT.vqt``.  Per size it reports the blocks, the process's wall
and CPU (user + system) seconds and peak resident memory (``ru_maxrss``, what ``/usr/bin/time
-v`` calls maximum resident set size), and per texel: CPU nanoseconds and bytes of peak memory
beyond the ``base_mib`` of a process that encodes a 64x64 texture (interpreter, numpy, the
encoder's fixed costs).  ``growth`` gives, between consecutive sizes, the exponent p of
figure ~ texels^p through the two points (1 = linear), for CPU time and peak memory, as
measured and beyond the base process (None where a figure is not above the base).  The figures are measured and
printed, never asserted (they depend on the machine and its load).

Run: ``python -m vqtex.sim.bench.encoding.scale [--sizes 1024,2048,4096] [--block 4x4] [-k 256]
[--color rgb] [--seed 0]``; prints JSON.  docs/stability.md holds the latest figures.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import tempfile

import numpy as np

from vqtex.golden.render.imageio import read_image, write_image
from vqtex.golden.render.scene import DATA_DIR
from ..robustness.load import run_command

__all__ = ["texture", "encode_once", "measure", "main"]


def texture(n: int, seed: int = 0) -> np.ndarray:
    """(n, n, 3) uint8: the bundled astronaut (512x512) tiled over n x n, each texel moved by
    seeded noise in [-6, 6] (clipped to 0..255)."""
    src = read_image(os.path.join(DATA_DIR, "astronaut.png"))[..., :3]
    reps = (-(-n // src.shape[0]), -(-n // src.shape[1]), 1)
    img = np.tile(src, reps)[:n, :n].astype(np.int16)
    img += np.random.default_rng(seed).integers(-6, 7, img.shape, dtype=np.int16)
    return np.clip(img, 0, 255).astype(np.uint8)


def encode_once(image_path: str, out_path: str, *, block: str = "4x4", k: int = 256,
                color: str = "rgb", seed: int = 0) -> dict:
    """One ``vqtex encode`` in its own process: wall, CPU seconds and peak MiB."""
    r = run_command(["encode", image_path, "--block", block, "-k", str(k), "--color", color,
                     "--encoder-seed", str(seed), "-o", out_path])
    if r["returncode"] != 0:
        raise RuntimeError(f"encode failed ({r['returncode']}): {r['stderr'].strip()}")
    return {"wall_s": round(r["seconds"], 2), "cpu_s": round(r["cpu_seconds"], 2),
            "peak_mib": round(r["peak_mib"], 1)}


def measure(sizes=(1024, 2048, 4096), *, block: str = "4x4", k: int = 256, color: str = "rgb",
            seed: int = 0) -> dict:
    """Encode an n x n texture for every n in ``sizes``; the figures described above."""
    bw, bh = (int(v) for v in block.lower().split("x"))
    with tempfile.TemporaryDirectory() as tmp:
        def run(n):
            img = os.path.join(tmp, f"tex{n}.png")
            write_image(img, texture(n, seed))
            r = encode_once(img, os.path.join(tmp, f"tex{n}.vqt"), block=block, k=k, color=color,
                            seed=seed)
            os.remove(img)
            return r

        base = run(64)
        rows = []
        for n in sizes:
            r = run(n)
            texels = n * n
            rows.append({"size": n, "texels": texels, "blocks": (n // bh) * (n // bw), **r,
                         "cpu_ns_per_texel": round(r["cpu_s"] / texels * 1e9, 1),
                         "cpu_ns_per_texel_beyond_base": round(
                             (r["cpu_s"] - base["cpu_s"]) / texels * 1e9, 1),
                         "bytes_per_texel_beyond_base": round(
                             (r["peak_mib"] - base["peak_mib"]) * 2 ** 20 / texels, 1)})
    def exponent(a, b, key, minus=0.0):
        lo, hi = a[key] - minus, b[key] - minus
        if lo <= 0 or hi <= 0:
            return None  # within the base process's figure: no growth to speak of
        return round(math.log(hi / lo) / math.log(b["texels"] / a["texels"]), 2)

    growth = [{"from": a["size"], "to": b["size"], "cpu_exponent": exponent(a, b, "cpu_s"),
               "cpu_beyond_base_exponent": exponent(a, b, "cpu_s", base["cpu_s"]),
               "peak_exponent": exponent(a, b, "peak_mib"),
               "peak_beyond_base_exponent": exponent(a, b, "peak_mib", base["peak_mib"])}
              for a, b in zip(rows, rows[1:])]
    return {"settings": {"block": block, "k": k, "color": color, "seed": seed,
                         "texture": "astronaut tiled, noise [-6, 6]"},
            "base_mib": base["peak_mib"], "base_cpu_s": base["cpu_s"], "sizes": rows,
            "growth": growth}


def main(argv=None) -> None:
    p = argparse.ArgumentParser(prog="python -m vqtex.sim.bench.encoding.scale", description=__doc__.split("\n")[0])
    p.add_argument("--sizes", default="1024,2048,4096",
                   help="texture sides, comma-separated (default: %(default)s)")
    p.add_argument("--block", default="4x4", help="block WxH (default: %(default)s)")
    p.add_argument("-k", type=int, default=256, help="codebook size (default: %(default)s)")
    p.add_argument("--color", default="rgb", help="colour mode (default: %(default)s)")
    p.add_argument("--seed", type=int, default=0, help="texture noise and encoder seed (default: %(default)s)")
    a = p.parse_args(argv)
    sizes = [int(s) for s in a.sizes.split(",") if s.strip()]
    print(json.dumps(measure(sizes, block=a.block, k=a.k, color=a.color, seed=a.seed), indent=1))


if __name__ == "__main__":
    main()
