"""Encoders: time against error.  ``vqtex bench tradeoff [--json] [--plot DIR] [--quick]``.

Every codebook designer the project has (``gla``: the TSVQ-initialised generalized Lloyd
algorithm, the default; ``tsvq``: the paper's tree-structured VQ with tree-search indices) and
two references run on the same images, across block sizes, codebook sizes and colour formats:

* ``kmeans``: scikit-learn's ``KMeans(k, init="k-means++", n_init=1)`` (Lloyd, its default
  tolerance and iteration cap), as a user runs it;
* ``minibatch``: scikit-learn's ``MiniBatchKMeans(k)`` with its defaults (batches of 1024,
  ``n_init="auto"``: 3 k-means++ starts).

faiss-cpu's k-means was tried and left out: on this project's vectors (d = 12..48, 16K-64K of
them) it was no faster than KMeans and 1.5-2.3 dB worse (docs/benchmarks.md).

Every method yields the same thing, a ``.vqt`` texture set (golden.format) a texel-fetch unit can
read: the references' centres are rounded to the stored bytes and every block's index is the exact
nearest stored codeword (``golden.codebook.nearest``), exactly what ``gla`` stores; their texture set
is the ``tsvq`` one with the codebook and index map replaced.  So every method is measured the same
way, through ``golden.fetch.decode``.

One row per (method, image, block, codebook size, colour); the fields shared with the codec rows
(``vqtex.sim.bench.codecs``):

* ``method``, ``config`` (``"2x2 k=256 rgb"``), ``image``;
* ``bits_per_texel``: as the paper counts a texture's size: the index map (``nblocks x b`` bits,
  b = ceil(log2 k)) plus the whole codebook (``k x entry bytes x 8``, entry = 3 bytes per texel for
  rgb, 6 bytes per 2x2 for yuv411), over the texels (``TextureSet.rates``: stored bits / texels);
* ``psnr_db``: PSNR of the decoded texture's R, G, B against the original image
  (10 log10(255^2 / MSE)); yuv411 includes its colour subsampling;
* ``encode_s``: wall seconds from the image in memory to the texture set (the encoder's whole
  path: block vectors, codebook design, final indices, packing); ``decode_s``: wall seconds of
  decoding the whole texture to RGBA (``golden.fetch.decode``);

and the fields of this bench:

* ``block`` ("2x2"), ``codebook_size``, ``color``, ``texels``, ``index_bits``;
* ``encode_cpu_s``: the process's CPU seconds (user + system, all threads) during the encode;
* ``frame_psnr_db``, ``frame_mse``: the error of a rendered frame: a 256x256 frame of a wall and
  a floor in perspective, both textured with the image (bilinear, one level), rendered with the
  decoded texture against the same frame with the original (``golden.render.frame_mse``: the
  paper's frame MSE over R, G, B);
* ``threads``: the thread count every library was held to (``None``: the libraries' defaults).

The grid is a list of independent jobs (:func:`job_list`, :func:`run_job`) run by
:func:`vqtex.sim.bench.sweep.run_jobs`: on a dask LocalCluster by default, an existing cluster
(``--scheduler ADDRESS``) or this process (``--scheduler serial``); the rows are the same either
way, the times are each job's own.  Each job holds every library to ``threads`` threads (default
1: jobs that share the machine's cores time one thread each; ``--threads 0`` leaves the
libraries' defaults, meaningful with ``--scheduler serial``).  The comparison with KMeans at each
library's default threads is ``vqtex bench encode``.
"""
from __future__ import annotations

import json
import math
import os
import sys
import time
from contextlib import contextmanager
from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np

__all__ = ["METHODS", "REFERENCES", "BLOCKS", "SIZES", "COLORS", "IMAGES", "QUICK", "FULL",
           "FIELDS", "Job", "job_list", "run_job", "load_image", "frame_error", "pareto", "run",
           "table", "save_plots"]

#: The project's encoders, then the references.
METHODS = ("gla", "tsvq")
REFERENCES = ("kmeans", "minibatch")
BLOCKS = ((2, 2), (4, 4), (4, 2))
SIZES = (16, 64, 256, 1024, 4096)
COLORS = ("rgb", "yuv411")

