"""``vqtex info FILE.vqt``: textures, levels, index bits and compression rates as the paper counts them."""

from __future__ import annotations

from .common import add_json, add_texture_set, emit, load_set

__all__ = ["add_parser", "cmd_info", "info_report", "info_text"]


def info_report(ts) -> dict:
    """Per texture and overall: sizes, levels, index bits, codebooks, memory bits and compression rates."""
    textures = []
    for t, info in enumerate(ts.textures):
        r = ts.rates(t)
        cb = ts.codebooks[info.codebook] if info.codebook >= 0 else None
        levels = ts.level_shapes(t)
        textures.append({
            "id": t, "name": info.name, "width": info.width, "height": info.height,
            "levels": info.levels, "color": info.color, "block": f"{info.block[0]}x{info.block[1]}",
            "index_bits": info.index_bits, "codebook": info.codebook,
            "codebook_size": cb.size if cb else 0, "mipmapped": info.mipmapped,
            "compressed_levels": [L for L in range(len(levels)) if ts.descriptors[t, L]["compressed"]],
            "base_rate": round(r["base"], 4), "overall_rate": round(r["overall"], 4),
        })
    return {
        "textures": textures,
        "codebooks": [{"id": n, "color": c.color, "block": f"{c.block[0]}x{c.block[1]}", "size": c.size,
                       "entry_bytes": c.layout.size, "extended_levels": c.nsub} for n, c in enumerate(ts.codebooks)],
        "word_bits": ts.word_bits,
        "memory_bits": {"index": int(len(ts.index_words) * ts.word_bits),
                        "codebook": int(ts.codebook.size * 8), "raw": int(len(ts.raw_words) * 32),
                        "descriptor": int(ts.descriptors.size * len(ts.descriptors.dtype.names) * 32)},
        "overall_rate": round(ts.rates()["overall"], 4),
    }


def info_text(ts, report) -> str:
    """``info_report`` as the table ``vqtex info`` prints."""
    lines = [f"{'id':>3} {'name':<16} {'size':>10} {'lv':>3} {'color':<9} {'block':<5} {'b':>3} "
             f"{'K':>5} {'base':>8} {'overall':>8}"]
    for t in report["textures"]:
        lines.append(f"{t['id']:>3} {t['name'][:16]:<16} {t['width']:>4}x{t['height']:<5} {t['levels']:>3} "
                     f"{t['color']:<9} {t['block']:<5} {t['index_bits']:>3} {t['codebook_size']:>5} "
                     f"{t['base_rate']:>7.2f}:1 {t['overall_rate']:>6.2f}:1")
    lines.append(f"overall compression rate {report['overall_rate']:.2f}:1 "
                 f"({len(ts.codebooks)} codebook(s), index words of {ts.word_bits} bits)")
    return "\n".join(lines)


def cmd_info(args) -> int:
    ts = load_set(args.file)
    report = info_report(ts)
    emit(report, args.json, info_text(ts, report))
    return 0


def add_parser(sub) -> None:
    i = sub.add_parser("info", help="textures, levels, index bits and compression rates of a .vqt")
    add_texture_set(i)
    add_json(i)
    i.set_defaults(func=cmd_info)
