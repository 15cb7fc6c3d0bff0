"""What it costs in ECP5 block RAMs to read a ROM through both ports of its DP16KDs instead of holding a
second copy: the measurement behind the texture filter's choice to give each lane its own codebook
(``python -m vqtex.sim.reports.rom_ports [--json]``, docs/filter.md).

For each ROM shape (depth x width, the codebook banks of the built-in sets and a few others) a
``lib.memory.Memory`` with random contents and one or two synchronous read ports is synthesized by
Yosys ``synth_ecp5`` (as ``vqtex report area`` does), and the DP16KDs of the netlist are counted.
A DP16KD is 18 Kbit: 512 x 36 through one port, but a true dual-port DP16KD has two ports of at most
18 bits (1024 x 18), so a 512-deep ROM read twice per cycle costs two DP16KDs per 36 bits, as much as a
second copy; from 1024 words deep the second port is free.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import re
import tempfile

__all__ = ["rom_cost", "SHAPES", "main"]

#: (depth, width) of the measured ROMs: a 512-word bank of the ``four`` set's codebook (504 bits), a
#: 1024-word one, a 512 x 36 word, and a 2048-word index memory of 32-bit words.
SHAPES = ((512, 36), (512, 504), (1024, 504), (2048, 32))


def rom_cost(depth: int, width: int, ports: int, *, seed: int = 1) -> dict:
    """``{"DP16KD": n, "LUT4": n}`` of a ``depth`` x ``width`` ROM read through ``ports`` (1 or 2)
    synchronous read ports, synthesized for ECP5."""
    from amaranth import Module
    from amaranth.back import rtlil
    from amaranth.lib import memory, wiring
    from amaranth.lib.wiring import In, Out

    from .synth.tools import run_yowasp

    class Rom(wiring.Component):
        def __init__(self):
            super().__init__({**{f"addr{p}": In(range(depth)) for p in range(ports)},
                              **{f"data{p}": Out(width) for p in range(ports)}})

        def elaborate(self, platform):
            m = Module()
            rng = random.Random(seed)
            m.submodules.rom = mem = memory.Memory(shape=width, depth=depth,
                                                   init=[rng.getrandbits(width) for _ in range(depth)])
            for p in range(ports):
                r = mem.read_port()
                m.d.comb += [r.addr.eq(getattr(self, f"addr{p}")), getattr(self, f"data{p}").eq(r.data)]
            return m

    with tempfile.TemporaryDirectory(prefix="vqtex-rom-") as folder:
        with open(os.path.join(folder, "rom.il"), "w") as f:
            f.write(rtlil.convert(Rom(), name="rom", emit_src=False))
        run_yowasp("yosys", ["-q", "-p", "read_rtlil rom.il; synth_ecp5 -top rom; tee -q -o stat.txt stat"], folder,
             "yosys.out")
        with open(os.path.join(folder, "stat.txt")) as f:
            stat = f.read()
    count = {cell: sum(int(n) for n in re.findall(rf"(\d+)\s+{cell}\b", stat)) for cell in ("DP16KD", "LUT4")}
    return count


def main(argv=None) -> None:
    p = argparse.ArgumentParser(prog="python -m vqtex.sim.reports.rom_ports", description=__doc__.split("\n")[0])
    p.add_argument("--json", action="store_true", help="one JSON object instead of the table")
    args = p.parse_args(argv)
    rows = []
    for depth, width in SHAPES:
        one, two = rom_cost(depth, width, 1), rom_cost(depth, width, 2)
        rows.append({"depth": depth, "width": width, "one_port_DP16KD": one["DP16KD"],
                     "two_copies_DP16KD": 2 * one["DP16KD"], "two_ports_DP16KD": two["DP16KD"]})
    if args.json:
        print(json.dumps({"device": "ECP5 (Yosys synth_ecp5)", "roms": rows}))
        return
    print("ROM depth x width | one port | two copies | one copy, two ports   (DP16KD)")
    for r in rows:
        print(f"{r['depth']:>5} x {r['width']:<4}      | {r['one_port_DP16KD']:>8} | {r['two_copies_DP16KD']:>10} | "
              f"{r['two_ports_DP16KD']:>8}")


if __name__ == "__main__":
    main()
