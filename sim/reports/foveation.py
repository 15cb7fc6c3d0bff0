"""What foveation saves: the fovea and the periphery of a foveated frame against the unbiased frame.

A foveated frame (:class:`vqtex.golden.render.fovea.Fovea`: a LOD bias growing with the distance from
a gaze point, 0 inside the radius) and the unbiased frame of the same fragments are compared region
by region. The *fovea* is the covered pixels whose centre is within the radius, the *periphery* the
other covered pixels. For each region and each render (``unbiased``, ``foveated``):

- ``pixels``, ``requests`` (the region's pixels' requests, in stream order);
- ``cycles``: the texel-fetch unit's cycles for that sub-stream alone, on the given backend (the
  golden backend is the exact cycle model): requests + latency without backpressure;
- from :mod:`vqtex.golden.need.analysis` on the sub-stream: ``blocks`` (distinct blocks: a compressed level
  group's block, or a raw texel), ``index_words``, ``codebook_entries`` and ``raw_words`` (distinct
  words of each memory read) and their sum ``memory_words``;

and for the foveated render, its error against the unbiased render over the region's pixels:
``mse`` (R, G, B, the paper's measure, :func:`~vqtex.golden.render.metrics.frame_mse`) and ``psnr``
(dB, ``None`` for identical pixels: infinite). The fovea is identical by construction (bias 0);
``identical`` says whether it is, checked pixel for pixel.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["REGIONS", "compare_regions", "region_figures", "summarize", "summary_lines"]

#: The two regions of a foveated frame.
REGIONS = ("fovea", "periphery")


def region_figures(ts, reqs: np.ndarray, frame_no: int = 0, *, backend: str = "golden", stall: float = 0.0,
                   seed: int = 0, one_port: bool = False) -> dict:
    """Requests, cycles, distinct blocks and memory words of one request (sub-)stream."""
    from vqtex.golden.need.analysis import NeedCounter
    from vqtex.sim.backends.interface import simulate
    reqs = np.asarray(reqs, np.int64).reshape(-1, 4)
    need = NeedCounter(ts).add(frame_no, reqs)
    cycles = simulate(ts, reqs, backend=backend, stall=stall, seed=seed, one_port=one_port).cycles if len(reqs) else 0
    words = need.index_words + need.codebook_entries + need.raw_words
    return {"requests": int(len(reqs)), "cycles": int(cycles), "blocks": need.blocks,
            "index_words": need.index_words, "codebook_entries": need.codebook_entries,
            "raw_words": need.raw_words, "memory_words": words}


def _error(a: np.ndarray, b: np.ndarray) -> dict:
    from vqtex.golden.render.metrics import frame_mse
    if len(a) == 0:
        return {"mse": 0.0, "psnr": None, "identical": True}
    mse = frame_mse(a[None], b[None])
    return {"mse": round(mse, 4), "psnr": _psnr(mse), "identical": bool(np.array_equal(a, b))}


def compare_regions(ts, fovea, foveated, unbiased, frame_no: int = 0, **sim) -> dict:
    """The region report of one frame.

    Arguments:
        ts: the TextureSet the requests address.
        fovea: the :class:`~vqtex.golden.render.fovea.Fovea` of the foveated render.
        foveated, unbiased: (requests (N, 4), Sampler after ``requests()`` with its ``fragments``
            attached (:func:`~vqtex.golden.render.frame.plan_frame`), frame (H, W, 4) uint8) of each
            render; the same fragments.
        sim: ``backend``, ``stall``, ``seed``, ``one_port`` for the cycle counts.

    Returns ``{"fovea": {...}, "periphery": {...}}``, each with ``pixels``, ``unbiased`` and
    ``foveated`` (:func:`region_figures`) and the foveated render's ``mse``, ``psnr``, ``identical``
    against the unbiased one over the region.
    """
    fr, fs, fimg = foveated
    ur, us, uimg = unbiased
    pixel = np.asarray(fs.fragments.pixel, np.int64)
    if not np.array_equal(pixel, us.fragments.pixel):
        raise ValueError("the foveated and unbiased renders cover different pixels")
    width = fimg.shape[1]
    inside = fovea.inside(pixel, width)
    out = {}
    for name, sel in zip(REGIONS, (inside, ~inside)):
        region = {"pixels": int(sel.sum())}
        for label, reqs, smp in (("unbiased", ur, us), ("foveated", fr, fs)):
            region[label] = region_figures(ts, reqs[np.repeat(sel, smp.counts)], frame_no, **sim)
        region.update(_error(fimg.reshape(-1, fimg.shape[2])[pixel[sel]], uimg.reshape(-1, uimg.shape[2])[pixel[sel]]))
        out[name] = region
    return out


def _psnr(mse: float):
    return None if mse == 0 else round(10 * math.log10(255.0 ** 2 / mse), 3)


def summarize(frames: list[dict]) -> dict:
    """Per region, every figure of :func:`compare_regions` averaged over ``frames`` (its results),
    the mean MSE, the PSNR of that mean (``None``: identical) and whether every frame's region was
    identical; plus each region's ``saved`` fractions (1 - foveated / unbiased) of requests, cycles,
    blocks and memory words."""
    out = {"frames": len(frames)}
    for name in REGIONS:
        rs = [f[name] for f in frames]
        region = {"pixels": round(float(np.mean([r["pixels"] for r in rs])), 1)}
        for label in ("unbiased", "foveated"):
            region[label] = {k: round(float(np.mean([r[label][k] for r in rs])), 1) for k in rs[0][label]}
        mse = float(np.mean([r["mse"] for r in rs]))
        region.update(mse=round(mse, 4), psnr=_psnr(mse), identical=all(r["identical"] for r in rs))
        region["saved"] = {k: (round(1 - region["foveated"][k] / region["unbiased"][k], 4)
                               if region["unbiased"][k] else 0.0)
                           for k in ("requests", "cycles", "blocks", "memory_words")}
        out[name] = region
    return out


def summary_lines(summary: dict) -> list[str]:
    """The text report of :func:`summarize` (with the Fovea's fields), one line per region."""
    lines = [f"fovea at ({summary['x']:g}, {summary['y']:g}), radius {summary['radius']:g} px, falloff "
             f"{summary['falloff']:g} levels per radius; per frame, unbiased -> foveated:"]
    for name in REGIONS:
        r = summary[name]
        u, f = r["unbiased"], r["foveated"]
        err = "identical" if r["identical"] else f"MSE {r['mse']:.3f}, PSNR {r['psnr']:.2f} dB"
        lines.append(f"  {name:9} {r['pixels']:9,.0f} px: requests {u['requests']:,.0f} -> {f['requests']:,.0f}, "
                     f"cycles {u['cycles']:,.0f} -> {f['cycles']:,.0f}, blocks {u['blocks']:,.0f} -> "
                     f"{f['blocks']:,.0f}, memory words {u['memory_words']:,.0f} -> {f['memory_words']:,.0f}; "
                     f"{err} against the unbiased frame")
    return lines
