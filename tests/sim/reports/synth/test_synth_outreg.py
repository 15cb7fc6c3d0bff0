"""sim.reports.synth.outreg: the fabric register behind a DP16KD read port moved into its output
register (``--bram-outreg``) only when that is the same circuit: on small hand-made netlists, no
tools; and once through Yosys and nextpnr (the ``paper`` preset's index reader alone, placed only;
needs the ``synth`` extra, as tests/sim/reports/synth/test_synth_stage.py)."""

from __future__ import annotations

import copy
import json

import pytest

from vqtex.sim.reports.synth.outreg import absorb_output_registers
from tests.support import need_synth_tools as _need_tools, run_cli as _run

CLK, EN, RST = 2, 3, 4


def _netlist(bits=2, *, ce=("CE", EN), lsr=RST, ram_rst=RST, extra_load=False, clk=CLK):
    """A DP16KD whose port B's ``bits`` outputs each feed a TRELLIS_FF (nets 100+k -> Q 200+k)."""
    ram = {"type": "DP16KD", "parameters": {"REGMODE_A": "NOREG", "REGMODE_B": "NOREG", "GSR": "DISABLED",
                                            "RESETMODE": "SYNC"},
           "port_directions": {**{f"DOB{k}": "output" for k in range(18)}, "CLKB": "input", "RSTB": "input",
                               "OCEB": "input", "CEB": "input"},
           "connections": {**{f"DOB{k}": [100 + k] for k in range(18)}, "CLKB": [CLK], "RSTB": [ram_rst],
                           "OCEB": ["1"], "CEB": [EN]}}
    cells = {"ram": ram}
    for k in range(bits):
        cells[f"ff{k}"] = {
            "type": "TRELLIS_FF",
            "parameters": {"CEMUX": ce[0], "CLKMUX": "CLK", "GSR": "DISABLED", "LSRMUX": "LSR", "REGSET": "RESET",
                           "SRMODE": "LSR_OVER_CE"},
            "port_directions": {"CLK": "input", "CE": "input", "LSR": "input", "DI": "input", "Q": "output"},
            "connections": {"CLK": [clk if k == 0 else CLK], "CE": [ce[1]], "LSR": [lsr], "DI": [100 + k],
                            "Q": [200 + k]}}
    if extra_load:
        cells["lut"] = {"type": "LUT4", "parameters": {}, "port_directions": {"A": "input", "Z": "output"},
                        "connections": {"A": [100], "Z": [300]}}
    return {"modules": {"unit": {"ports": {}, "cells": cells}}}


def test_register_moved_into_the_block_ram():
    n = _netlist()
    assert absorb_output_registers(n) == {"ports": 1, "flip_flops": 2}
    cells = n["modules"]["unit"]["cells"]
    ram = cells["ram"]
    assert ram["parameters"]["REGMODE_B"] == "OUTREG" and ram["parameters"]["REGMODE_A"] == "NOREG"
    assert ram["connections"]["OCEB"] == [EN] and "OCEBMUX" not in ram["parameters"]
    assert ram["connections"]["DOB0"] == [200] and ram["connections"]["DOB1"] == [201]
    assert ram["connections"]["DOB2"] == [102]          # an unused output: as it was
    assert set(cells) == {"ram"}


def test_inverted_enable_and_no_enable():
    n = _netlist(ce=("INV", EN))
    assert absorb_output_registers(n)["ports"] == 1
    ram = n["modules"]["unit"]["cells"]["ram"]
    assert ram["connections"]["OCEB"] == [EN] and ram["parameters"]["OCEBMUX"] == "INV"
    n = _netlist(ce=("1", EN))
    assert absorb_output_registers(n)["ports"] == 1
    assert n["modules"]["unit"]["cells"]["ram"]["connections"]["OCEB"] == ["1"]


@pytest.mark.parametrize("change", [dict(extra_load=True), dict(lsr=5), dict(ram_rst="0"), dict(clk=9)])
def test_left_alone_when_not_the_same_circuit(change):
    """An output with a second load, a reset that is not the port's, a port without the register's
    reset, a flip-flop on another clock: nothing changes."""
    n = _netlist(**change)
    before = copy.deepcopy(n)
    assert absorb_output_registers(n) == {"ports": 0, "flip_flops": 0}
    assert n == before


def test_report_area_bram_outreg(capsys):
    """The block RAMs of the loadable index reader (topspin's geometry: 10 block RAMs, seconds; the
    ``paper`` preset's 16 take a minute) take their data registers, and nextpnr places the result:
    port B, the bus read's (no reset, no enable), of every block RAM; port A, the pipeline's bank
    data register, where its bits sit on one copy of ``advance`` (``hw.pipeline.INDEX_DATA_COPIES``
    shares a bank's bits out over copies; a port whose outputs span two shares has two enables and
    stays in the fabric, the rule of :func:`absorb_output_registers`)."""
    _need_tools()
    code, out, err = _run(capsys, "report", "area", "--unit", "loadable", "--builtin", "topspin", "--stage",
                          "index_reader", "--no-route", "--bram-outreg", "--json")
    assert code == 0, err
    rep = json.loads(out)
    brams = rep["utilisation"]["brams"]
    assert brams > 0 and brams < rep["bram_outreg"]["ports"] <= 2 * brams
    assert rep["bram_outreg"]["flip_flops"] >= brams and rep["timing"]["fmax_mhz"] > 0
