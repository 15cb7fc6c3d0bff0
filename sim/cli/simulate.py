"""``vqtex sim FILE.vqt REQUESTS -o RESPONSES.npy``: trace-driven simulation of the texel-fetch unit.

``vqtex sim FILE.vqt PIXELS -o COLORS.npy --filter-lanes N --memory external [--unit loadable --geometry
NAME]``: the texture filter through the memory system (``hw.memory.filter``, docs/memory.md) on a pixel
trace: PIXELS is a request file (``golden.requests``, ``.npy`` or CSV) of seven columns,
``golden.requests.PIXEL_COLUMNS`` (texture, s, t, lod, mode, address_s, address_t; ``s`` and ``t``
with ``sim.backends.filter.default_frac(ts)`` fractional bits, the filter's own); the colours out
are (N, 4) uint8; the report is :func:`sim.reports.cycles.filter_cycle_report`. The on-chip filter
is not offered here (``vqtex render --filter-in-rtl`` runs it).
"""

from __future__ import annotations

import io
import os

import numpy as np

from .common import (CliError, Outputs, add_backend, add_hardware_options, add_json, add_memory_options,
                     add_texture_set, add_unit, emit, load_set, memory_config, resolve, stall_seed, unit_geometry,
                     warn_slow, with_default, write_bytes)

__all__ = ["add_parser", "cmd_sim", "read_requests", "run_trace", "plot_output", "add_trace_arguments"]


def read_requests(path: str) -> np.ndarray:
    """A request file (.npy without pickles, or CSV with an optional header row) as int64 (N, 4), N >= 1:
    :func:`vqtex.golden.requests.read_request_file` (its RequestError is one line naming the file),
    and at least one request."""
    from vqtex.golden.requests import read_request_file
    if not os.path.isfile(path):
        raise CliError(f"{path}: no such file")
    req = read_request_file(path)
    if len(req) == 0:
        raise CliError(f"{path}: no requests (the file is empty or holds only a header)")
    return req


def plot_output(outs, path):
    """Register ``--plot`` (a .png) in ``outs`` and check matplotlib is there, before any work;
    None when no plot is asked for."""
    if not path:
        return None
    path = outs.add(path, (".png",), "the cycle plot")
    from vqtex.sim.reports.plotting import require
    require()
    return path


def run_trace(args):
    """Load ``args.file`` and ``args.requests``, check them and simulate on ``args.backend``;
    returns (SimResult, cycle report)."""
    from vqtex.golden.fetch import check_requests
    from vqtex.sim.backends.interface import simulate
    from vqtex.sim.reports.cycles import cycle_report
    args.seed = stall_seed(args)
    memory = memory_config(args)
    if args.filter_lanes is not None:
        return _run_filter_trace(args, memory)
    if memory is not None:
        if args.one_port or args.unit not in (None, "loadable"):
            bad = "--one-port" if args.one_port else f"--unit {args.unit}"
            raise CliError(f"--memory external is the specialised baked unit behind caches or the loadable one "
                           f"(--unit loadable): no {bad}")
    resolve(args, "unit", "specialised", args.backend != "golden" or (memory is not None and args.unit == "loadable"),
            "chooses the RTL unit: it does not apply to --backend golden (the cycle model)")
    ts = load_set(args.file)
    geometry = unit_geometry(args, ts, args.file)
    req = read_requests(args.requests)
    check_requests(ts, req[:, 0], req[:, 1], req[:, 2], req[:, 3])
    warn_slow(args.backend, len(req))
    res = simulate(ts, req, backend=args.backend, stall=args.stall, seed=args.seed, one_port=args.one_port,
                   specialise=args.unit == "specialised", geometry=geometry, memory=memory)
    extra = {"unit": args.unit}
    if res.memory is not None:
        extra.update(memory=res.memory)
    if geometry is not None:
        extra.update(geometry=args.geometry or "the set's own", load_cycles=res.load_cycles)
    return res, cycle_report(res, backend=args.backend, one_port=args.one_port, stall=args.stall, extra=extra)


