"""Codebook design benchmark: ``golden.codebook`` (TSVQ-initialised GLA) against scikit-learn's
KMeans (k-means++, one init, Lloyd, its default tolerance) on the same vectors, side by side, at
each library's default thread settings (as a user runs them) and with both held to one thread.

Images are scikit-image's bundled photographs (nothing is downloaded): 512x512 centre crops of
astronaut, immunohistochemistry, hubble_deep_field and retina.

Cases (targets: PSNR loss against KMeans at most ``max_loss_db`` and a speed-up of at least
``min_speedup``, both at default threads):

1. 2x2 RGB blocks (d = 12), k = 256, each photograph on its own: 0.10 dB, 5x
2. 4x4 RGB blocks (d = 48), k = 1024, each photograph on its own: 0.10 dB, 5x
3. 2x2 RGB blocks, k = 4096 shared by the four photographs (one training set): 0.15 dB, 10x

A case with several photographs encodes each on its own; its speed-up is KMeans's total time over
ours, its PSNR loss the worst photograph's (both also per photograph in ``per_image``).

PSNR = 10 log10(255^2 / MSE) over every reconstructed pixel component, each block decoded to its
codeword rounded and clipped to uint8.  Thread settings: "default" leaves both libraries alone
(our encoder's worker threads: ``VQTEX_THREADS`` or the cores; KMeans: its OpenMP threads, BLAS
as configured); "one" holds both to one thread (threadpoolctl for OpenMP and BLAS,
``workers.set_threads(1)`` for ours).  The two methods alternate; the time of a method is the
minimum wall time over ``repeats`` runs (the same count for both; case 3 runs once by default
because KMeans takes minutes there).

Run: ``vqtex bench encode [--json]``.  For whole-process timings, ``python -m
vqtex.sim.bench.encoding.encoder --only gla|kmeans --case 1 --image hubble_deep_field`` runs one method once
(both import the same modules) and prints its PSNR; ``--only load`` does everything but the fit
(the fixed cost to subtract).
"""
from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np

__all__ = ["run", "blocks", "psnr", "load_images", "CASES", "SETTINGS", "fit", "thread_setting"]

PHOTOS = ("astronaut", "immunohistochemistry", "hubble_deep_field", "retina")
CASES = {
    1: dict(name="2x2 blocks, k=256, each photograph", block=2, k=256, images=PHOTOS, separate=True,
            max_loss_db=0.10, min_speedup=5.0, repeats=3),
    2: dict(name="4x4 blocks, k=1024, each photograph", block=4, k=1024, images=PHOTOS, separate=True,
            max_loss_db=0.10, min_speedup=5.0, repeats=3),
    3: dict(name="2x2 blocks, k=4096 shared by 4 photographs", block=2, k=4096, images=PHOTOS,
            separate=False, max_loss_db=0.15, min_speedup=10.0, repeats=1),
}
#: Thread settings, in the order they run: the libraries' defaults, then one thread each.
SETTINGS = ("default", "one")


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


def load_images(names, size: int = 512) -> list[np.ndarray]:
    """size x size x 3 uint8 images bundled with scikit-image (centre crops)."""
    import skimage.data
    return [_centre(getattr(skimage.data, n)(), size) for n in names]


def fit(method: str, x: np.ndarray, k: int, seed: int = 0):
    """Design a k-codeword codebook for ``x`` with ``method`` ("gla" or "kmeans"); returns
    (codebook, labels, iterations, converged)."""
    if method == "gla":
        from vqtex.golden.codebook import gla
        r = gla(x, k, seed=seed)
        return r.codebook, r.indices, r.iterations, bool(r.converged)
    from sklearn.cluster import KMeans
    km = KMeans(n_clusters=k, init="k-means++", n_init=1, random_state=seed, algorithm="lloyd").fit(x)
    return km.cluster_centers_, km.labels_, int(km.n_iter_), bool(km.n_iter_ < km.max_iter)


def thread_setting(setting: str):
    """The thread setting as a context: "default" changes nothing, "one" holds both libraries to
    one thread."""
    from contextlib import contextmanager

    from threadpoolctl import threadpool_limits

    from vqtex.golden.codebook import workers

    @contextmanager
    def ctx():
        if setting == "default":
            yield
            return
        with workers.using_threads(1), threadpool_limits(limits=1):
            yield
    return ctx()


