"""Figures drawn with matplotlib (the optional ``plot`` extra): where the cycles went, and a
frame's difference from the uncompressed one with its colour scale.

Without matplotlib, :func:`require` raises :class:`PlotError` (an ``OSError``: the command line
prints one line naming ``pip install '.[plot]'`` and exits 2); commands call it before any work.
"""

from __future__ import annotations

import numpy as np

__all__ = ["PlotError", "require", "cycle_figure", "save_cycle_plot", "save_difference_plot", "INSTALL_HINT",
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
    share; the title names the backend, the index reader and the texels per clock."""
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
    fig, ax = plt.subplots(figsize=(9, 3.2), dpi=100)
    left = 0
    for key, label, colour in parts:
        v = values[key]
        ax.barh([0], [v], left=left, color=colour, height=0.6,
                label=f"{label}: {v} cycles ({100 * v / total:.1f}%)")
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
    fig.tight_layout()
    return fig


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