#: Images by name: (kind, source, size).  "photo": scikit-image's CC0/public-domain photographs,
#: centre-cropped (the ``bench`` extra); "generated": golden.render.textures (the scenes'
#: procedural textures); "bundled": the PNGs of golden/data (LICENSE-textures.md).
IMAGES = {
    "astronaut": ("photo", "astronaut", 512),
    "hubble_deep_field": ("photo", "hubble_deep_field", 512),
    "immunohistochemistry": ("photo", "immunohistochemistry", 512),
    "wood": ("generated", "wood", 256),
    "marble": ("generated", "marble", 256),
    "lawn": ("bundled", "lawn.png", 128),
    "brick_red": ("bundled", "brick_red.png", 128),
    "marble64": ("generated", "marble", 64),
    "marble32": ("generated", "marble", 32),
}

#: The grids: images, blocks, codebook sizes, colours, methods.
FULL = dict(images=("astronaut", "hubble_deep_field", "wood", "marble", "lawn"), blocks=BLOCKS,
            sizes=SIZES, colors=COLORS, methods=METHODS + REFERENCES)
QUICK = dict(images=("marble64",), blocks=((2, 2), (4, 4)), sizes=(16, 64), colors=COLORS,
             methods=METHODS + REFERENCES)
#: A codebook needs at least this many blocks per codeword to be worth designing.
MIN_BLOCKS_PER_CODEWORD = 4

#: Every field a row holds (the shared schema first).
FIELDS = ("method", "config", "image", "bits_per_texel", "psnr_db", "encode_s", "decode_s",
          "block", "codebook_size", "color", "texels", "index_bits", "encode_cpu_s",
          "frame_psnr_db", "frame_mse", "threads")

FRAME_SIZE = 256
_SCENE = """
[scene]
name = "tradeoff"
size = [{fs}, {fs}]
background = [24, 26, 40]
[camera]
position = [0.0, 0.9, 2.6]
target = [0.0, 0.45, 0.0]
fov = 50
[[texture]]
name = "image"
generator = "checker"
size = [{w}, {h}]
address = "wrap"
[[mesh]]
name = "wall"
shape = "quad"
texture = "image"
size = [1.6, 1.2]
translate = [0.0, 0.65, -0.4]
rotate = [0, 30, 0]
[[mesh]]
name = "floor"
shape = "plane"
texture = "image"
size = [6.0, 6.0]
tiling = [3.0, 3.0]
"""


@dataclass(frozen=True)
class Job:
    """One point of the grid (picklable: it travels to dask workers)."""

    method: str
    image: str
    block: tuple
    codebook_size: int
    color: str
    seed: int = 0
    threads: int | None = 1

    @property
    def config(self) -> str:
        return f"{self.block[0]}x{self.block[1]} k={self.codebook_size} {self.color}"


@lru_cache(maxsize=None)
def load_image(name: str) -> np.ndarray:
    """The (H, W, 3) uint8 image of :data:`IMAGES` ``name`` (cached per process)."""
    kind, src, size = IMAGES[name]
    if kind == "photo":
        import skimage.data
        img = getattr(skimage.data, src)()
        h, w = img.shape[:2]
        y, x = (h - size) // 2, (w - size) // 2
        img = img[y:y + size, x:x + size, :3]
    elif kind == "generated":
        from vqtex.golden.render.textures import generate
        img = generate(src, (size, size), seed=7)[..., :3]
    else:
        from vqtex.golden.render.imageio import read_image
        from vqtex.golden.render.scene import DATA_DIR
        img = read_image(DATA_DIR / src)
        img = img[..., :3] if img.ndim == 3 else np.repeat(img[..., None], 3, axis=2)
    img = np.ascontiguousarray(img, dtype=np.uint8)
    img.setflags(write=False)
    return img


def job_list(grid: dict, seed: int = 0, threads: int | None = 1) -> list[Job]:
    """The grid's jobs, method-major inside each point; codebook sizes above
    blocks / :data:`MIN_BLOCKS_PER_CODEWORD` are left out."""
    jobs = []
    for image in grid["images"]:
        size = IMAGES[image][2]
        for block in grid["blocks"]:
            nblocks = size * size // (block[0] * block[1])
            for k in grid["sizes"]:
                if k * MIN_BLOCKS_PER_CODEWORD > nblocks:
                    continue
                for color in grid["colors"]:
                    for method in grid["methods"]:
                        jobs.append(Job(method, image, tuple(block), int(k), color, seed, threads))
    return jobs


# ------------------------------------------------------------------------------------------- frame
@lru_cache(maxsize=4)
def _scene(w: int, h: int):
    from vqtex.golden.render.scene import parse_scene
    return parse_scene(_SCENE.format(fs=FRAME_SIZE, w=w, h=h), "<tradeoff scene>")


