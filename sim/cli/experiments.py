"""``vqtex experiments table3|table4|table5 [--frames A:B:STEP | --frame-step N] [--json]``: the paper's
tables (see docs/experiments.md). Every table takes the frames it renders the same way.
"""

from __future__ import annotations

import json

from vqtex.sim.bench import experiments

from .common import CliError, add_json, with_default
from .render import parse_frames

__all__ = ["add_parser", "cmd_experiments", "print_table", "DEFAULT_FRAMES"]

#: The frames each table renders by default (Python slices of the scene's frames).
DEFAULT_FRAMES = {"table3": "::10", "table4": "::10", "table5": "::25"}


def print_table(rows: list[dict]) -> None:
    """Rows of a table as aligned text columns."""
    if not rows:
        return
    cols = [c for c in rows[0] if c != "rtl_backend"]
    width = {c: max(len(c), *(len(str(r[c])) for r in rows)) for c in cols}
    print("  ".join(c.ljust(width[c]) for c in cols))
    for r in rows:
        print("  ".join(str(r[c]).ljust(width[c]) for c in cols))


def cmd_experiments(args) -> int:
    from vqtex.golden.render.scene import load_scene
    if args.frame_step is not None:
        if args.frames is not None:
            raise CliError("give --frames or --frame-step, not both")
        if args.frame_step < 1:
            raise CliError(f"--frame-step {args.frame_step} must be at least 1")
        text = f"::{args.frame_step}"
    else:
        text = args.frames or DEFAULT_FRAMES[args.table]
    scene = load_scene("town" if args.table == "table4" else "topspin")
    frames = parse_frames(text, scene.frames)
    if args.table == "table3":
        rows = experiments.table3(frames=frames)
    elif args.table == "table4":
        rows = experiments.table4(frames=frames)
    else:
        rows = experiments.table5(frames=tuple(frames), backend=args.backend)
    if args.json:
        print(json.dumps({"table": args.table, "frames": frames, "rows": rows}, sort_keys=True))
    else:
        print_table(rows)
    return 0


def add_parser(sub) -> None:
    e = sub.add_parser("experiments", help="regenerate the paper's Tables 3, 4 and 5")
    e.add_argument("table", choices=["table3", "table4", "table5"],
                   help="table3: topspin rates and MSE; table4: town's codebook sharing; table5: fetch cost")
    e.add_argument("--frames", default=None,
                   help="frames to render, a Python slice A:B[:STEP] or one number (default "
                        + ", ".join(f"{t} {v}" for t, v in DEFAULT_FRAMES.items()) + ")")
    e.add_argument("--frame-step", type=int, default=None,
                   help=with_default("render every Nth frame: the same as --frames ::N", "see --frames"))
    e.add_argument("--backend", choices=["golden", "cxxrtl", "verilator"], default="golden",
                   help=with_default("where Table 5's cycles come from (golden = the exact cycle model)", "golden"))
    add_json(e)
    e.set_defaults(func=cmd_experiments)
