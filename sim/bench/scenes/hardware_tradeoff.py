"""The hardware's trade-off: frame error against cycles per frame and memory bits.

``vqtex experiments hardware [--json] [--plot FILE.png]``. For each scene (``topspin-paper`` and
``town-paper``, the paper-sized scenes of Tables 3 and 4), each sampling (point, trilinear), index
width (8 bits: 256 codewords; 12 bits: 4096 codewords), and colour format of the RGB textures (rgb,
yuv411), one job (:func:`point`):

1. encode the scene: every RGB texture in one shared codebook of 4x4 blocks (the paper's "all RGB"
   rows); the town's one-channel and RGBA textures in codebooks of 256 2x2 codewords, as in the
   paper's Table 3, their index maps as wide as the RGB ones (so every fetch of a 12-bit point
   takes the 12-bit index path);
2. render the selected frames from the compressed and the uncompressed textures with the same
   requests: the mean frame MSE (the paper's measure) and PSNR;
3. run every frame's texel requests through the RTL (``backend``, the compiled CXXRTL model by
   default) with the two-bank index memory (the design) and with one port (the paper's penalty):
   cycles per frame and straddling index reads per frame;
4. count the memory: the bits of the index, codebook and raw memories the unit holds (the memory
   images of ``golden.format``: index words x word width, codebook entries x entry width, raw words
   x 32), and the paper's stored bits (index bits, raw levels and codebooks, no word padding).

The jobs run through :func:`sim.bench.sweep.run_jobs` (serially or on dask), results in job order.
"""

from __future__ import annotations

import time

import numpy as np

__all__ = ["SCENES", "SAMPLINGS", "INDEX_BITS", "COLORS", "CODEBOOK_SIZE", "jobs", "point", "sweep",
           "memory_bits", "check_plotting", "plot"]

SCENES = ("topspin-paper", "town-paper")
SAMPLINGS = ("point", "trilinear")
INDEX_BITS = (8, 12)
COLORS = ("rgb", "yuv411")
#: Codewords of the RGB codebook for each index width.
CODEBOOK_SIZE = {8: 256, 12: 4096}
#: The codebooks of the scene's one-channel and RGBA textures (Table 3's): (K, block).
OTHER_CODEBOOK = (256, "2x2")


def _codebooks(scene, index_bits: int, color: str):
    """One shared codebook for every RGB texture of ``scene`` (K from the index width, 4x4 blocks,
    ``color``), one for its one-channel and one for its RGBA textures (:data:`OTHER_CODEBOOK`), all
    with ``index_bits``-wide index maps."""
    from .paper_configs import Codebook
    by_color: dict = {}
    for t in scene.textures:
        kind = "rgb" if t.color in ("rgb", "yuv411") else t.color
        by_color.setdefault(kind, [])
        if t.group not in by_color[kind]:
            by_color[kind].append(t.group)
    cbs = []
    for kind, groups in by_color.items():
        if kind == "rgb":
            cbs.append(Codebook(tuple(groups), CODEBOOK_SIZE[index_bits], "4x4", color, index_bits=index_bits))
        else:
            cbs.append(Codebook(tuple(groups), OTHER_CODEBOOK[0], OTHER_CODEBOOK[1], kind, index_bits=index_bits))
    return tuple(cbs)


def jobs(frame_step: int = 10, backend: str = "cxxrtl", scenes=SCENES, samplings=SAMPLINGS,
         index_bits=INDEX_BITS, colors=COLORS, stream: str = "fixed") -> list[tuple]:
    """The sweep's jobs (arguments of :func:`point`), scene by scene."""
    return [(s, m, b, c, frame_step, backend, stream)
            for s in scenes for m in samplings for b in index_bits for c in colors]


def memory_bits(ts) -> dict:
    """Bits of the memories the unit holds for ``ts`` (index, codebook, raw; descriptors apart)."""
    index = int(ts.index_words.size) * int(ts.word_bits)
    codebook = int(ts.codebook.size) * 8
    raw = int(ts.raw_words.size) * 32
    return {"index": index, "codebook": codebook, "raw": raw, "total": index + codebook + raw}


