"""Codebook design benchmark: ``golden.codebook`` (TSVQ-initialised GLA) against scikit-learn's
KMeans (k-means++, one init, Lloyd to convergence) on the same vectors, side by side.

Images are scikit-image's bundled photographs (nothing is downloaded): astronaut and
immunohistochemistry (512x512), and 512x512 centre crops of hubble_deep_field and retina.

Cases (targets: PSNR loss against KMeans at most ``max_loss_db`` and a speed-up of at least
``min_speedup``):

1. 2x2 RGB blocks (d = 12), k = 256, astronaut: 0.10 dB, 5x
2. 4x4 RGB blocks (d = 48), k = 1024, astronaut: 0.15 dB, 5x
3. 2x2 RGB blocks, k = 4096 shared by the four images (one training set): 0.15 dB, 10x

PSNR = 10 log10(255^2 / MSE) over every reconstructed pixel component, each block decoded to its
codeword rounded and clipped to uint8.  Both methods run under the same BLAS/OpenMP thread limit
(threadpoolctl; default 1 thread, the reproducible setting on a shared machine; with more
threads sklearn's OpenMP Lloyd loop gains more than our mostly single-threaded numpy pipeline),
and interleaved; the time of a method is the minimum wall time over ``repeats`` runs (same count for
both methods; case 3 runs once by default because KMeans takes minutes there).

Run: ``python -m sim.bench.encoder [--json] [--threads N] [--repeats R] [--cases 1,2,3]``
or ``vqtex bench encode [--json]``.
"""
from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np

__all__ = ["run", "blocks", "psnr", "load_images"]

CASES = {
    1: dict(name="2x2 blocks, k=256, astronaut", block=2, k=256, images=("astronaut",),
            max_loss_db=0.10, min_speedup=5.0, repeats=3),
    2: dict(name="4x4 blocks, k=1024, astronaut", block=4, k=1024, images=("astronaut",),
            max_loss_db=0.15, min_speedup=5.0, repeats=3),
    3: dict(name="2x2 blocks, k=4096 shared by 4 images", block=2, k=4096,
            images=("astronaut", "immunohistochemistry", "hubble_deep_field", "retina"),
            max_loss_db=0.15, min_speedup=10.0, repeats=1),
}


_KM_MAX_ITER = 10000  # KMeans runs until its own (default) tolerance stops it


def _ours_settings() -> dict:
    import inspect

    from vqtex.golden.codebook import gla
    return {n: p.default for n, p in inspect.signature(gla).parameters.items()
            if p.kind is p.KEYWORD_ONLY and n not in ("weights", "init", "seed")}