def _pools() -> list[str]:
    from threadpoolctl import threadpool_info

    from vqtex.golden.codebook import workers
    return sorted({f"{p['internal_api']}={p['num_threads']}" for p in threadpool_info()}
                  | {f"vqtex={workers.threads()}"})


def _timed(fn):
    t0, c0 = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - t0, time.process_time() - c0


def _run_set(x, k, seed, reps, log, label):
    """Both methods on one training set, alternating; min wall time of ``reps`` runs each."""
    best = {}
    out = {}
    for rep in range(reps):
        for method in ("gla", "kmeans"):
            log(f"  {label}: {method:6s} run {rep + 1}/{reps} ({len(x)} vectors, k={k}) ...")
            res, wall, cpu = _timed(lambda: fit(method, x, k, seed))
            if method not in best or wall < best[method][0]:
                best[method] = (wall, cpu)
            out[method] = res
    row = {}
    for method, name in (("gla", "ours"), ("kmeans", "kmeans")):
        cb, lab, it, conv = out[method]
        row[name] = {"time_s": best[method][0], "cpu_s": best[method][1], "psnr_db": psnr(x, cb, lab),
                     "iterations": it, "converged": conv}
    return row


def _run_case(cid: int, spec: dict, seed: int, repeats: int | None, setting: str, log,
              images=None, size: int = 512) -> dict:
    names = tuple(images or spec["images"])
    imgs = load_images(names, size)
    k = spec["k"]
    reps = spec["repeats"] if repeats is None else repeats
    if spec["separate"]:
        sets = [(n, blocks(im, spec["block"])) for n, im in zip(names, imgs)]
    else:
        sets = [("+".join(names), np.concatenate([blocks(im, spec["block"]) for im in imgs]))]
    per = []
    with thread_setting(setting):
        for name, x in sets:
            r = _run_set(x, k, seed, reps, log, f"case {cid} {setting} {name}")
            r.update(image=name, vectors=int(x.shape[0]),
                     psnr_loss_db=r["kmeans"]["psnr_db"] - r["ours"]["psnr_db"],
                     speedup=r["kmeans"]["time_s"] / r["ours"]["time_s"])
            log(f"  case {cid} {setting} {name}: ours {r['ours']['time_s']:.3f} s "
                f"{r['ours']['psnr_db']:.3f} dB, KMeans {r['kmeans']['time_s']:.3f} s "
                f"{r['kmeans']['psnr_db']:.3f} dB: {r['speedup']:.1f}x")
            per.append(r)
    ours_t = sum(r["ours"]["time_s"] for r in per)
    km_t = sum(r["kmeans"]["time_s"] for r in per)
    loss = max(r["psnr_loss_db"] for r in per)
    speedup = km_t / ours_t
    return {
        "case": cid, "name": spec["name"], "threads": setting, "images": list(names),
        "dim": int(sets[0][1].shape[1]), "k": k, "repeats": reps,
        "per_image": per,
        "ours_time_s": ours_t, "kmeans_time_s": km_t,
        "psnr_loss_db": loss, "speedup": speedup,
        "target": {"max_psnr_loss_db": spec["max_loss_db"], "min_speedup": spec["min_speedup"],
                   "at": "default"},
        "quality_met": bool(loss <= spec["max_loss_db"]),
        "speed_met": bool(speedup >= spec["min_speedup"]),
        "met": bool(loss <= spec["max_loss_db"] and speedup >= spec["min_speedup"]),
    }


def run(json_out: bool = False, *, settings=SETTINGS, repeats: int | None = None,
        cases=(1, 2, 3), seed: int = 0, images=None, size: int = 512) -> dict:
    """Run the benchmark; print a table (or one JSON object) and return the result dict.

    settings: thread settings to run ("default", "one"). repeats: runs per method and training
    set (None: the case's). images, size: other photographs or a smaller crop (tests).
    """
    import sklearn

    def log(msg):
        print(msg, file=sys.stderr if json_out else sys.stdout, flush=True)

    results = []
    pools = {}
    for setting in settings:
        with thread_setting(setting):
            pools[setting] = _pools()
        log(f"threads {setting}: {', '.join(pools[setting])}")
        for cid in cases:
            results.append(_run_case(cid, CASES[cid], seed, repeats, setting, log, images, size))
    targets = [r for r in results if r["threads"] == "default"]
    out = {
        "benchmark": "encode",
        "settings": list(settings),
        "thread_pools": pools,
        "numpy": np.__version__,
        "sklearn": sklearn.__version__,
        "seed": seed,
        "ours_settings": _ours_settings(),
        "cases": results,
        "all_met": bool(targets) and all(r["met"] for r in targets),
    }
    if json_out:
        print(json.dumps(out))
    else:
        _print_table(out)
    return out


