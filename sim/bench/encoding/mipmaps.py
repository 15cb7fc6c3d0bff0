"""Extended codewords: the paper's averaged sub-levels against joint training on all sub-levels.

For each texture, encode with ``mip_training="average"`` (the paper: codebook trained on level 0 of
each level group, sub-levels 1 and 2 are rounded means of the codeword) and ``"joint"`` (trained on
levels 0, 1, 2 of the original pyramid at once), same seed and codebook, and report the PSNR of
levels 0, 1 and 2 against the original box-filtered pyramid.
"""

from __future__ import annotations

import json
import time

import numpy as np

from vqtex.golden.encode import encode, reference_pyramid
from vqtex.golden.fetch import decode

__all__ = ["run"]


def _psnr(a, b):
    mse = np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2)
    return float(10 * np.log10(255.0 ** 2 / max(mse, 1e-12)))


def _textures():
    from vqtex.golden.render.imageio import read_image
    from vqtex.golden.render.scene import DATA_DIR as data
    out = []
    for p in sorted(data.glob("*.png")):
        img = read_image(p)
        if img.shape[0] >= 128 and img.shape[1] >= 128 and img.shape[2] == 3:
            out.append((p.stem, img[..., :3]))
    if not out:
        from vqtex.golden.render.textures import generate
        out = [(n, generate(n, (256, 256), seed=1)[..., :3]) for n in ("wood", "marble")]
    return out[:4]


def run(json_out: bool = False, codebook_size: int = 256, block=(4, 4), seed: int = 0) -> dict:
    rows = []
    for name, img in _textures():
        ref = reference_pyramid(img, "rgb", True)
        row = {"texture": name, "size": f"{img.shape[1]}x{img.shape[0]}"}
        for mode in ("average", "joint"):
            t0 = time.perf_counter()
            ts = encode([img], block=block, codebook_size=codebook_size, mipmaps=True,
                        mip_training=mode, seed=seed)
            row[f"{mode}_seconds"] = round(time.perf_counter() - t0, 3)
            row[mode] = [round(_psnr(decode(ts, 0, L)[..., :3], ref[L][..., :3]), 3) for L in range(3)]
        rows.append(row)
    result = {"codebook_size": codebook_size, "block": f"{block[0]}x{block[1]}", "psnr_db_levels_0_1_2": rows}
    if json_out:
        print(json.dumps(result, sort_keys=True))
    else:
        print(f"mip training, {block[0]}x{block[1]} blocks, K={codebook_size}: PSNR (dB) of levels 0, 1, 2")
        print(f"{'texture':<16} {'average (paper)':>26} {'joint':>26}")
        for r in rows:
            fmt = lambda v: " ".join(f"{x:7.2f}" for x in v)
            print(f"{r['texture'][:16]:<16} {fmt(r['average']):>26} {fmt(r['joint']):>26}")
    return result


if __name__ == "__main__":
    run()
