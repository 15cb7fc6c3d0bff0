"""The report as text (:func:`area_text`), and the full and the specialised unit side by side
(:func:`compare_units`, :func:`compare_text`)."""

from __future__ import annotations

__all__ = ["area_text", "COMPARE_ROWS", "compare_units", "compare_text"]


def area_text(rep: dict) -> str:
    u = rep["utilisation"]
    lines = [
        f"{rep['design']}: {rep.get('top', 'texel fetch')}, {rep['textures']} texture(s), {rep.get('unit', 'full')} unit, "
        f"{rep['index_reader']} index reader, "
        f"tag width {rep['tag_width']}, latency {rep.get('latency', '?')}, on {rep['device']}",
        f"  LUT4 {u.get('luts', 0)}  FF {u.get('ffs', 0)}  DP16KD {u.get('brams', 0)}  "
        f"MULT18X18D {u.get('dsps', 0)}  CCU2C {u.get('carry', 0)}  DPR16X4 {u.get('dist_ram', 0)}  "
        f"PFUMX/L6MUX21 {u.get('wide_mux', 0)}   (unit; harness adds {rep['harness_ffs']} FF)",
    ]
    if rep.get("mapper", "abc9") != "abc9":
        lines.append(f"  LUT mapping: Yosys's {rep['mapper']} (abc9, the default, stopped on an internal "
                     f"assertion; the counts and timing are the older mapper's)")
    mem_cfg = rep.get("memory")
    if mem_cfg:
        c = [f"{name} {d['size'] // 1024 if d['size'] >= 1024 else d['size']}{' KB' if d['size'] >= 1024 else ' B'} "
             f"({d['sets']} sets x {d['ways']} ways of {d['line']}-byte lines)"
             for name, d in (("index cache", mem_cfg["index_cache"]), ("raw cache", mem_cfg["raw_cache"]))]
        lines.append(f"  external memory: {', '.join(c)}, {mem_cfg['prefetch']}-entry reference FIFO, "
                     f"{mem_cfg['bus_bytes']}-byte AXI bus")
    for mem, d in rep.get("memories", {}).items():
        shape = f"{d['depth']} x {d['width']}" if "depth" in d else "?"
        how = f"{d['DP16KD']} DP16KD" if d["DP16KD"] else d["mapped_to"]
        lines.append(f"    {mem.split('.', 1)[-1]:<34} {shape:>12}  -> {how}")
    t = rep.get("timing")
    if t:
        lines.append(f"  Fmax {t['fmax_mhz']:.1f} MHz ({'meets' if t['met'] else 'misses'} "
                     f"{t['target_mhz']:.0f} MHz; clock {t['clock']}, seed {t['seed']}, "
                     + (f"{t.get('router', 'router1')})" if t.get("routed", True) else "placement estimate, not routed)"))
        cp = t.get("critical_path")
        if cp:
            lines.append(f"  critical path {cp['delay_ns']:.2f} ns ({cp['logic_ns']:.2f} logic, "
                         f"{cp['routing_ns']:.2f} routing): {cp['from_stage']} -> {cp['to_stage']}")
            lines.append(f"    from {cp['from_signal']}  ({cp['from']})")
            lines.append(f"    to   {cp['to_signal']}  ({cp['to']})")
            lines.append(f"    through {' -> '.join(cp['stages'])}")
            if cp.get("cells"):
                short = [c[len("unit.fetch."):] if c.startswith("unit.fetch.") else c for c in cp["cells"]]
                lines.append(f"    via {' -> '.join(short)}")
    s = rep["seconds"]
    lines.append("  time: " + ", ".join(f"{k.replace('_', ' ')} {v:.1f} s" for k, v in s.items()))
    return "\n".join(lines)


#: The rows of the side-by-side table: (label, function of a report).
COMPARE_ROWS = (
    ("LUT4", lambda r: r["utilisation"].get("luts")),
    ("flip-flops", lambda r: r["utilisation"].get("ffs")),
    ("DP16KD", lambda r: r["utilisation"].get("brams")),
    ("MULT18X18D", lambda r: r["utilisation"].get("dsps")),
    ("CCU2C", lambda r: r["utilisation"].get("carry")),
    ("PFUMX+L6MUX21", lambda r: r["utilisation"].get("wide_mux")),
    ("Fmax MHz", lambda r: (r.get("timing") or {}).get("fmax_mhz")),
)


def compare_units(reports: dict) -> dict:
    """Reports of the same set by unit (``{"full": rep, "specialised": rep}``) -> ``{"units":
    reports, "table": {row: {unit: value, "change_pct": specialised vs full}}}``."""
    table = {}
    for label, get in COMPARE_ROWS:
        row = {unit: get(rep) for unit, rep in reports.items()}
        full, spec = row.get("full"), row.get("specialised")
        if full and spec is not None:
            row["change_pct"] = round(100.0 * (spec - full) / full, 1)
        table[label] = row
    return {"units": reports, "table": table}


def compare_text(comparison: dict) -> str:
    """The side-by-side table of :func:`compare_units`, then each unit's own report."""
    units = list(comparison["units"])
    first = comparison["units"][units[0]]
    lines = [f"{first['design']}: {first['textures']} texture(s), {first['index_reader']} index reader, "
             f"latency {first.get('latency', '?')}, on {first['device']}",
             f"  {'':<16}" + "".join(f"{u:>13}" for u in units) + f"{'change':>10}"]
    for label, row in comparison["table"].items():
        cells = "".join(f"{('-' if row[u] is None else format(row[u], 'g')):>13}" for u in units)
        change = f"{row['change_pct']:+.1f}%" if "change_pct" in row else ""
        lines.append(f"  {label:<16}{cells}{change:>10}")
    for u in units:
        feats = comparison["units"][u].get("features")
        if feats:
            lines.append(f"  {u}: " + _features_line(feats))
    for u in units:
        lines.append("")
        lines.append(area_text(comparison["units"][u]))
    return "\n".join(lines)


def _features_line(f: dict) -> str:
    if not f.get("specialised"):
        return "every path, every descriptor field"
    parts = ["/".join(f["colors"]) or "raw only", "b=" + ",".join(map(str, f["index_widths"])),
             "straddling" if f["straddle"] else "no straddles", "raw levels" if f["raw"] else "no raw levels",
             "colour matrix" if f["color_matrix"] else "no colour matrix", f"k*b by {f['k_times_b']}",
             f"{len(f['descriptor_columns'])} descriptor columns"]
    return ", ".join(parts)