def _render(img_rgba: np.ndarray) -> np.ndarray:
    from vqtex.golden.render.frame import render_frame
    from vqtex.golden.render.pyramid import ReferenceSource
    h, w = img_rgba.shape[:2]
    return render_frame(_scene(w, h), 0, ReferenceSource([img_rgba], levels=[1]), "trilinear")


@lru_cache(maxsize=8)
def _reference_frame(image: str) -> np.ndarray:
    return _render(load_image(image))


def frame_error(image: str, decoded_rgba: np.ndarray) -> tuple[float, float]:
    """(frame MSE, frame PSNR in dB) of the test frame rendered with ``decoded_rgba`` against the
    frame rendered with the original image ``image``."""
    from vqtex.golden.render.metrics import frame_mse
    mse = frame_mse(_render(decoded_rgba), _reference_frame(image))
    return mse, (math.inf if mse == 0 else 10 * math.log10(255.0 ** 2 / mse))


# ------------------------------------------------------------------------------------------ encode
def _clock():
    return time.perf_counter(), time.process_time()


def _reference_set(job: Job, img: np.ndarray, template):
    """Design with a reference and store it like the project's encoder (rounded codewords, exact
    nearest stored codeword).  Returns the texture set."""
    from vqtex.golden import codebook as vq
    from vqtex.golden.encode import block_vectors
    from vqtex.golden.format import pack_indices
    from vqtex.golden.mipmap import to_rgba

    rgba = to_rgba(img)
    v = block_vectors(rgba, job.color, job.block[0], job.block[1]).astype(np.float32)
    if job.method == "kmeans":
        from sklearn.cluster import KMeans
        est = KMeans(n_clusters=job.codebook_size, init="k-means++", n_init=1, random_state=job.seed)
    else:
        from sklearn.cluster import MiniBatchKMeans
        est = MiniBatchKMeans(n_clusters=job.codebook_size, random_state=job.seed)
    est.fit(v)
    code = np.clip(np.rint(est.cluster_centers_), 0, 255).astype(np.uint8)
    idx, _ = vq.nearest(v, code.astype(np.float32))
    info = template.textures[0]
    words = pack_indices(idx, info.index_bits, template.word_bits)
    words = np.concatenate([words, np.zeros(1, words.dtype)]).astype(template.index_words.dtype)
    if template.codebook.shape != code.shape or template.index_words.shape != words.shape:
        raise AssertionError("reference texture set does not match the encoder's layout")
    return replace(template, codebook=code, index_words=words)


@contextmanager
def _limits(threads):
    """Hold every library to ``threads`` threads (None: leave the defaults); restored after."""
    from vqtex.golden.codebook import workers
    if threads is None:
        with workers.using_threads(None):
            yield
        return
    from threadpoolctl import threadpool_limits
    with workers.using_threads(int(threads)), threadpool_limits(limits=int(threads)):
        yield


def run_job(job: Job) -> dict:
    """Encode, decode and measure one point; returns its row (:data:`FIELDS`)."""
    from vqtex.golden.encode import encode
    from vqtex.golden.fetch import decode

    img = load_image(job.image)
    if job.method in REFERENCES:
        import sklearn.cluster  # noqa: F401  (imported before the clock starts)
    kw = dict(block=job.block, codebook_size=job.codebook_size, color=job.color, seed=job.seed)
    with _limits(job.threads):
        if job.method in METHODS:
            w0, c0 = _clock()
            ts = encode([img], encoder=job.method, **kw)
            w1, c1 = _clock()
        elif job.method in REFERENCES:
            template = encode([img], encoder="tsvq", **kw)  # the layout (not timed)
            w0, c0 = _clock()
            ts = _reference_set(job, img, template)
            w1, c1 = _clock()
        else:
            raise ValueError(f"unknown method {job.method!r}")
        t0 = time.perf_counter()
        dec = decode(ts, 0, 0)
        t1 = time.perf_counter()
    d = dec[..., :3].astype(np.int64) - img
    mse = float(np.mean(d * d))
    fmse, fpsnr = frame_error(job.image, dec)
    texels = int(img.shape[0] * img.shape[1])
    return {
        "method": job.method, "config": job.config, "image": job.image,
        "bits_per_texel": float(ts.rates(0)["stored_bits"]) / texels,
        "psnr_db": math.inf if mse == 0 else 10 * math.log10(255.0 ** 2 / mse),
        "encode_s": w1 - w0, "decode_s": t1 - t0,
        "block": f"{job.block[0]}x{job.block[1]}", "codebook_size": job.codebook_size,
        "color": job.color, "texels": texels, "index_bits": int(ts.textures[0].index_bits),
        "encode_cpu_s": c1 - c0, "frame_psnr_db": fpsnr, "frame_mse": fmse, "threads": job.threads,
    }


