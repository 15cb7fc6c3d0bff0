"""``vqtex sim FILE.vqt REQUESTS -o RESPONSES.npy``: trace-driven simulation of the texel-fetch unit."""

from __future__ import annotations

import io
import os

import numpy as np

from .common import CliError, check_output, emit, load_set, write_bytes

__all__ = ["add_parser", "cmd_sim", "read_requests"]


def read_requests(path: str) -> np.ndarray:
    """A request file (.npy without pickles, or CSV with an optional header row) as int64 (N, 4)."""
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
    from vqtex.golden.fetch import check_requests
    ts = load_set(args.file)
    req = read_requests(args.requests)
    if len(req) == 0:
        raise CliError(f"{args.requests}: no requests")
    check_requests(ts, req[:, 0], req[:, 1], req[:, 2], req[:, 3])
    if not 0.0 <= args.stall < 1.0:
        raise CliError(f"--stall {args.stall} must be in [0, 1)")
    from vqtex.sim.backends.interface import simulate
    res = simulate(ts, req, backend=args.backend, stall=args.stall, seed=args.seed, one_port=args.one_port)
    buf = io.BytesIO()
    np.save(buf, res.responses.astype(np.uint8))
    write_bytes(args.output, buf.getvalue())
    from vqtex.sim.reports.cycles import cycle_report, cycle_text
    report = cycle_report(res, backend=args.backend, one_port=args.one_port, stall=args.stall)
    if args.plot:
        from vqtex.sim.reports.cycles import cycle_plot
        check_output(args.plot)
        cycle_plot(report, args.plot)                                   # atomic (write_image)
    emit(report, args.json, cycle_text(report) + f"\nwrote {args.output}")
    return 0


def add_parser(sub) -> None:
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
