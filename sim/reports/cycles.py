"""Cycle reports: one dict (for ``--json``) and a readable table, from any backend's SimResult (the
texel-fetch unit) or FilterResult (the texture filter through memory: :func:`filter_cycle_report`)."""

from __future__ import annotations

__all__ = ["cycle_report", "filter_cycle_report", "cycle_text", "cycle_plot"]


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


def filter_cycle_report(res, *, backend: str, stall: float = 0.0, extra: dict | None = None) -> dict:
    """The texture filter through memory's run (a ``sim.backends.filter.FilterResult`` with ``memory``):
    pixels, groups of ``lanes`` texel slots, cycles, pixels and texels per clock, latency, stall
    cycles (``memory``: the lanes' fill waits summed over the lanes, lane-cycles), and the memory
    figures (bursts, bytes, bytes per pixel; golden: references, hit rates, the stall detail). The
    on-chip filter's cycles on the same pixels (``groups + hw.filter.LATENCY``, 24, golden's model) and its pixels per
    clock."""
    from vqtex.hw.filter import LATENCY
    groups = int(res.texels // res.lanes)
    on_chip = groups + LATENCY if groups else 0
    rep = {
        "backend": backend,
        "top": f"texture filter through memory, {res.lanes} lane(s)",
        "stall_probability": stall,
        "pixels": int(res.pixels),
        "groups": groups,
        "lanes": int(res.lanes),
        "cycles": int(res.cycles),
        "pixels_per_clock": res.pixels / res.cycles if res.cycles else 0.0,
        "texels_per_clock": res.texels / res.cycles if res.cycles else 0.0,
        "latency": int(res.latency),
        "stall_cycles": {k: int(v) for k, v in res.stall_cycles.items()},
        "on_chip_cycles": on_chip,
        "on_chip_pixels_per_clock": res.pixels / on_chip if on_chip else 0.0,
        "memory": {k: v for k, v in res.memory.items() if k != "ar"},
    }
    if extra:
        rep.update(extra)
    return rep


def _cache_lines(mem: dict, noun: str) -> list:
    """One line per cache (index, raw): its references and, if it had any, its hit rate."""
    lines = []
    for name in ("index", "raw"):
        hr = mem["hit_rate"][name]
        lines.append(f"{name + ' ' + noun:<18} {mem['references'][name]} references"
                     + (f", hit rate {100 * hr:.2f}%" if hr is not None else ""))
    return lines


def _load_lines(rep: dict, lines: list, what: str) -> None:
    """A loadable unit's lines (its geometry second, the load's cycles before ``what``), in place."""
    if rep.get("load_cycles") is not None:
        lines.insert(1, f"unit               loadable, geometry {rep['geometry']}")
        lines.append(f"load (bus writes)  {rep['load_cycles']} cycles, before the {what}")


def _filter_text(rep: dict) -> list:
    mem = rep["memory"]
    lines = [
        f"backend            {rep['backend']} ({rep['top']})",
        f"pixels             {rep['pixels']} ({rep['groups']} groups of {rep['lanes']} texel slots)",
        f"cycles             {rep['cycles']}",
        f"pixels per clock   {rep['pixels_per_clock']:.4f} (the on-chip filter: {rep['on_chip_pixels_per_clock']:.4f}, "
        f"{rep['on_chip_cycles']} cycles)",
        f"latency            {rep['latency']} cycles when every reference hits",
        f"memory             {mem['configuration']}, a cache per lane",
    ]
    _load_lines(rep, lines, "pixels")
    if "references" in mem:
        lines += _cache_lines(mem, "caches")
    lines.append(f"memory read        {mem['bursts']} bursts, {sum(mem['memory_bytes'].values())} bytes, "
                 f"{mem['bytes_per_pixel']:.4f} bytes per pixel")
    lines.append(f"stalls: output     {rep['stall_cycles']['output_backpressure']} cycles")
    lines.append(f"fill waits         {rep['stall_cycles']['memory']} lane-cycles (summed over the lanes)")
    detail = mem.get("stall_detail")
    if detail:
        lines.append(f"memory stall split data reads waited: miss {detail['miss']}, bandwidth {detail['bandwidth']}; "
                     f"join {detail['join']}; tag checks waited: FIFO full {detail['fifo_full']}, victim in use "
                     f"{detail['victim']} (lane-cycles); ARs waited for the arbiter {detail['arbiter']} cycles")
    return lines


def cycle_text(rep: dict) -> str:
    if "pixels" in rep:
        return "\n".join(_filter_text(rep))
    lines = [
        f"backend            {rep['backend']} ({rep['index_reader']} index reader)",
        f"requests           {rep['requests']}",
        f"cycles             {rep['cycles']}",
        f"texels per clock   {rep['texels_per_clock']:.4f}",
        f"latency            {rep['latency']} cycles",
        f"straddling reads   {rep['straddling_index_reads']}",
    ]
    _load_lines(rep, lines, "requests")
    mem = rep.get("memory")
    if mem:
        lines.append(f"memory             {mem['configuration']}")
        lines += _cache_lines(mem, "cache")
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
