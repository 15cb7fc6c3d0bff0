"""The cocotb side of tests/sim/backends/test_cocotb_bus.py (not a pytest module: cocotb imports it
inside Icarus Verilog, by this name, from this folder).

A third-party Wishbone master, cocotbext-wishbone's ``WishboneMaster``, drives the exported loadable
unit's ``bus_*`` port. The plan (``$VQTEX_COCOTB_PLAN``, JSON written by the pytest side from
golden.register_map) is a list of bus cycles, each a list of operations ``[adr, data or null (a
read), sel, expected code (1 ack, 2 err), expected data or null (don't care)]``, then texel requests
``[texture, level, i, j]`` and their golden RGBA. This module runs them all, writes what it saw to
``$VQTEX_COCOTB_OBSERVED`` (the pytest side checks it again) and fails on any difference.

No vqtex import here: the expectations come in the plan only, so the simulator process needs
nothing but cocotb and cocotbext-wishbone (and cocotb-bus, which cocotbext-wishbone imports).

How cocotbext-wishbone 2.0.1's master behaves (read from its driver.py): ``send_cycle`` holds
``cyc`` over the whole list; for each operation it raises ``stb``, waits for a clock edge with
``stall`` low, drops ``stb`` and waits for ``ack``/``err`` (``rty``) before the next operation, so
transfers are one at a time, never back to back; a reply is ``WBRes.ack`` 1 (ack) or 2 (err), no
exception; ``stall`` or ``ack`` at X count as low. Its default ``sel`` is 0xF (four byte lanes):
the port's ``sel`` is one bit, so every operation passes its own.
"""

from __future__ import annotations

import json
import os

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import RisingEdge, Timer
from cocotbext.wishbone.driver import WBOp, WishboneMaster

#: cocotbext-wishbone attribute -> port suffix (the ports are ``bus_<suffix>``, amaranth-soc names).
#: err, stall and sel are listed so that they are required, not silently optional.
SIGNALS = {"cyc": "cyc", "stb": "stb", "we": "we", "adr": "adr", "datwr": "dat_w", "datrd": "dat_r",
           "ack": "ack", "err": "err", "stall": "stall", "sel": "sel"}
#: Clock cycles the master waits for stall to drop / for an answer before it fails the test.
TIMEOUT = 64


def _int(value):
    """A sampled LogicArray as an int, or its string if it holds X/Z (then it cannot equal golden)."""
    return int(value) if value.is_resolvable else str(value)


async def _requests(dut, requests):
    """Present ``requests`` on i_* (one per accepted handshake, tag = position % 256)."""
    for n, (tex, level, i, j) in enumerate(requests):
        dut.i_texture.value, dut.i_level.value, dut.i_i.value, dut.i_j.value = tex, level, i, j
        dut.i_tag.value = n % 256
        dut.i_valid.value = 1
        while True:
            await RisingEdge(dut.clk)
            if dut.i_ready.value == 1:          # sampled at the edge: the request was taken
                break
    dut.i_valid.value = 0


async def _responses(dut, n, out):
    """Collect ``n`` responses (o_ready is held high): [r, g, b, a, tag] each."""
    while len(out) < n:
        await RisingEdge(dut.clk)
        if dut.o_valid.value == 1 and dut.o_ready.value == 1:
            out.append([_int(dut.o_r.value), _int(dut.o_g.value), _int(dut.o_b.value), _int(dut.o_a.value),
                        _int(dut.o_tag.value)])


@cocotb.test(timeout_time=2, timeout_unit="ms")
async def wishbone_load_read_errors_fetch(dut):
    with open(os.environ["VQTEX_COCOTB_PLAN"]) as f:
        plan = json.load(f)
    # Nothing is driven at time 0: Icarus 11 does not propagate a VPI write made then to the logic
    # that reads the port (the port shows the value, every assign and always_comb fed by it keeps
    # X/Z: iverilog issues #1041/#1111, cocotb #4886), which left the bus port's decode at X for ever.
    # cocotbext-wishbone's own time-0 idle values (Immediate writes in its constructor) are lost the
    # same way, so everything starts 1 ns in.
    await Timer(1, unit="ns")
    cocotb.start_soon(Clock(dut.clk, 10, unit="ns").start())
    dut.i_valid.value = 0
    for name in ("i_texture", "i_level", "i_i", "i_j", "i_tag", "bus_cyc", "bus_stb", "bus_we", "bus_adr",
                 "bus_dat_w"):
        getattr(dut, name).value = 0
    dut.bus_sel.value = 1
    dut.o_ready.value = 1
    dut.rst.value = 1
    wb = WishboneMaster(dut, "bus", dut.clk, width=32, timeout=TIMEOUT, signals_dict=SIGNALS)
    for _ in range(3):                          # synchronous reset, held for three edges
        await RisingEdge(dut.clk)
    dut.rst.value = 0
    await RisingEdge(dut.clk)

    observed = {"cycles": [], "responses": []}
    mismatches = []
    for c, cycle in enumerate(plan["cycles"]):
        ops = [WBOp(adr=adr, dat=dat, sel=sel, acktimeout=TIMEOUT) for adr, dat, sel, _, _ in cycle]
        results = await wb.send_cycle(ops)
        # WBRes.ack is the reply code: 1 ack, 2 err (3 rty); one result per operation, in order
        got = [[int(r.adr), int(r.ack), _int(r.datrd), int(r.waitStall), int(r.waitAck)] for r in results]
        observed["cycles"].append(got)
        if len(got) != len(cycle):
            mismatches.append(f"cycle {c}: {len(got)} answers to {len(cycle)} operations")
            continue
        for (adr, dat, _, code, data), (radr, rcode, rdata, _, _) in zip(cycle, got):
            if radr != adr or rcode != code or (data is not None and rdata != data):
                mismatches.append(f"cycle {c}: {'write' if dat is not None else 'read'} 0x{adr:x}: "
                                  f"code {rcode} data {rdata!r}, expected code {code} data {data!r}")

    requests = plan["requests"]
    task = cocotb.start_soon(_responses(dut, len(requests), observed["responses"]))
    await _requests(dut, requests)
    await task
    for n, (got, want) in enumerate(zip(observed["responses"], plan["texels"])):
        if got != [*want, n % 256]:
            mismatches.append(f"request {n} {requests[n]}: {got}, expected {[*want, n % 256]}")

    with open(os.environ["VQTEX_COCOTB_OBSERVED"], "w") as f:
        json.dump(observed, f)
    assert not mismatches, f"{len(mismatches)} mismatches:\n" + "\n".join(mismatches[:40])