def _print_table(out: dict) -> None:
    hdr = (f"{'case':<44} {'threads':<8} {'k':>5} | {'ours s':>7} | {'KMeans s':>8} | "
           f"{'loss dB':>7} {'speedup':>7} | target (default threads)")
    print("codebook design vs sklearn KMeans (k-means++, n_init=1, lloyd, default tol)")
    for s, p in out["thread_pools"].items():
        print(f"threads {s}: {', '.join(p)}")
    print("ours: golden.codebook.gla(" + ", ".join(f"{k}={v}" for k, v in out["ours_settings"].items())
          + "), TSVQ-initialised")
    print(hdr)
    print("-" * len(hdr))
    for r in out["cases"]:
        t = r["target"]
        tgt = (f"<= {t['max_psnr_loss_db']:.2f} dB {'ok' if r['quality_met'] else 'MISSED'}, "
               f">= {t['min_speedup']:.0f}x {'ok' if r['speed_met'] else 'MISSED'}"
               if r["threads"] == "default" else "")
        print(f"{r['case']}. {r['name']:<41} {r['threads']:<8} {r['k']:>5} | "
              f"{r['ours_time_s']:>7.2f} | {r['kmeans_time_s']:>8.2f} | "
              f"{r['psnr_loss_db']:>+7.3f} {r['speedup']:>6.1f}x | {tgt}")
        for p in r["per_image"]:
            print(f"     {p['image']:<40} {'':<8} {'':>5} | {p['ours']['time_s']:>7.2f} | "
                  f"{p['kmeans']['time_s']:>8.2f} | {p['psnr_loss_db']:>+7.3f} {p['speedup']:>6.1f}x | "
                  f"{p['ours']['psnr_db']:.2f} vs {p['kmeans']['psnr_db']:.2f} dB")
    print(f"all targets met (default threads): {'yes' if out['all_met'] else 'NO'}")


def _only(method: str, case: int, image: str, seed: int, size: int = 512) -> None:
    """One method once on one photograph of a case (whole-process timing)."""
    import sklearn.cluster  # noqa: F401  (both methods' processes import the same modules)

    import vqtex.golden.codebook  # noqa: F401

    spec = CASES[case]
    x = blocks(load_images([image], size)[0], spec["block"])
    if method == "load":  # the fixed cost of the other two: imports and the image's vectors
        print(f"load case {case} {image}: {x.shape[0]} vectors")
        return
    cb, lab, it, _ = fit(method, x, spec["k"], seed)
    print(f"{method} case {case} {image}: {psnr(x, cb, lab):.3f} dB, {it} iterations")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--settings", default="default,one", help="thread settings (default,one)")
    ap.add_argument("--repeats", type=int, default=None, help="runs per method (default: the case's)")
    ap.add_argument("--cases", default="1,2,3", help="cases to run (default 1,2,3)")
    ap.add_argument("--seed", type=int, default=0, help="seed of both methods (default 0)")
    ap.add_argument("--images", default=None, help="comma-separated photographs (default: the four)")
    ap.add_argument("--only", choices=("gla", "kmeans", "load"),
                    help="run one method once (whole-process timing); load: only the imports and the vectors")
    ap.add_argument("--case", type=int, default=1, help="with --only: the case (default 1)")
    ap.add_argument("--image", default="hubble_deep_field", help="with --only: the photograph")
    ap.add_argument("--size", type=int, default=512, help="with --only: the crop's side (default 512)")
    a = ap.parse_args(argv)
    if a.only:
        _only(a.only, a.case, a.image, a.seed, a.size)
        return 0
    cases = tuple(int(c) for c in a.cases.split(","))
    run(a.json, settings=tuple(a.settings.split(",")), repeats=a.repeats, cases=cases, seed=a.seed,
        images=tuple(a.images.split(",")) if a.images else None)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
