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
    mem = rep.get("memory")
    if mem:
        lines.append(f"memory             {mem['configuration']}")
        for name in ("index", "raw"):
            hr = mem["hit_rate"][name]
            lines.append(f"{name + ' cache':<18} {mem['references'][name]} references"
                         + (f", hit rate {100 * hr:.2f}%" if hr is not None else ""))
        lines.append(f"memory read        {mem['bursts']} bursts, {sum(mem['memory_bytes'].values())} bytes, "
                     f"{mem['bytes_per_texel']:.4f} bytes per texel")
        if "of_zero_latency" in mem:
            lines.append(f"zero latency       {mem['zero_latency_cycles']} cycles "
                         f"({mem['of_zero_latency']:.4f} of its texels per clock)")
    for cause, n in rep["stall_cycles"].items():
        lines.append(f"stalls: {cause:<11} {n}")
    detail = (mem or {}).get("stall_detail")
    if detail:
        lines.append(f"memory stall split data read waited: miss {detail['miss']}, bandwidth {detail['bandwidth']}; "
                     f"tag check waited: FIFO full {detail['fifo_full']}, victim in use {detail['victim']}")
    for stage, occ in rep.get("occupancy", {}).items():
        lines.append(f"occupancy {stage:<8} {occ:.3f}")
    return "\n".join(lines)


def cycle_plot(rep: dict, path: str) -> None:
    """Where the cycles went, a PNG drawn with matplotlib (the ``plot`` extra; see
    :func:`vqtex.sim.reports.plotting.cycle_figure`): title, axis, legend, the stall causes named."""
    from .plotting import save_cycle_plot
    save_cycle_plot(rep, path)