def _run_filter_trace(args, memory):
    """``run_trace`` for ``--filter-lanes``: the texture filter through memory on a pixel trace;
    returns (FilterResult, its cycle report)."""
    from vqtex.golden.requests import PIXEL_COLUMNS, read_request_file
    from vqtex.sim.backends.filter import check_pixels, default_frac
    from vqtex.sim.backends.filter_memory import simulate_cached_filter
    from vqtex.sim.reports.cycles import filter_cycle_report
    if memory is None:
        raise CliError("--filter-lanes needs --memory external: vqtex sim runs the texture filter through memory; "
                       "the on-chip filter runs in vqtex render --filter-in-rtl")
    if args.one_port or args.unit == "full":
        bad = "--one-port" if args.one_port else f"--unit {args.unit}"
        raise CliError(f"--filter-lanes: the filter's lanes are specialised baked units or loadable ones (--unit "
                       f"loadable): no {bad}")
    resolve(args, "unit", "specialised", args.backend != "golden" or args.unit == "loadable",
            "chooses the RTL lanes: it does not apply to --backend golden (the cycle model)")
    ts = load_set(args.file)
    geometry = unit_geometry(args, ts, args.file)
    if not os.path.isfile(args.requests):
        raise CliError(f"{args.requests}: no such file")
    rows = read_request_file(args.requests, PIXEL_COLUMNS)
    if len(rows) == 0:
        raise CliError(f"{args.requests}: no pixels (the file is empty or holds only a header)")
    frac = default_frac(ts)
    try:
        pixels = check_pixels(ts, {f: rows[:, k] for k, f in enumerate(PIXEL_COLUMNS)}, frac)
    except ValueError as e:
        raise CliError(f"{args.requests}: {e}") from None
    warn_slow(args.backend, len(rows) * 8 // args.filter_lanes)
    res = simulate_cached_filter(ts, pixels, memory, backend=args.backend, lanes=args.filter_lanes, frac=frac,
                                 stall=args.stall, seed=args.seed, geometry=geometry)
    extra = {"unit": args.unit, "frac": frac}
    if geometry is not None:
        extra.update(geometry=args.geometry or "the set's own", load_cycles=res.load_cycles)
    return res, filter_cycle_report(res, backend=args.backend, stall=args.stall, extra=extra)


def cmd_sim(args) -> int:
    from vqtex.sim.reports.cycles import cycle_plot, cycle_text
    with Outputs() as outs:
        out = outs.add(args.output, (".npy",), "the responses (an (N, 4) uint8 array; the colours with --filter-lanes)")
        plot = plot_output(outs, args.plot)
        res, report = run_trace(args)
        buf = io.BytesIO()
        np.save(buf, (res.colors if args.filter_lanes is not None else res.responses).astype(np.uint8))
        write_bytes(outs.path(out), buf.getvalue())
        if plot:
            cycle_plot(report, outs.path(plot))
    emit(report, args.json, cycle_text(report) + f"\nwrote {args.output}" + (f" and {args.plot}" if plot else ""))
    return 0


def add_trace_arguments(s) -> None:
    """The texture set, the request file, the backend and the unit's options (sim, report cycles)."""
    add_texture_set(s)
    s.add_argument("requests", metavar="REQUESTS",
                   help=".npy (N, 4) integer array or CSV (header line allowed): texture, level, i, j (with "
                        "--filter-lanes: pixels, seven columns)")
    add_backend(s, ["golden", "pysim", "cxxrtl", "verilator"], "golden")
    add_hardware_options(s)
    add_unit(s)
    add_memory_options(s)
    s.add_argument("--filter-lanes", type=int, choices=[1, 2, 4, 8], default=None,
                   help=with_default("simulate the texture filter through memory (needs --memory external; "
                                     "docs/memory.md) with this many lanes: REQUESTS is then a pixel trace, .npy "
                                     "(N, 7) or CSV of texture, s, t, lod, mode, address_s, address_t (s and t "
                                     "with the set's fractional bits), the output its colours", "the texel-fetch unit"))


def add_parser(sub) -> None:
    s = sub.add_parser("sim", help="trace-driven simulation of the texel-fetch unit")
    add_trace_arguments(s)
    s.add_argument("-o", "--output", required=True, help="the responses to write: .npy (N, 4) uint8 RGBA")
    s.add_argument("--plot", metavar="PLOT.png",
                   help=with_default("also draw where the cycles went, a PNG (needs the plot extra)", "none"))
    add_json(s)
    s.set_defaults(func=cmd_sim)
