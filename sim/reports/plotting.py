"""Figures drawn with matplotlib (the optional ``plot`` extra): where the cycles went, and a
frame's difference from the uncompressed one with its colour scale.

Without matplotlib, :func:`require` raises :class:`PlotError` (an ``OSError``: the command line
prints one line naming ``pip install '.[plot]'`` and exits 2); commands call it before any work.
"""

from __future__ import annotations

import numpy as np

__all__ = ["PlotError", "require", "cycle_figure", "memory_axes", "save_cycle_plot", "save_difference_plot", "INSTALL_HINT",
           "CYCLE_PARTS"]

INSTALL_HINT = "pip install '.[plot]' (matplotlib)"

#: What each part of the cycle bar means, in order: (key, label, colour).
CYCLE_PARTS = (
    ("requests", "one cycle per request (the unit's throughput)", "#3ca03c"),
    ("groups", "a group of lanes texel slots per clock (the filter)", "#50a050"),
    ("latency", "pipeline fill: the latency of the first response", "#7878dc"),
    ("output_backpressure", "stall: the consumer held ready low (--stall)", "#dc5a3c"),
    ("one_port_straddle", "stall: a straddling index on a one-port index memory", "#e6b428"),
    ("memory", "stall: the cache waited for a line from memory (--memory external)", "#3c8cc8"),
)


class PlotError(OSError):
    """matplotlib is missing; ``str()`` is one line naming what to install."""


def require():
    """matplotlib's pyplot on the file-only Agg backend; PlotError if matplotlib is not installed."""
    try:
        import matplotlib
    except ImportError:
        raise PlotError(f"plots need matplotlib: {INSTALL_HINT}") from None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def cycle_figure(rep: dict):
    """A figure of where the cycles of a cycle report (:func:`~vqtex.sim.reports.cycles.cycle_report`)
    went: one horizontal bar, the cycles split by cause, every part in the legend with its count and
    share; the title names the backend, the index reader and the texels per clock. A report of the
    unit through external memory (``rep["memory"]``, ``--memory external``) gets a second row,
    :func:`memory_axes`: each cache's hit rate, the bytes read from memory per texel, and the texels
    per clock against the zero-latency unit's; its memory stall's legend entry splits the wait into
    miss and bandwidth where the report has the split (``stall_detail``)."""
    plt = require()
    if "pixels" in rep:             # the filter through memory: a group of lanes texels a clock, at best
        held = rep["stall_cycles"]["output_backpressure"]
        values = {"groups": rep["groups"], "latency": rep["latency"], "output_backpressure": held,
                  "memory": max(0, rep["cycles"] - rep["groups"] - rep["latency"] - held)}
    else:
        values = {"requests": rep["requests"], "latency": rep["latency"], **rep["stall_cycles"]}
    known = {k for k, _, _ in CYCLE_PARTS}
    parts = [(k, label, col) for k, label, col in CYCLE_PARTS if k in values]
    parts += [(k, f"stall: {k.replace('_', ' ')}", "#9650b4") for k in values if k not in known]
    total = max(1, rep["cycles"])
    mem = rep.get("memory")
    if mem:
        fig = plt.figure(figsize=(9, 5.6), dpi=100)
        grid = fig.add_gridspec(2, 3, height_ratios=(1, 1.1), hspace=1.1, wspace=0.45)
        ax = fig.add_subplot(grid[0, :])
    else:
        fig, ax = plt.subplots(figsize=(9, 3.2), dpi=100)
    detail = (mem or {}).get("stall_detail") if "pixels" not in rep else None   # (the filter's: lane-cycles)
    left = 0
    for key, label, colour in parts:
        v = values[key]
        split = f"; miss {detail['miss']}, bandwidth {detail['bandwidth']}" if key == "memory" and detail else ""
        ax.barh([0], [v], left=left, color=colour, height=0.6,
                label=f"{label}: {v} cycles ({100 * v / total:.1f}%{split})")
        left += v
    other = rep["cycles"] - left
    if other > 0:
        ax.barh([0], [other], left=left, color="#aaaaaa", height=0.6, label=f"other: {other} cycles")
    ax.set_xlim(0, total)
    ax.set_yticks([])
    ax.set_xlabel("clock cycles")
    if "pixels" in rep:
        ax.set_title(f"Where the {rep['cycles']} cycles went: {rep['pixels']} pixels, {rep['top']}, "
                     f"{rep['backend']} backend, {rep['pixels_per_clock']:.3f} pixels/clock", fontsize=9)
    else:
        ax.set_title(f"Where the {rep['cycles']} cycles went: {rep['requests']} requests, {rep['backend']} backend, "
                     f"{rep['index_reader']} index reader, {rep['texels_per_clock']:.3f} texels/clock", fontsize=9)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.35), fontsize=8, frameon=False)
    if mem:
        memory_axes(fig, [fig.add_subplot(grid[1, k]) for k in range(3)], rep)
    else:
        fig.tight_layout()
    return fig


