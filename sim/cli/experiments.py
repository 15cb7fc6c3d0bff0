"""``vqtex experiments table3|table4|table5|hardware [--frames A:B:STEP | --frame-step N] [--json]``: the
paper's tables and the hardware's cycles against error (see docs/experiments.md). Every table takes
the frames it renders the same way; tables 3 and 4 and ``hardware`` run their rows as a sweep
(``--scheduler``, ``--workers``).
"""

from __future__ import annotations

import json

from vqtex.sim.bench.scenes import experiments, hardware_tradeoff

from . import limits
from .common import CliError, Outputs, add_json, add_sweep_options, number_help, resolve, sweep_options, with_default
from .render import parse_frames

__all__ = ["add_parser", "cmd_experiments", "print_table", "DEFAULT_FRAMES", "SCENES"]

#: The frames each table renders by default (Python slices of the scene's frames).
DEFAULT_FRAMES = {"table3": "::5", "table4": "::1", "table5": "::25", "hardware": "::10"}
#: hardware renders each scene's every Nth frame (its scenes differ in length), so it takes a step only.
#: The scene each table renders (hardware: both).
SCENES = {"table3": "town-paper", "table4": "topspin-paper", "table5": "topspin", "hardware": "topspin-paper"}
#: Columns print_table leaves out of the text table (they are in --json).
HIDDEN = ("rtl_backend", "codebooks")


def print_table(rows: list[dict]) -> None:
    """Rows of a table as aligned text columns."""
    if not rows:
        return
    cols = [c for c in rows[0] if c not in HIDDEN]
    text = [{c: "-" if r[c] is None else str(r[c]) for c in cols} for r in rows]
    width = {c: max(len(c), *(len(t[c]) for t in text)) for c in cols}
    print("  ".join(c.ljust(width[c]) for c in cols))
    for t in text:
        print("  ".join(t[c].ljust(width[c]) for c in cols))


def cmd_experiments(args) -> int:
    from vqtex.golden.render.scene import load_scene
    if args.frame_step is not None:
        if args.frames is not None:
            raise CliError("give --frames or --frame-step, not both")
        text = f"::{args.frame_step}"
    else:
        text = args.frames or DEFAULT_FRAMES[args.table]
    if args.plot is not None and args.table != "hardware":
        raise CliError("--plot is for the hardware experiment")
    _options_that_apply(args)
    if args.table == "hardware" and not text.startswith("::"):
        raise CliError("hardware renders every Nth frame of each scene: give --frame-step N (or --frames ::N)")
    scene = load_scene(args.scene or SCENES[args.table])
    frames = parse_frames(text, scene.frames)
    sweep = sweep_options(args)
    backend = args.backend or ("cxxrtl" if args.table == "hardware" else "golden")
    extra = {}
    if args.table == "table3":
        rows = experiments.table3(frames=frames, own=not args.paper_only, sweep=sweep, scene=args.scene)
    elif args.table == "table4":
        rows = experiments.table4(frames=frames, own=not args.paper_only, sweep=sweep, scene=args.scene)
    elif args.table == "table5":
        rows = experiments.table5(frames=tuple(frames), backend=backend, scene=args.scene or "topspin")
    else:
        with Outputs() as outputs:
            plot = outputs.add(args.plot, (".png",), "the plot") if args.plot is not None else None
            if plot is not None:
                hardware_tradeoff.check_plotting()          # before the work: one line if matplotlib is missing
            step = frames[1] - frames[0] if len(frames) > 1 else scene.frames
            scenes = (args.scene,) if args.scene else hardware_tradeoff.SCENES
            rows = hardware_tradeoff.sweep(frame_step=step, backend=backend, sweep=sweep, scenes=scenes,
                                           stream=args.requests)
            if plot is not None:
                hardware_tradeoff.plot(rows, outputs.path(plot))
                extra["plot"] = args.plot
        extra["frame_step"] = step
    if args.json:
        head = {"table": args.table} if args.table == "hardware" else {"table": args.table, "frames": frames}
        print(json.dumps({**head, "rows": rows, **extra}, sort_keys=True))
    else:
        print_table(rows)
    return 0


def _options_that_apply(args) -> None:
    """Refuse an option given to a table it changes nothing in, whatever its value: ``--backend``
    (table5, hardware), ``--requests`` (hardware), ``--paper-only`` (tables 3 and 4), ``--scheduler``
    and ``--workers`` (the sweeps: tables 3 and 4, hardware)."""
    t = args.table
    resolve(args, "backend", "cxxrtl" if t == "hardware" else "golden", t in ("table5", "hardware"),
            "is where the cycles of table5 and hardware come from: tables 3 and 4 count no cycles")
    resolve(args, "requests", "fixed", t == "hardware", "is the hardware experiment's request stream")
    if args.paper_only and t not in ("table3", "table4"):
        raise CliError("--paper-only is for tables 3 and 4 (the paper's rows and ours)")
    for opt in ("scheduler", "workers"):
        if getattr(args, opt) is not None and t == "table5":
            raise CliError(f"--{opt} is for the sweeps (table3, table4, hardware): table5 runs none")


def add_parser(sub) -> None:
    e = sub.add_parser("experiments", help="regenerate the paper's Tables 3, 4 and 5, and the hardware's "
                                           "cycles against error")
    e.add_argument("table", choices=["table3", "table4", "table5", "hardware"],
                   help="table3: the town's rates and frame MSE; table4: topspin's; table5: fetch cost; "
                        "hardware: frame error against cycles and memory bits on the RTL")
    e.add_argument("--frames", default=None,
                   help="frames to render, a Python slice A:B[:STEP] or one number (default "
                        + ", ".join(f"{t} {v}" for t, v in DEFAULT_FRAMES.items()) + ")")
    e.add_argument("--frame-step", type=limits.FRAME_STEP, default=None,
                   help=number_help("render every Nth frame: the same as --frames ::N", limits.FRAME_STEP,
                                    "see --frames"))
    e.add_argument("--backend", choices=["golden", "cxxrtl", "verilator"], default=None,
                   help=with_default("where the cycles of table5 and hardware come from (golden = the exact "
                                     "cycle model, which every RTL backend matches)",
                                     "golden for table5, cxxrtl for hardware"))
    e.add_argument("--scene", default=None,
                   help=with_default("the scene to render instead (a built-in name or a scene file with the "
                                     "same texture groups: topspin's floor, marble, top; the town's signs, "
                                     "roads, other, grey, cutouts)",
                                     ", ".join(f"{t} {v}" for t, v in SCENES.items() if t != "hardware")
                                     + ", hardware both paper scenes"))
    e.add_argument("--requests", choices=["fixed", "sparse"], default=None,
                   help=with_default("hardware: the request stream, fixed (eight requests a trilinear pixel, as "
                                     "the paper's renderer) or sparse (the requests that cannot change a pixel "
                                     "left out: the same frames in fewer cycles)", "fixed"))
    e.add_argument("--paper-only", action="store_true",
                   help="tables 3 and 4: only the paper's rows, not ours below them")
    e.add_argument("--plot", metavar="FILE.png", default=None,
                   help=with_default("hardware: write the plot of frame error against cycles and memory bits "
                                     "(needs matplotlib, the plot extra)", "no plot"))
    add_sweep_options(e)
    add_json(e)
    e.set_defaults(func=cmd_experiments)