def point(scene_name: str, sampling: str, index_bits: int, color: str, frame_step: int = 10,
          backend: str = "cxxrtl", stream: str = "fixed") -> dict:
    """One point of the trade-off (a sweep job) over every ``frame_step``-th frame: see the module's
    steps 1-4. ``stream``: the renderer's request stream, "fixed" (eight requests a trilinear pixel,
    as the paper's renderer issues them) or "sparse" (the requests that cannot change a pixel left
    out; the same frames, fewer cycles: docs/skipping.md)."""
    from vqtex.golden.render.frame import frame_requests
    from vqtex.golden.render.metrics import frame_mse
    from vqtex.golden.render.pyramid import ReferenceSource
    from vqtex.golden.render.scene import load_scene
    from .experiments import encode_config, permuted_source
    scene = load_scene(scene_name)
    if frame_step < 1:
        raise ValueError(f"frame step {frame_step} must be at least 1")
    frames = list(range(0, scene.frames, frame_step))
    images = [img for img, _ in scene.load_textures()]
    t0 = time.perf_counter()
    ts, ids = encode_config(scene, images, _codebooks(scene, index_bits, color), sampling == "trilinear")
    enc_s = time.perf_counter() - t0
    src, to_set = permuted_source(ts, ids)
    ref = ReferenceSource(images, levels=[len(src.level_shapes(t.id)) for t in scene.textures])
    mses, nreq, straddles = [], 0, 0
    cycles = {"two_bank": 0, "one_port": 0}
    t1 = time.perf_counter()
    with _Units(ts, backend) as units:
        build_s = time.perf_counter() - t1
        sim_s = 0.0
        for f in frames:
            reqs, sampler = frame_requests(scene, f, src, sampling, stream=stream)
            hw = np.column_stack([to_set[reqs[:, 0]], reqs[:, 1:]])
            t1 = time.perf_counter()
            two, one = units.run(hw, False), units.run(hw, True)
            sim_s += time.perf_counter() - t1
            if not np.array_equal(two.responses, one.responses):
                raise RuntimeError(f"{scene_name} frame {f}: one-port and two-bank responses differ")
            img = sampler.resolve(two.responses)           # the frame as the RTL answered it
            mses.append(frame_mse(img, sampler.resolve(ref.fetch(*reqs.T))))
            cycles["two_bank"] += two.cycles
            cycles["one_port"] += one.cycles
            straddles += one.straddles
            nreq += len(reqs)
    n = len(frames)
    mse = float(np.mean(mses))
    rates = ts.rates()
    return {
        "scene": scene_name, "sampling": sampling, "index_bits": index_bits,
        "codebook_size": CODEBOOK_SIZE[index_bits], "color": color, "frames": n, "stream": stream,
        "mse": round(mse, 3), "psnr": round(float(10 * np.log10(255.0 ** 2 / mse)), 2) if mse > 0 else None,
        "requests_per_frame": round(nreq / n), "cycles_per_frame_two_bank": round(cycles["two_bank"] / n),
        "cycles_per_frame_one_port": round(cycles["one_port"] / n),
        "one_port_extra_pct": round(100 * (cycles["one_port"] / cycles["two_bank"] - 1), 2),
        "straddles_per_frame": round(straddles / n),
        "memory_bits": memory_bits(ts), "stored_bits": int(round(rates["stored_bits"])),
        "overall_rate": round(rates["overall"], 2), "rtl_backend": backend,
        "encode_seconds": round(enc_s, 2), "build_seconds": round(build_s, 2), "simulate_seconds": round(sim_s, 2),
    }


