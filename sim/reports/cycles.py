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
    if rep.get("load_cycles") is not None:
        lines.insert(1, f"unit               loadable, geometry {rep['geometry']}")
        lines.append(f"load (bus writes)  {rep['load_cycles']} cycles, before the requests")
    for cause, n in rep["stall_cycles"].items():
        lines.append(f"stalls: {cause:<11} {n}")
    for stage, occ in rep.get("occupancy", {}).items():
        lines.append(f"occupancy {stage:<8} {occ:.3f}")
    return "\n".join(lines)


def cycle_plot(rep: dict, path: str) -> None:
    """Where the cycles went, a PNG drawn with matplotlib (the ``plot`` extra; see
    :func:`vqtex.sim.reports.plotting.cycle_figure`): title, axis, legend, the stall causes named."""
    from .plotting import save_cycle_plot
    save_cycle_plot(rep, path)