def memory_axes(fig, axes, rep: dict) -> None:
    """The memory row of :func:`cycle_figure` on three axes: the index and raw caches' hit rates
    (percent; a cache no request used is drawn empty and labelled "unused"), the bytes read from
    memory per texel split by cache, and the texels per clock of this run beside the zero-latency
    unit's on the same stream (when the report has it: the golden model's ``zero_latency_cycles``).
    For the texture filter through memory (``rep["pixels"]``, :func:`sim.reports.cycles.
    filter_cycle_report`): bytes per pixel, and pixels per clock beside the on-chip filter's on the
    same pixels; the hit rates are golden's (an RTL run's are labelled "not measured")."""
    mem = rep["memory"]
    hit, rates, bytes_ = axes
    names = ("index", "raw")
    measured = "hit_rate" in mem
    rate = [mem["hit_rate"][n] if measured else None for n in names]
    hit.bar(names, [100 * r if r is not None else 0 for r in rate], color=("#3c8cc8", "#e6b428"))
    for x, r in enumerate(rate):
        hit.text(x, 2, f"{100 * r:.1f}%" if r is not None else "unused" if measured else "not measured",
                 ha="center", fontsize=8)
    hit.set_ylim(0, 100)
    hit.set_ylabel("hit rate (%)", fontsize=8)
    hit.set_title("cache hit rate", fontsize=9)
    if "pixels" in rep:
        per = [mem["memory_bytes"][n] / max(1, rep["pixels"]) for n in names]
        bytes_.bar(names, per, color=("#3c8cc8", "#e6b428"))
        bytes_.set_ylabel("bytes per pixel", fontsize=8)
        bytes_.set_title(f"memory read: {mem['bytes_per_pixel']:.3f} B/pixel", fontsize=9)
        ppc = [rep["pixels_per_clock"], rep["on_chip_pixels_per_clock"]]
        rates.bar(["this run", "on-chip filter"], ppc, color=("#3ca03c", "#aaaaaa"))
        rates.set_ylim(0, 1.05 * max(1.0, *ppc))
        rates.set_ylabel("pixels per clock", fontsize=8)
        rates.set_title(f"pixels per clock ({ppc[0] / max(ppc[1], 1e-12):.3f} of on-chip)", fontsize=9)
        for a in axes:
            a.tick_params(labelsize=8)
        return
    requests = max(1, rep["requests"])
    per = [mem["memory_bytes"][n] / requests for n in names]
    bytes_.bar(names, per, color=("#3c8cc8", "#e6b428"))
    bytes_.set_ylabel("bytes per texel", fontsize=8)
    bytes_.set_title(f"memory read: {mem['bytes_per_texel']:.3f} B/texel", fontsize=9)
    labels, tpc = ["this run"], [rep["texels_per_clock"]]
    if "zero_latency_cycles" in mem:
        labels.append("zero latency")
        tpc.append(rep["requests"] / max(1, mem["zero_latency_cycles"]))
    rates.bar(labels, tpc, color=("#3ca03c", "#aaaaaa")[:len(tpc)])
    rates.set_ylim(0, 1.05 * max(1.0, *tpc))
    rates.set_ylabel("texels per clock", fontsize=8)
    rates.set_title("texels per clock" + (f" ({mem['of_zero_latency']:.3f} of zero latency)"
                                          if "of_zero_latency" in mem else ""), fontsize=9)
    for a in axes:
        a.tick_params(labelsize=8)


def save_cycle_plot(rep: dict, path: str) -> None:
    """:func:`cycle_figure` written to ``path`` (PNG)."""
    plt = require()
    fig = cycle_figure(rep)
    fig.savefig(path, format="png", bbox_inches="tight")
    plt.close(fig)


def save_difference_plot(diff: np.ndarray, path: str, title: str, vmax: int) -> None:
    """A difference map (:func:`~vqtex.sim.reports.quality.difference`) as a heat map with a colour
    bar 0..``vmax`` (larger differences saturate), written to ``path`` (PNG)."""
    plt = require()
    h, w = diff.shape
    fig, ax = plt.subplots(figsize=(max(4.0, w / 100 + 1.6), max(3.0, h / 100 + 0.8)), dpi=100)
    im = ax.imshow(diff, cmap="inferno", vmin=0, vmax=vmax, interpolation="nearest")
    ax.set_axis_off()
    ax.set_title(title, fontsize=9)
    bar = fig.colorbar(im, ax=ax, fraction=0.046, pad=0.04, extend="max")
    bar.set_label("|compressed - uncompressed|, max over R, G, B (levels of 255)", fontsize=8)
    fig.savefig(path, format="png", bbox_inches="tight")
    plt.close(fig)