class _Units:
    """The texel-fetch unit holding ``ts``, two-bank and one-port, on ``backend``: the compiled
    library is built (or taken from the cache) and loaded once per port and then runs every frame
    (``cxxrtl``); other backends go through ``sim.backends.simulate`` per frame."""

    def __init__(self, ts, backend: str):
        self.ts, self.backend, self.open = ts, backend, {}

    def __enter__(self):
        if self.backend == "cxxrtl":
            from vqtex.sim.backends.cxxrtl import open_cxxrtl
            for one_port in (False, True):
                self.open[one_port] = open_cxxrtl(self.ts, one_port=one_port)[:2]
        return self

    def run(self, requests, one_port: bool):
        if one_port in self.open:
            from vqtex.sim.backends.cxxrtl import run_batch
            lib, info = self.open[one_port]
            return run_batch(lib, info, requests)
        from vqtex.sim.backends.interface import simulate
        return simulate(self.ts, requests, backend=self.backend, one_port=one_port)

    def __exit__(self, *exc):
        for lib, _ in self.open.values():
            lib.close()
        self.open.clear()


def sweep(frame_step: int = 10, backend: str = "cxxrtl", sweep: dict | None = None, **select) -> list[dict]:
    """Every point (:func:`jobs`, narrowed by ``select``: scenes, samplings, index_bits, colors, stream), run
    with :func:`sim.bench.sweep.run_jobs` (``sweep``: its keyword arguments; default serial)."""
    from ..sweep import run_jobs
    return run_jobs(point, jobs(frame_step, backend, **select), **(sweep or {"scheduler": "serial", "progress": False}))


def check_plotting() -> None:
    """PlotError (one line naming the extra) if matplotlib is missing: call before the work."""
    from vqtex.sim.reports.plotting import require
    require()


def plot(rows: list[dict], path: str) -> None:
    """Frame MSE against cycles per frame (left) and against memory bits (right), one marker per
    point: colour = scene and sampling, filled = two banks / hollow = one port (left), circle = 8-bit
    / square = 12-bit indices, solid edge = rgb / dashed = yuv411. Written to ``path`` (PNG)."""
    from vqtex.sim.reports.plotting import require
    plt = require()
    fig, (ax_c, ax_m) = plt.subplots(1, 2, figsize=(12, 5), dpi=100)
    palette = {}
    colours = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b"]
    for r in rows:
        key = f"{r['scene']} {r['sampling']}"
        col = palette.setdefault(key, colours[len(palette) % len(colours)])
        marker = "o" if r["index_bits"] == 8 else "s"
        style = "-" if r["color"] == "rgb" else "--"
        y = r["mse"]
        ax_c.scatter(r["cycles_per_frame_two_bank"], y, marker=marker, color=col, edgecolors=col, s=50)
        ax_c.scatter(r["cycles_per_frame_one_port"], y, marker=marker, facecolors="none", edgecolors=col, s=50,
                     linestyle=style)
        ax_c.plot([r["cycles_per_frame_two_bank"], r["cycles_per_frame_one_port"]], [y, y], color=col, lw=0.6,
                  linestyle=style)
        ax_m.scatter(r["memory_bits"]["total"], y, marker=marker, color=col, s=50,
                     facecolors=col if r["color"] == "rgb" else "none", edgecolors=col)
    from matplotlib.ticker import NullFormatter
    for ax in (ax_c, ax_m):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_minor_formatter(NullFormatter())        # decade labels only: no overlapping ticks
        ax.set_ylabel("frame MSE (the paper's, mean over frames; log scale)")
        ax.grid(True, which="both", lw=0.3)
    ax_c.set_xlabel("RTL cycles per frame (filled: two banks; hollow: one port)")
    ax_m.set_xlabel("memory bits (index + codebook + raw memories; filled: rgb, hollow: yuv411)")
    handles = [plt.Line2D([], [], color=c, marker="o", ls="", label=k) for k, c in palette.items()]
    handles += [plt.Line2D([], [], color="grey", marker="o", ls="", label="8-bit indices (K = 256)"),
                plt.Line2D([], [], color="grey", marker="s", ls="", label="12-bit indices (K = 4096)"),
                plt.Line2D([], [], color="grey", ls="-", label="rgb (left: line to the one-port point)"),
                plt.Line2D([], [], color="grey", ls="--", label="yuv411")]
    ax_m.legend(handles=handles, fontsize=7, loc="best")
    backends = ", ".join(sorted({r["rtl_backend"] for r in rows}))
    fig.suptitle(f"Frame error against cycles per frame and memory bits (cycles from: {backends})", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, format="png", bbox_inches="tight")
    plt.close(fig)