# ------------------------------------------------------------------------------------------ report
def pareto(rows, x: str, y: str = "psnr_db") -> list[dict]:
    """The rows no other row beats on both ``x`` (lower is better) and ``y`` (higher), by x."""
    front, best = [], -math.inf
    for r in sorted(rows, key=lambda r: (r[x], -r[y])):
        if r[y] > best:
            front.append(r)
            best = r[y]
    return front


def _json_safe(v):
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v


def table(rows) -> str:
    """The rows as a fixed-width text table."""
    hdr = (f"{'image':<20} {'config':<28} {'method':<10} {'bits/tx':>7} {'PSNR dB':>7} "
           f"{'frame dB':>8} {'enc s':>7} {'cpu s':>7} {'dec ms':>7}")
    out = [hdr, "-" * len(hdr)]
    for r in rows:
        cpu = r.get("encode_cpu_s")
        dec = r.get("decode_s")
        fr = r.get("frame_psnr_db")
        p = r["psnr_db"]
        out.append(f"{r['image']:<20} {r['config']:<28.28} {r['method']:<10} {r['bits_per_texel']:>7.3f} "
                   f"{'exact' if p is None or not math.isfinite(p) else f'{p:.2f}':>7} "
                   f"{'' if fr is None else f'{fr:.2f}':>8} "
                   f"{r['encode_s']:>7.3f} {'' if cpu is None else f'{cpu:.3f}':>7} "
                   f"{'' if dec is None else f'{1e3 * dec:.2f}':>7}")
    return "\n".join(out)


_STYLE = {"gla": ("#1f77b4", "o"), "tsvq": ("#2ca02c", "s"), "kmeans": ("#d62728", "^"),
          "minibatch": ("#ff7f0e", "v"), "bc1": ("#9467bd", "D"), "astc": ("#8c564b", "P"),
          "jpeg2000": ("#e377c2", "X"), "wavelet": ("#17becf", "*")}


def save_plots(rows, folder: str, time_field: str = "encode_s") -> list[str]:
    """Two PNGs in ``folder``: encode time against PSNR and bits per texel against PSNR, one panel
    per image, every method's points and its Pareto front.  ``time_field``: ``encode_s`` (wall
    seconds) or ``encode_cpu_s`` (CPU seconds; rows without it are left out of that plot).
    Returns the paths."""
    from vqtex.sim.reports.plotting import require
    plt = require()
    os.makedirs(folder, exist_ok=True)
    images = list(dict.fromkeys(r["image"] for r in rows))
    methods = list(dict.fromkeys(r["method"] for r in rows))
    paths = []
    tlabel = "encode time (CPU s, log)" if time_field == "encode_cpu_s" else "encode time (s, log)"
    for x, label, name, logx in ((time_field, tlabel, "tradeoff_time.png", True),
                                 ("bits_per_texel", "bits per texel (indices + codebook)",
                                  "tradeoff_bits.png", False)):
        cols = min(3, len(images))
        nr = -(-len(images) // cols)
        fig, axes = plt.subplots(nr, cols, figsize=(5.2 * cols, 4.0 * nr), dpi=100, squeeze=False)
        for ax, image in zip(axes.flat, images):
            for m in methods:
                pts = [r for r in rows if r["image"] == image and r["method"] == m
                       and _scored(r) and (r.get(x) or 0) > 0]
                if not pts:
                    continue
                colour, marker = _STYLE.get(m, ("#7f7f7f", "d"))
                ax.scatter([r[x] for r in pts], [r["psnr_db"] for r in pts], s=14, c=colour,
                           marker=marker, alpha=0.45, label=m)
                front = pareto(pts, x)
                ax.plot([r[x] for r in front], [r["psnr_db"] for r in front], c=colour, lw=1.2)
            if logx:
                ax.set_xscale("log")
                # less than a decade of range: matplotlib labels the minor ticks, which overlap
                ax.xaxis.set_minor_formatter(plt.NullFormatter())
            ax.set_title(image)
            ax.set_xlabel(label)
            ax.set_ylabel("PSNR (dB)")
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=8)
        for ax in list(axes.flat)[len(images):]:
            ax.set_visible(False)
        fig.suptitle(("time" if logx else "bits") + " against error (points: every block, codebook "
                     "size and colour; lines: each method's Pareto front)")
        fig.tight_layout()
        path = os.path.join(folder, name)
        fig.savefig(path)
        plt.close(fig)
        paths.append(path)
    return paths


