"""scripts/netlist-levels (docs/area.md, "The timing work, fifth round"): logic levels between
registers of a synth_ecp5 netlist, on a hand-made netlist (no synthesis)."""

import json
import subprocess
import sys
from pathlib import Path

from tests.support import REPO

SCRIPT = str(Path(REPO) / "scripts" / "netlist-levels")


def _cell(kind, ins, outs):
    conns = {**ins, **outs}
    dirs = {**{p: "input" for p in ins}, **{p: "output" for p in outs}}
    return {"type": kind, "port_directions": dirs, "connections": conns}


def _netlist():
    # a -> LUT -> LUT RAM read -> PFUMX -> LUT -> b (3.3 levels); a -> LUT -> c (1 level)
    cells = {
        "a_ff": _cell("TRELLIS_FF", {"DI": [100], "CLK": [99]}, {"Q": [2]}),
        "l1": _cell("LUT4", {"A": [2], "B": [3]}, {"Z": [4]}),
        "ram": _cell("TRELLIS_DPR16X4", {"RAD": [4], "WAD": [5], "DI": [6], "WRE": [7]}, {"DO": [8]}),
        "mx": _cell("PFUMX", {"ALUT": [8], "BLUT": [2], "C0": [3]}, {"Z": [9]}),
        "l2": _cell("LUT4", {"A": [9]}, {"Z": [10]}),
        "b_ff": _cell("TRELLIS_FF", {"DI": [10], "CLK": [99]}, {"Q": [11]}),
        "l3": _cell("LUT4", {"A": [2]}, {"Z": [12]}),
        "c_ff": _cell("TRELLIS_FF", {"DI": [12], "CLK": [99]}, {"Q": [13]}),
    }
    nets = {"a": [2], "sel": [3], "b": [11], "c": [13], "clk": [99], "mem_rd": [8]}
    return {"modules": {"top": {"cells": cells, "netnames": {k: {"bits": v} for k, v in nets.items()}}}}


def _run(*args):
    return subprocess.run([sys.executable, SCRIPT, *args], capture_output=True, text=True)


def test_levels_and_path(tmp_path):
    f = tmp_path / "netlist.json"
    f.write_text(json.dumps(_netlist()))
    r = _run(str(f))
    assert r.returncode == 0, r.stderr
    rows = [line.split() for line in r.stdout.splitlines()]
    assert rows[0][:1] == ["3.3"] and rows[0][1:] == ["a", "->", "[ram]", "->", "b_ff"]
    assert ["1.0", "a", "->", "c_ff"] in rows
    r = _run(str(f), "--path", "b_ff")
    assert r.returncode == 0 and "TRELLIS_DPR16X4" in r.stdout and r.stdout.startswith("3.3 levels into b_ff")


def test_bad_input_exits_2(tmp_path):
    bad = tmp_path / "x.json"
    bad.write_text("not json")
    r = _run(str(bad))
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1
    bad.write_text(json.dumps(_netlist()))
    r = _run(str(bad), "--module", "nope")
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1


def test_fanout_and_depth(tmp_path):
    """``--fanout``: the nets of most loads (cell inputs), their drivers; ``--depth``: dotted names
    kept whole (``unit.x`` and ``unit.y`` apart, where depth 1 makes both ``unit``)."""
    nl = _netlist()
    cells = nl["modules"]["top"]["cells"]
    # a fourth load on a (bit 2): a -> LUT -> d_ff; then a has 4 loads (l1, mx, l3, l4), sel 2
    cells["l4"] = _cell("LUT4", {"A": [2]}, {"Z": [14]})
    cells["d_ff"] = _cell("TRELLIS_FF", {"DI": [14], "CLK": [99]}, {"Q": [15]})
    nl["modules"]["top"]["netnames"].update({"unit.x": {"bits": [12]}, "unit.y": {"bits": [14]}})
    cells["unit.x_TRELLIS_FF_Q"] = cells.pop("c_ff")      # (Yosys names a cell after its net and type)
    cells["unit.y_TRELLIS_FF_Q"] = cells.pop("d_ff")
    f = tmp_path / "netlist.json"
    f.write_text(json.dumps(nl))
    r = _run(str(f), "--fanout", "2")
    assert r.returncode == 0, r.stderr
    rows = [line.split() for line in r.stdout.splitlines()]
    assert len(rows) == 2 and rows[0] == ["4", "TRELLIS_FF", "a"], rows     # (clk and sel have no driver)
    ends = [line.split()[-1] for line in _run(str(f), "--depth", "99").stdout.splitlines()]
    assert "unit.x" in ends and "unit.y" in ends
    ends = [line.split()[-1] for line in _run(str(f)).stdout.splitlines()]
    assert "unit.x" not in ends and "unit" in ends
