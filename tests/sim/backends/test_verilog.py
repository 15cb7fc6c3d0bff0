"""``vqtex export``: readable ports, no simulation-only constructs, Verilator lint clean (with the
documented waivers), Icarus Verilog four-state run with no X after reset and golden responses."""

import json
import os
import re

import numpy as np
import pytest

from tests.support import back_to_back_requests, need, random_requests, texture_sets
from vqtex.golden.fetch import fetch
from vqtex.sim.backends.interface import simulate
from vqtex.sim.cli import main


@pytest.fixture(scope="module")
def sets():
    return texture_sets()


@pytest.fixture(scope="module")
def mixed_file(sets, tmp_path_factory):
    path = tmp_path_factory.mktemp("vqt") / "mixed.vqt"
    sets["mixed"].save(path)
    return str(path)


def test_export_cli_ports_and_constructs(mixed_file, tmp_path, capsys):
    out = tmp_path / "tf.v"
    assert main(["export", mixed_file, "-o", str(out), "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["module"] == "texel_fetch" and rep["latency"] == 15 and rep["dialect"] == "sv"
    for port in ("i_valid", "i_ready", "i_texture", "i_level", "i_i", "i_j", "i_tag",
                 "o_valid", "o_ready", "o_r", "o_g", "o_b", "o_a", "o_tag", "straddle", "stall_one_port"):
        assert port in rep["ports"], port
    text = out.read_text()
    header = text[text.index("module texel_fetch("):].split(";")[0]
    assert "i__payload" not in header and "o_r" in header and "clk" in header and "rst" in header
    # No simulation-only constructs: no system tasks, no delays; initial blocks only fill memories.
    assert not re.search(r"\$(display|finish|fatal|stop|readmem|write|monitor|random)", text)
    assert not re.search(r"#\s*\d", text)
    # sv dialect: registers as always_ff with their enable and reset, combinational logic as assign
    # statements (no always_comb next-state blocks: Verilator re-evaluates them on every input change)
    assert "always_ff" in text and "always @*" not in text and "always_comb" not in text
    assert re.search(r"always_ff @\(posedge clk\)\s*\n?\s*if \(rst\) \S+ <= [^;]+;\s*else if \(", text)
    blocks = re.findall(r"initial begin\n(.*?)\n\s*end", text, re.S)
    assert blocks and all(re.fullmatch(r"(\s*[\\\w$.]+\s*\[\d+\] = \d+'[hdb][0-9a-fA-F_]+;\s*)+", b) for b in blocks)


def test_export_errors_one_line(mixed_file, tmp_path, capsys):
    trunc = tmp_path / "t.vqt"
    trunc.write_bytes(open(mixed_file, "rb").read()[:200])
    cases = [
        (["export", str(tmp_path / "missing.vqt"), "-o", str(tmp_path / "x.v")], "cannot read"),
        (["export", str(trunc), "-o", str(tmp_path / "x.v")], "truncated|checksum|short"),
        (["export", mixed_file, "-o", str(tmp_path / "nodir" / "x.v")], "does not exist"),
        (["export", mixed_file, "-o", str(tmp_path / "x.v"), "--name", "9bad"], "identifier"),
        (["export", mixed_file], "required"),
    ]
    for argv, msg in cases:
        capsys.readouterr()
        code = main(argv)
        err = capsys.readouterr().err
        assert code == 2 and err.count("\n") == 1 and err.startswith("vqtex: error:"), (argv, err)
        assert re.search(msg, err), (argv, err)
    assert not (tmp_path / "x.v").exists()
    assert not [p for p in os.listdir(tmp_path) if p.startswith(".vqtex-")]


@pytest.mark.parametrize("one_port,dialect", [(False, "sv"), (True, "sv"), (False, "v2005")])
def test_verilator_lint_clean(mixed_file, tmp_path, one_port, dialect, capsys):
    need("verilator")
    argv = ["export", mixed_file, "-o", str(tmp_path / "tf.v"), "--lint", "--dialect", dialect]
    code = main(argv + (["--one-port"] if one_port else []))
    assert code == 0, capsys.readouterr().err


@pytest.mark.parametrize("name,one_port,stall", [("mixed", False, 0.0), ("mixed", True, 0.4), ("w16", False, 0.3)])
def test_icarus_no_x_and_golden(sets, name, one_port, stall):
    need("iverilog", "vvp")
    from vqtex.sim.backends.verilog import run_icarus
    ts = sets[name]
    req = np.concatenate([back_to_back_requests(ts, limit=120), random_requests(ts, 120, seed=4)])
    res = run_icarus(ts, req, stall=stall, seed=2, one_port=one_port)
    assert res["xerrors"] == 0 and res["unknown"] == 0
    assert np.array_equal(res["responses"], fetch(ts, *req.T))
    assert np.array_equal(res["tags"], np.arange(len(req)) & 0xFF)
    assert res["cycles"] == simulate(ts, req, stall=stall, seed=2, one_port=one_port).cycles


def test_verilator_build_has_no_warnings(sets):
    """The Verilator backend's build (lint and style rules off, the lint test above covers them)
    reports nothing: no UNOPTFLAT or other scheduling warning that would cost speed (docs/simulation.md,
    Verilator section: they are fixed in the hardware or the export, not waived)."""
    need("verilator")
    from vqtex.sim.backends.verilator import build_verilator
    build = build_verilator(sets["mixed"])
    with open(os.path.join(os.path.dirname(build.library), "build.log")) as f:
        log = f.read()
    assert "%Warning" not in log, [ln for ln in log.splitlines() if "%Warning" in ln][:5]


def test_verilator_harness_wraps_every_port(mixed_file, tmp_path, capsys):
    """The Verilator backend's harness (one eval() per cycle) around the exported unit: its ports are
    the unit's with clk replaced by tick, at the unit's widths, and every output of the unit is
    registered into the harness output of the same name at the unit's clock edge."""
    from vqtex.sim.backends.verilator import HARNESS_NAME, harness_verilog, top_ports
    out = tmp_path / "tf.v"
    assert main(["export", mixed_file, "-o", str(out), "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    text = out.read_text()
    ports = top_ports(text, "texel_fetch")
    assert {n: w for _, n, w in ports} == {**rep["ports"], "clk": 1, "rst": 1}    # the export's own report
    harness = harness_verilog(text, "texel_fetch")
    assert top_ports(harness, HARNESS_NAME) == [("input", "tick", 1)] + [
        (d, n, w) for d, n, w in sorted(ports, key=lambda p: p[0] != "input") if n != "clk"]
    for d, n, _ in ports:
        if d == "output":
            assert f"    {n} <= unit_{n};" in harness, n
    assert "wire clk = tick ^ phase;" in harness and "phase <= tick;" in harness