#: Codecs of ``vqtex bench codecs`` added by ``--codecs`` (VQ's rows are this bench's own).
CODECS = ("bc1", "astc", "jpeg2000", "wavelet")
#: The rate-controlled codecs (JPEG 2000, wavelets) run at up to this many of an image's GLA rgb rates.
CODEC_RATES = 6


def _codec_rows(rows, images) -> list[dict]:
    """The rows of ``vqtex.sim.bench.codecs`` on the same images: BC1 and ASTC at their fixed rates,
    JPEG 2000 and the wavelet coder at up to :data:`CODEC_RATES` of the image's GLA rgb rates
    (spread over the range; their ``config`` names the GLA configuration they match)."""
    from vqtex.sim.bench import codecs
    out = []
    for name in images:
        gla = sorted({r["bits_per_texel"]: r["config"] for r in rows
                      if r["image"] == name and r["method"] == "gla" and r["color"] == "rgb"}.items())
        pick = [gla[i] for i in sorted({round(j * (len(gla) - 1) / max(1, CODEC_RATES - 1))
                                        for j in range(CODEC_RATES)})] if gla else []
        targets = {cfg.replace(" k=", "/"): bpt for bpt, cfg in pick}
        out += codecs.codec_rows({name: load_image(name)}, methods=CODECS, targets=targets or None)
    return out


def _scored(r) -> bool:
    """A row with a finite PSNR (lossless rows have None or inf)."""
    p = r.get("psnr_db")
    return p is not None and math.isfinite(p)


def run(json_out: bool = False, *, plot: str | None = None, quick: bool = False,
        include_codecs: bool = False, grid: dict | None = None, seed: int = 0,
        threads: int | None = 1, scheduler: str | None = None, workers: int | None = None,
        progress: bool = True, plot_into: str | None = None) -> dict:
    """Run the grid (``grid``, else :data:`QUICK` or :data:`FULL`); print a table (or one JSON
    object) and return ``{"benchmark", "grid", "threads", "rows", "pareto", "plots"}``. The plots
    are named in the folder ``plot`` and written into ``plot_into`` when given (the command line's
    staging folder, renamed into ``plot`` when the run ends well), else into ``plot``."""
    from vqtex.sim.bench.sweep import run_jobs

    g = dict(grid or (QUICK if quick else FULL))
    if plot:
        from vqtex.sim.reports.plotting import require
        require()  # fail before the work
    if any(m in REFERENCES for m in g["methods"]):
        import sklearn  # noqa: F401  (the bench extra; fail before the work)
    jobs = job_list(g, seed, threads)
    rows = run_jobs(run_job, [(j,) for j in jobs], scheduler=scheduler, workers=workers,
                    progress=progress)
    if include_codecs:
        rows += _codec_rows(rows, g["images"])
    fronts = {}
    for image in dict.fromkeys(r["image"] for r in rows):
        mine = [r for r in rows if r["image"] == image and _scored(r)]
        fronts[image] = {
            "time": [(r["method"], r["config"]) for r in pareto(mine, "encode_s")],
            "bits": [(r["method"], r["config"]) for r in pareto(mine, "bits_per_texel")],
        }
    out = {
        "benchmark": "tradeoff",
        "grid": {k: [list(b) if isinstance(b, tuple) else b for b in v] for k, v in g.items()},
        "threads": threads,
        "cores": os.cpu_count(),
        "bits_per_texel": "index map (nblocks x ceil(log2 k)) + the whole codebook (k x entry bytes x 8), over the texels",
        "rows": [{k: _json_safe(v) for k, v in r.items()} for r in rows],
        "pareto": fronts,
        "plots": [os.path.join(plot, os.path.basename(p)) for p in save_plots(rows, plot_into or plot)] if plot else [],
    }
    if json_out:
        print(json.dumps(out))
    else:
        print(f"encoders: time against error; every library held to "
              f"{threads if threads else 'its default'} thread(s); {len(rows)} points")
        print(table(rows))
        for p in out["plots"]:
            print(f"plot: {p}")
    return out