def blocks(img: np.ndarray, bh: int, bw: int | None = None) -> np.ndarray:
    """(H, W, C) -> (H/bh * W/bw, bh*bw*C) float64, blocks in row-major order, each block's
    texels row-major (H and W must be multiples of the block size)."""
    bw = bh if bw is None else bw
    h, w, c = img.shape
    if h % bh or w % bw:
        raise ValueError(f"image {h}x{w} is not a multiple of the {bh}x{bw} block")
    x = img.reshape(h // bh, bh, w // bw, bw, c).transpose(0, 2, 1, 3, 4)
    return x.reshape(-1, bh * bw * c).astype(np.float64)


def psnr(vectors: np.ndarray, codebook: np.ndarray, labels: np.ndarray) -> float:
    """PSNR in dB of vectors decoded to their codeword, rounded and clipped to uint8."""
    cb8 = np.clip(np.rint(codebook), 0, 255).astype(np.uint8)
    err = cb8[labels].astype(np.float64) - vectors
    mse = float(np.mean(err * err))
    return float("inf") if mse == 0 else float(10 * np.log10(255.0 ** 2 / mse))


def _centre(img: np.ndarray, size: int = 512) -> np.ndarray:
    h, w = img.shape[:2]
    if h < size or w < size:
        raise ValueError("image smaller than the crop")
    y, x = (h - size) // 2, (w - size) // 2
    return np.ascontiguousarray(img[y:y + size, x:x + size, :3])


def load_images(names) -> list[np.ndarray]:
    """512x512x3 uint8 images bundled with scikit-image (centre crops of the larger ones)."""
    import skimage.data
    return [_centre(getattr(skimage.data, n)()) for n in names]


def _time(fn):
    t0, c0 = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - t0, time.process_time() - c0


def _run_case(cid: int, spec: dict, seed: int, repeats: int | None, log) -> dict:
    from sklearn.cluster import KMeans

    from vqtex.golden.codebook import gla

    imgs = load_images(spec["images"])
    x = np.concatenate([blocks(im, spec["block"]) for im in imgs])
    k = spec["k"]
    reps = spec["repeats"] if repeats is None else repeats
    ours_t, km_t = [], []
    for rep in range(reps):
        log(f"  case {cid}: ours   run {rep + 1}/{reps} ({len(x)} vectors, k={k}) ...")
        res, wall, cpu = _time(lambda: gla(x, k, seed=seed))
        ours_t.append((wall, cpu))
        log(f"  case {cid}: ours   {wall:8.3f} s")
        log(f"  case {cid}: KMeans run {rep + 1}/{reps} (the slow one: up to minutes) ...")
        km, wall, cpu = _time(lambda: KMeans(n_clusters=k, init="k-means++", n_init=1,
                                             random_state=seed, algorithm="lloyd",
                                             max_iter=_KM_MAX_ITER).fit(x))
        km_t.append((wall, cpu))
        log(f"  case {cid}: KMeans {wall:8.3f} s")
    ours_wall, ours_cpu = min(ours_t)
    km_wall, km_cpu = min(km_t)
    p_ours = psnr(x, res.codebook, res.indices)
    p_km = psnr(x, km.cluster_centers_, km.labels_)
    loss = p_km - p_ours
    speedup = km_wall / ours_wall
    return {
        "case": cid,
        "name": spec["name"],
        "images": list(spec["images"]),
        "vectors": int(x.shape[0]),
        "distinct_vectors": int(np.unique(x, axis=0).shape[0]),
        "dim": int(x.shape[1]),
        "k": k,
        "repeats": reps,
        "ours": {"time_s": ours_wall, "cpu_s": ours_cpu, "psnr_db": p_ours,
                 "iterations": res.iterations, "converged": bool(res.converged)},
        "kmeans": {"time_s": km_wall, "cpu_s": km_cpu, "psnr_db": p_km,
                   "iterations": int(km.n_iter_), "converged": bool(km.n_iter_ < _KM_MAX_ITER)},
        "psnr_loss_db": loss,
        "speedup": speedup,
        "target": {"max_psnr_loss_db": spec["max_loss_db"], "min_speedup": spec["min_speedup"]},
        "quality_met": bool(loss <= spec["max_loss_db"]),
        "speed_met": bool(speedup >= spec["min_speedup"]),
        "met": bool(loss <= spec["max_loss_db"] and speedup >= spec["min_speedup"]),
    }


def run(json_out: bool = False, *, threads: int | None = 1, repeats: int | None = None,
        cases=(1, 2, 3), seed: int = 0) -> dict:
    """Run the benchmark; print a table (or one JSON object) and return the result dict.

    threads: BLAS/OpenMP thread limit applied to both methods (None: library defaults).
    repeats: runs per method and case (None: 3 for cases 1-2, 1 for case 3); min wall time counts.
    """
    import sklearn
    from threadpoolctl import threadpool_info, threadpool_limits

    def log(msg):
        print(msg, file=sys.stderr if json_out else sys.stdout, flush=True)

    results = []
    with threadpool_limits(limits=threads):
        pools = sorted({f"{p['internal_api']}={p['num_threads']}" for p in threadpool_info()})
        log(f"threads: limit {threads if threads else 'default'} ({', '.join(pools)})")
        for cid in cases:
            results.append(_run_case(cid, CASES[cid], seed, repeats, log))
    out = {
        "benchmark": "encode",
        "threads": threads,
        "thread_pools": pools,
        "numpy": np.__version__,
        "sklearn": sklearn.__version__,
        "seed": seed,
        "ours_settings": _ours_settings(),
        "cases": results,
        "all_met": all(r["met"] for r in results),
    }
    if json_out:
        print(json.dumps(out))
    else:
        _print_table(out)
    return out


def _print_table(out: dict) -> None:
    hdr = (f"{'case':<40} {'N':>7} {'d':>3} {'k':>5} | {'ours s':>7} {'dB':>6} | "
           f"{'KMeans s':>8} {'dB':>6} | {'loss dB':>7} {'speedup':>7} | target")
    print(f"codebook design vs sklearn KMeans (k-means++, lloyd), threads: "
          f"{out['threads'] if out['threads'] else 'library default'} ({', '.join(out['thread_pools'])})")
    print("ours: golden.codebook.gla(" + ", ".join(f"{k}={v}" for k, v in out["ours_settings"].items())
          + "), TSVQ-initialised; KMeans: init='k-means++', n_init=1, algorithm='lloyd', default tol")
    print(hdr)
    print("-" * len(hdr))
    for r in out["cases"]:
        t = r["target"]
        tgt = (f"<= {t['max_psnr_loss_db']:.2f} dB {'ok' if r['quality_met'] else 'MISSED'}, "
               f">= {t['min_speedup']:.0f}x {'ok' if r['speed_met'] else 'MISSED'}")
        print(f"{r['case']}. {r['name']:<37} {r['vectors']:>7} {r['dim']:>3} {r['k']:>5} | "
              f"{r['ours']['time_s']:>7.2f} {r['ours']['psnr_db']:>6.2f} | "
              f"{r['kmeans']['time_s']:>8.2f} {r['kmeans']['psnr_db']:>6.2f} | "
              f"{r['psnr_loss_db']:>+7.3f} {r['speedup']:>6.1f}x | {tgt}")
    print(f"all targets met: {'yes' if out['all_met'] else 'NO'}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--threads", type=int, default=1,
                    help="BLAS/OpenMP threads for both methods (0: library default)")
    ap.add_argument("--repeats", type=int, default=None)
    ap.add_argument("--cases", default="1,2,3")
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args(argv)
    cases = tuple(int(c) for c in a.cases.split(","))
    run(a.json, threads=a.threads or None, repeats=a.repeats, cases=cases, seed=a.seed)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
