"""The ``vqtex`` command line (see ``docs/usage.md``).

Every command that reports takes ``--json`` and then prints exactly one JSON object on stdout.
Bad input ends with a one-line error on stderr and exit status 2, never a traceback and never a
partly written output file (outputs are written to a temporary file and renamed).
"""

from __future__ import annotations

import argparse
import io
import json
import os
import sys
import tempfile

import numpy as np

__all__ = ["main", "CliError"]


class CliError(Exception):
    """A user error: printed as one line, exit status 2."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):            # one line, exit 2 (argparse would print the usage too)
        raise CliError(f"{self.prog}: {message}")


def _block(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"block {text!r} is not WxH (e.g. 4x4)") from None
    return w, h


def _emit(obj: dict, as_json: bool, text: str) -> None:
    if as_json:
        print(json.dumps(obj, sort_keys=True))
    else:
        print(text)


def _check_output(path: str) -> str:
    """The folder of an output file; a CliError if it does not exist."""
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise CliError(f"output folder {folder} does not exist")
    return folder


def _atomic_write(path: str, write) -> None:
    """Call ``write(tmp_path)`` then rename over ``path``; never leave a partial file."""
    folder = _check_output(path)
    suffix = os.path.splitext(path)[1]
    fd, tmp = tempfile.mkstemp(prefix=".vqtex-", suffix=suffix, dir=folder)
    os.close(fd)
    try:
        write(tmp)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def _write_bytes(path: str, data: bytes) -> None:
    def write(tmp):
        with open(tmp, "wb") as f:
            f.write(data)
    _atomic_write(path, write)


def _write_json(path: str, obj) -> None:
    _write_bytes(path, json.dumps(obj, indent=2, sort_keys=True).encode())


def _load_set(path: str):
    from golden.format import TextureSet
    return TextureSet.load(path)


# ---------------------------------------------------------------------------------------------
# encode / info / decode

def cmd_encode(args) -> int:
    from golden.encode import encode
    from golden.render.imageio import read_image
    images = [read_image(p) for p in args.images]
    names = [os.path.splitext(os.path.basename(p))[0] for p in args.images]
    ts = encode(images, block=args.block, codebook_size=args.codebook_size, color=args.color,
                index_bits=args.index_bits, mipmaps=args.mipmaps, encoder=args.encoder, seed=args.seed,
                mip_training=args.mip_training, names=names, word_bits=args.word_bits)
    ts.save(args.output)
    report = _info(ts)
    _emit(report, args.json, _info_text(ts, report) + f"\nwrote {args.output}")
    return 0


def _info(ts) -> dict:
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


def _info_text(ts, report) -> str:
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
    ts = _load_set(args.file)
    report = _info(ts)
    _emit(report, args.json, _info_text(ts, report))
    return 0


def cmd_decode(args) -> int:
    from golden.fetch import decode
    from golden.render.imageio import write_image
    ts = _load_set(args.file)
    if not 0 <= args.texture < ts.n_textures:
        raise CliError(f"texture {args.texture} does not exist (the file has {ts.n_textures})")
    levels = ts.textures[args.texture].levels
    if not 0 <= args.level < levels:
        raise CliError(f"texture {args.texture} has no level {args.level} (it has {levels})")
    img = decode(ts, args.texture, args.level)
    channels = {"rgb": 3, "yuv411": 3, "rgba": 4, "intensity": 1}[ts.textures[args.texture].color]
    _check_output(args.output)
    write_image(args.output, np.ascontiguousarray(img[..., :channels]))          # atomic itself
    h, w = img.shape[:2]
    _emit({"texture": args.texture, "level": args.level, "width": w, "height": h, "output": args.output},
          args.json, f"wrote {args.output} ({w}x{h}, texture {args.texture} level {args.level})")
    return 0


# ---------------------------------------------------------------------------------------------
# sim

def _read_requests(path: str) -> np.ndarray:
    if not os.path.isfile(path):
        raise CliError(f"{path}: no such file")
    try:
        if path.endswith(".npy"):
            req = np.load(path, allow_pickle=False)
        else:
            req = np.loadtxt(path, delimiter=",", dtype=np.int64, ndmin=2,
                             skiprows=_csv_header_rows(path))
    except (ValueError, OSError, EOFError) as e:
        raise CliError(f"{path}: cannot read requests ({str(e).splitlines()[0] if str(e) else type(e).__name__})") from None
    if req.ndim != 2 or req.shape[1] != 4 or not np.issubdtype(req.dtype, np.integer):
        raise CliError(f"{path}: requests must be an integer array of shape (N, 4): texture, level, i, j")
    return req.astype(np.int64)


def _csv_header_rows(path: str) -> int:
    with open(path) as f:
        first = f.readline()
    return 1 if any(c.isalpha() for c in first) else 0


def cmd_sim(args) -> int:
    from golden.fetch import check_requests
    ts = _load_set(args.file)
    req = _read_requests(args.requests)
    if len(req) == 0:
        raise CliError(f"{args.requests}: no requests")
    check_requests(ts, req[:, 0], req[:, 1], req[:, 2], req[:, 3])
    if not 0.0 <= args.stall < 1.0:
        raise CliError(f"--stall {args.stall} must be in [0, 1)")
    from sim.backend import simulate
    res = simulate(ts, req, backend=args.backend, stall=args.stall, seed=args.seed, one_port=args.one_port)
    buf = io.BytesIO()
    np.save(buf, res.responses.astype(np.uint8))
    _write_bytes(args.output, buf.getvalue())
    from sim.report import cycle_report, cycle_text
    report = cycle_report(res, backend=args.backend, one_port=args.one_port, stall=args.stall)
    if args.plot:
        from sim.report import cycle_plot
        _check_output(args.plot)
        cycle_plot(report, args.plot)                                   # atomic (write_image)
    _emit(report, args.json, cycle_text(report) + f"\nwrote {args.output}")
    return 0


# ---------------------------------------------------------------------------------------------

def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="vqtex", description="VQ texture compression and the texel-fetch hardware model")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    e = sub.add_parser("encode", help="compress images into a .vqt texture set (one shared codebook)")
    e.add_argument("images", nargs="+")
    e.add_argument("-o", "--output", required=True)
    e.add_argument("--block", type=_block, default=(4, 4), help="block WxH, powers of two 1..8 (default 4x4)")
    e.add_argument("--codebook-size", "-k", type=int, default=256, help="codewords, 2..4096 (default 256)")
    e.add_argument("--color", choices=["rgb", "rgba", "intensity", "yuv411"], default="rgb")
    e.add_argument("--index-bits", type=int, default=None, help="index width b, 1..16 (default ceil(log2 K))")
    e.add_argument("--mipmaps", action="store_true", help="mip pyramid with extended codewords")
    e.add_argument("--mip-training", choices=["average", "joint"], default="average",
                   help="extended codewords: averages of level 0 (paper) or trained on all sub-levels")
    e.add_argument("--encoder", choices=["gla", "tsvq"], default="gla")
    e.add_argument("--seed", type=int, default=0)
    e.add_argument("--word-bits", type=int, choices=[16, 32, 64], default=32)
    e.add_argument("--json", action="store_true")
    e.set_defaults(func=cmd_encode)

    i = sub.add_parser("info", help="textures, levels, index bits and compression rates of a .vqt")
    i.add_argument("file")
    i.add_argument("--json", action="store_true")
    i.set_defaults(func=cmd_info)

    d = sub.add_parser("decode", help="decode one level of one texture to an image")
    d.add_argument("file")
    d.add_argument("-o", "--output", required=True)
    d.add_argument("--texture", type=int, default=0)
    d.add_argument("--level", type=int, default=0)
    d.add_argument("--json", action="store_true")
    d.set_defaults(func=cmd_decode)

    s = sub.add_parser("sim", help="trace-driven simulation of the texel-fetch unit")
    s.add_argument("file")
    s.add_argument("requests", help=".npy (N, 4) int array or CSV: texture, level, i, j")
    s.add_argument("-o", "--output", required=True, help=".npy (N, 4) uint8 RGBA responses")
    s.add_argument("--backend", choices=["golden", "pysim", "cxxrtl", "verilator"], default="golden")
    s.add_argument("--stall", type=float, default=0.0, help="probability the output's ready is low")
    s.add_argument("--seed", type=int, default=0)
    s.add_argument("--one-port", action="store_true", help="one-port index memory (paper's penalty)")
    s.add_argument("--plot", help="also draw where the cycles went (PNG)")
    s.add_argument("--json", action="store_true")
    s.set_defaults(func=cmd_sim)

    for extra in _extra_commands():
        extra(sub)
    return p


def _extra_commands():
    """Commands that live in their own modules (render, demo, export, report, bench, experiments)."""
    from sim import cmd_bench, cmd_export, cmd_render, cmd_report, experiments
    return [m.add_parser for m in (cmd_render, cmd_export, cmd_report, cmd_bench, experiments)]


def _user_errors():
    from golden.encode import EncodeError
    from golden.fetch import RequestError
    from golden.format import FormatError
    from golden.render.scene import SceneError
    return (CliError, FormatError, EncodeError, RequestError, SceneError, OSError)


def main(argv=None) -> int:
    try:
        args = build_parser().parse_args(argv)
        return args.func(args) or 0
    except _user_errors() as e:
        msg = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        print(f"vqtex: error: {msg}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("vqtex: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
