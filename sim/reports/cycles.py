"""Cycle reports: one dict (for ``--json``) and a readable table, from any backend's SimResult."""

from __future__ import annotations

__all__ = ["cycle_report", "cycle_text", "cycle_plot"]


def cycle_report(res, *, backend: str, one_port: bool = False, stall: float = 0.0, extra: dict | None = None) -> dict:
    """Requests, cycles, texels per clock, latency, stall cycles by cause, straddling index reads,
    per-stage occupancy (where the backend measures it)."""
    rep = {
        "backend": backend,
        "index_reader": "one-port" if one_port else "two-bank",
        "stall_probability": stall,
        "requests": int(res.requests),
        "cycles": int(res.cycles),
        "texels_per_clock": (res.requests / res.cycles) if res.cycles else 0.0,
        "latency": int(res.latency),
        "stall_cycles": {k: int(v) for k, v in res.stall_cycles.items()},
        "straddling_index_reads": int(res.straddles),
    }
    if getattr(res, "occupancy", None):
        rep["occupancy"] = {k: round(float(v), 4) for k, v in res.occupancy.items()}
    if extra:
        rep.update(extra)
    return rep


def cycle_text(rep: dict) -> str:
    lines = [
        f"backend            {rep['backend']} ({rep['index_reader']} index reader)",
        f"requests           {rep['requests']}",
        f"cycles             {rep['cycles']}",
        f"texels per clock   {rep['texels_per_clock']:.4f}",
        f"latency            {rep['latency']} cycles",
        f"straddling reads   {rep['straddling_index_reads']}",
    ]
    for cause, n in rep["stall_cycles"].items():
        lines.append(f"stalls: {cause:<11} {n}")
    for stage, occ in rep.get("occupancy", {}).items():
        lines.append(f"occupancy {stage:<8} {occ:.3f}")
    return "\n".join(lines)


def cycle_plot(rep: dict, path: str) -> None:
    """A stacked bar (PNG, 640x80) of where the cycles went, left to right: one cycle per request
    (green), the pipeline latency (blue), output backpressure stalls (red), one-port straddle stalls
    (yellow). Each part's width is proportional to its cycle count.

    Drawn with numpy into an image (no plotting library needed) and written with OpenImageIO.
    """
    import numpy as np
    from vqtex.golden.render.imageio import write_image
    parts = [("requests", rep["requests"], (60, 160, 60)), ("latency", rep["latency"], (120, 120, 220))]
    colours = [(220, 90, 60), (230, 180, 40), (150, 80, 180)]
    for n, (cause, v) in enumerate(rep["stall_cycles"].items()):
        parts.append((cause, v, colours[n % len(colours)]))
    total = max(1, sum(v for _, v, _ in parts))
    w, h = 640, 80
    img = np.full((h, w, 3), 255, np.uint8)
    x = 0
    for _, v, col in parts:
        dx = int(round(v * (w - 1) / total))
        img[10:70, x: x + dx] = col
        x += dx
    write_image(path, img)
