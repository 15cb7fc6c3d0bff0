"""``vqtex info FILE.vqt [--images IMAGE...]``: textures, levels, index bits and compression rates as the
paper counts them; with the uncompressed images, PSNR per texture and mip level."""

from __future__ import annotations

from .common import CliError, add_json, add_texture_set, emit, load_set, with_default

__all__ = ["add_parser", "cmd_info", "info_report", "info_text", "add_psnr"]


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
            "absent_levels": list(info.absent_levels),
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


def add_psnr(report: dict, ts, images) -> None:
    """Add each texture's PSNR per level against its uncompressed image (``psnr_db``, a list by
    level, ``None`` for an exact level) to ``report`` (from :func:`info_report`)."""
    from vqtex.sim.reports.quality import texture_psnr
    for t, p in zip(report["textures"], texture_psnr(ts, images)):
        t["psnr_db"] = p["psnr_db"]


def _psnr_text(values) -> str:
    return " ".join("exact" if v is None else f"{v:.1f}" for v in values)


def info_text(ts, report) -> str:
    """``info_report`` as the table ``vqtex info`` prints."""
    lines = [f"{'id':>3} {'name':<16} {'size':>10} {'lv':>3} {'color':<9} {'block':<5} {'b':>3} "
             f"{'K':>5} {'base':>8} {'overall':>8}"]
    for t in report["textures"]:
        lines.append(f"{t['id']:>3} {t['name'][:16]:<16} {t['width']:>4}x{t['height']:<5} {t['levels']:>3} "
                     f"{t['color']:<9} {t['block']:<5} {t['index_bits']:>3} {t['codebook_size']:>5} "
                     f"{t['base_rate']:>7.2f}:1 {t['overall_rate']:>6.2f}:1")
    pruned = [t for t in report["textures"] if t["absent_levels"]]
    if pruned or ts.present_blocks is not None:
        lines.append("pruned set (vqtex prune): " + "; ".join(
            f"texture {t['id']} levels {', '.join(map(str, t['absent_levels']))} absent" for t in pruned)
            + ("; only the blocks its frames touched" if ts.present_blocks is not None else ""))
    if any("psnr_db" in t for t in report["textures"]):
        lines.append("PSNR against the uncompressed image, dB, by mip level (0 first):")
        lines += [f"{t['id']:>3} {t['name'][:16]:<16} {_psnr_text(t['psnr_db'])}" for t in report["textures"]]
    lines.append(f"overall compression rate {report['overall_rate']:.2f}:1 "
                 f"({len(ts.codebooks)} codebook(s), index words of {ts.word_bits} bits)")
    return "\n".join(lines)


def cmd_info(args) -> int:
    from vqtex.golden.render.imageio import read_image
    ts = load_set(args.file)
    report = info_report(ts)
    if args.images:
        if len(args.images) != ts.n_textures:
            raise CliError(f"--images: {len(args.images)} image(s) for the file's {ts.n_textures} textures")
        images = [read_image(p) for p in args.images]
        for k, (img, info) in enumerate(zip(images, ts.textures)):
            if img.shape[:2] != (info.height, info.width):
                raise CliError(f"--images: {args.images[k]} is {img.shape[1]}x{img.shape[0]}, texture {k} is "
                               f"{info.width}x{info.height}")
        add_psnr(report, ts, images)
    emit(report, args.json, info_text(ts, report))
    return 0


def add_parser(sub) -> None:
    i = sub.add_parser("info", help="textures, levels, index bits and compression rates of a .vqt")
    add_texture_set(i)
    i.add_argument("--images", nargs="+", metavar="IMAGE",
                   help=with_default("the uncompressed images, one per texture in order: also report PSNR per "
                                     "texture and mip level", "none"))
    add_json(i)
    i.set_defaults(func=cmd_info)
