"""The yardstick process of the whole-process encoder benchmark: what a user would write to design
a codebook with scikit-learn instead of ``vqtex encode``. It reads one image file with OpenImageIO
(as ``vqtex encode`` does), cuts it into BxB RGB blocks, fits ``KMeans(k, init="k-means++",
n_init=1)`` (Lloyd, the default tolerance, the default threads), prints the PSNR of the blocks
decoded to their rounded centre, and exits.

It imports numpy, OpenImageIO and scikit-learn only (no vqtex module), and is run as a file:
``python kmeans_process.py IMAGE BLOCK K [SEED] [--no-fit]`` (``encoder.py --processes`` runs it);
``--no-fit`` does everything but the fit and the PSNR (the process's own start, imports and
reading, to subtract from it).
"""
import sys

import numpy as np
import OpenImageIO as oiio
from sklearn.cluster import KMeans


def main(argv) -> int:
    fit = "--no-fit" not in argv
    argv = [a for a in argv if a != "--no-fit"]
    path, block, k = argv[0], int(argv[1]), int(argv[2])
    seed = int(argv[3]) if len(argv) > 3 else 0
    inp = oiio.ImageInput.open(path)
    spec = inp.spec()
    img = np.asarray(inp.read_image(0, 0, 0, 3, "uint8"), np.uint8).reshape(spec.height, spec.width, 3)
    inp.close()
    h, w = img.shape[:2]
    x = (img.reshape(h // block, block, w // block, block, 3).transpose(0, 2, 1, 3, 4)
         .reshape(-1, block * block * 3).astype(np.float64))
    if not fit:
        return 0
    km = KMeans(n_clusters=k, init="k-means++", n_init=1, random_state=seed, algorithm="lloyd").fit(x)
    err = np.clip(np.rint(km.cluster_centers_), 0, 255)[km.labels_] - x
    print(f"kmeans {path} {block}x{block} k={k}: {10 * np.log10(255.0 ** 2 / np.mean(err * err)):.3f} dB, "
          f"{km.n_iter_} iterations")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
