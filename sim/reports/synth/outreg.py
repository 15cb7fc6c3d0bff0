"""The block RAMs' output registers (``vqtex report area --bram-outreg``): a netlist step between Yosys
and nextpnr that moves the fabric register behind a block RAM into the DP16KD's own output register.

Yosys 0.70's ECP5 memory mapping (``memory_libmap`` with ``+/lattice/brams_16kd.txt``) describes a
DP16KD port with one read register (the address latch, ``clken``, a synchronous or asynchronous
reset) and nothing after it: every DP16KD it writes has ``REGMODE_A = REGMODE_B = "NOREG"``, so a
register behind the read port (:class:`hw.banked_rom.BankedROM`'s per-bank data register) stays in
the fabric, and the block RAM's clock-to-out (4.26 ns at speed 8) plus the routing to those
flip-flops is one cycle. Lattice's own synthesis absorbs such a register into the block RAM
(``REGMODE = "OUTREG"``); :func:`absorb_output_registers` does the same on Yosys's JSON netlist,
with the same cycles: the register's clock enable becomes the port's ``OCE`` (inverted by
``OCEAMUX``/``OCEBMUX`` = ``INV`` when the flip-flops' was, ``CEMUX`` = ``INV``), its reset the
port's ``RST`` (which the port's read latch already shares).

A port's register is absorbed only when every used data output of the port drives exactly one
flip-flop (``TRELLIS_FF``) and nothing else, and all those flip-flops have the block RAM port's
clock (not inverted), one clock enable (or none), and a reset that is the port's own ``RST`` net
(synchronous, ``LSR_OVER_CE``, to 0: as the port's read latch) or no reset when the port has
none. Anything else is left as it was. It is a measurement option: the RTL, the exported Verilog
and every simulation are unchanged (the same cycles; what a vendor's synthesis does with them).
"""

from __future__ import annotations

import json
import os

__all__ = ["absorb_output_registers", "absorb_netlist"]

_CONST = ("0", "1", "x", "z")


def _param(cell, name, default=""):
    return str(cell["parameters"].get(name, default)).strip()


def _enable(ff) -> tuple:
    """A flip-flop's clock enable: (net bits, inverted)."""
    mux = _param(ff, "CEMUX", "1")
    if mux in ("CE", "INV"):
        return tuple(ff["connections"].get("CE", ["1"])), mux == "INV"
    return ("1",), False


def _reset(ff) -> list:
    """A flip-flop's reset net (``["0"]`` when its LSR input is not used)."""
    return ff["connections"].get("LSR", ["0"]) if _param(ff, "LSRMUX", "LSR") == "LSR" else ["0"]


def absorb_output_registers(netlist: dict) -> dict:
    """Absorb the fabric registers behind DP16KD read ports into their output registers, in place
    (see the module docstring). Returns ``{"ports": n, "flip_flops": n}``: the ports changed to
    ``OUTREG`` and the flip-flops removed."""
    ports_done = ffs_done = 0
    for mod in netlist.get("modules", {}).values():
        cells = mod.get("cells", {})
        if not any(c["type"] == "DP16KD" for c in cells.values()):
            continue
        port_bits = {b for p in mod.get("ports", {}).values() for b in p["bits"] if b not in _CONST}
        sinks = {}                              # net -> [(cell name, pin)] of its inputs
        for name, c in cells.items():
            dirs = c.get("port_directions", {})
            for pin, bits in c["connections"].items():
                if dirs.get(pin) == "input":
                    for b in bits:
                        if b not in _CONST:
                            sinks.setdefault(b, []).append((name, pin))
        for bram in [n for n, c in cells.items() if c["type"] == "DP16KD"]:
            ram = cells[bram]
            conn = ram["connections"]
            for side in ("A", "B"):
                if _param(ram, f"REGMODE_{side}", "NOREG") != "NOREG":
                    continue
                ffs = []
                ok = True
                for k in range(18):
                    (net,) = conn.get(f"DO{side}{k}", ["x"])
                    if net in _CONST or (net not in sinks and net not in port_bits):
                        continue                # an unused output
                    loads = sinks.get(net, [])
                    if net in port_bits or len(loads) != 1 or loads[0][1] != "DI" \
                            or cells[loads[0][0]]["type"] != "TRELLIS_FF":
                        ok = False
                        break
                    ffs.append((k, loads[0][0]))
                if not ok or not ffs:
                    continue
                first = cells[ffs[0][1]]
                ce = _enable(first)
                lsr = _reset(first)
                if lsr != conn.get(f"RST{side}", ["0"]):
                    continue                    # the register's reset is not the port's
                for _, f in ffs:
                    ff = cells[f]
                    fc = ff["connections"]
                    same = (fc.get("CLK") == conn.get(f"CLK{side}") and _param(ff, "CLKMUX", "CLK") == "CLK"
                            and _enable(ff) == ce
                            and _reset(ff) == lsr
                            and _param(ff, "REGSET", "RESET") == "RESET"
                            and (lsr == ["0"] or _param(ff, "SRMODE", "LSR_OVER_CE") == "LSR_OVER_CE")
                            and _param(ff, "GSR", "DISABLED") == _param(ram, "GSR", "DISABLED"))
                    if not same:
                        ok = False
                        break
                if not ok or (lsr != ["0"] and _param(ram, "RESETMODE", "SYNC") != "SYNC"):
                    continue
                for k, f in ffs:                # the output pin drives the register's Q net
                    conn[f"DO{side}{k}"] = list(cells[f]["connections"]["Q"])
                    del cells[f]
                ram["parameters"][f"REGMODE_{side}"] = "OUTREG"
                conn[f"OCE{side}"] = list(ce[0])
                if ce[1]:                       # the flip-flops' enable was inverted: so is the port's
                    ram["parameters"][f"OCE{side}MUX"] = "INV"
                ports_done += 1
                ffs_done += len(ffs)
    return {"ports": ports_done, "flip_flops": ffs_done}


def absorb_netlist(path: str) -> dict:
    """:func:`absorb_output_registers` on the JSON netlist file ``path``, rewritten in place (Yosys's
    own kept beside it as ``*-yosys.json``)."""
    with open(path) as f:
        netlist = json.load(f)
    counts = absorb_output_registers(netlist)
    root, ext = os.path.splitext(path)
    os.replace(path, f"{root}-yosys{ext}")
    with open(path, "w") as f:
        json.dump(netlist, f)
    return counts
