"""``vqtex experiments table3|table4|table5 [--json]``: the paper's tables (see docs/experiments.md)."""

from __future__ import annotations

import json

from vqtex.sim.bench import experiments

__all__ = ["add_parser", "cmd_experiments", "print_table"]


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
    if args.table == "table3":
        rows = experiments.table3(frame_step=args.frame_step)
    elif args.table == "table4":
        rows = experiments.table4(frame_step=args.frame_step)
    else:
        rows = experiments.table5(backend=args.backend)
    if args.json:
        print(json.dumps({"table": args.table, "rows": rows}, sort_keys=True))
    else:
        print_table(rows)
    return 0


def add_parser(sub) -> None:
    e = sub.add_parser("experiments", help="regenerate the paper's Tables 3, 4 and 5")
    e.add_argument("table", choices=["table3", "table4", "table5"])
    e.add_argument("--frame-step", type=int, default=10, help="render every Nth frame (default 10)")
    e.add_argument("--backend", choices=["golden", "cxxrtl", "verilator"], default="golden",
                   help="where Table 5's cycles come from (golden = the exact cycle model)")
    e.add_argument("--json", action="store_true")
    e.set_defaults(func=cmd_experiments)
