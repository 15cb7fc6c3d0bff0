"""The cocotb side of tests/sim/backends/test_cocotb_axi.py (not a pytest module: cocotb imports it
inside the simulator, by this name, from this folder).

A third-party AXI slave, cocotbext-axi's ``AxiRamRead``, holding the texture set's external memory
image, answers the exported cached unit's ``axi_*`` master. The plan (``$VQTEX_COCOTB_PLAN``, JSON
from the pytest side: the image in hex, the requests, their golden RGBA, the output's ready pattern)
is run through ``i_*``/``o_*``; every AR handshake is checked as it happens (INCR bursts of the bus
width that do not cross a 4 KB boundary and stay inside the image), and what was seen is written to
``$VQTEX_COCOTB_OBSERVED`` for the pytest side to check again.

No vqtex import here: the simulator process needs cocotb and cocotbext-axi only.
"""

from __future__ import annotations

import json
import os

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import ReadOnly, RisingEdge, Timer
from cocotbext.axi import AxiRamRead, AxiReadBus


def _int(value):
    return int(value) if value.is_resolvable else str(value)


# Every loop drives its inputs after a rising edge and samples the handshakes in that cycle's
# ReadOnly phase, before the next edge: the same values whichever the simulator (Icarus shows the
# values before the edge's updates at RisingEdge, Verilator those after them).

async def _requests(dut, requests):
    for n, (tex, level, i, j) in enumerate(requests):
        dut.i_texture.value, dut.i_level.value, dut.i_i.value, dut.i_j.value = tex, level, i, j
        dut.i_tag.value = n % 256
        dut.i_valid.value = 1
        while True:
            await ReadOnly()
            fire = dut.i_ready.value == 1
            await RisingEdge(dut.clk)
            if fire:
                break
    dut.i_valid.value = 0


async def _responses(dut, n, ready, out):
    cycle = 0
    while len(out) < n:
        r = ready[cycle % len(ready)]
        dut.o_ready.value = r
        await ReadOnly()
        if dut.o_valid.value == 1 and r == 1:
            out.append([_int(dut.o_r.value), _int(dut.o_g.value), _int(dut.o_b.value), _int(dut.o_a.value),
                        _int(dut.o_tag.value)])
        await RisingEdge(dut.clk)
        cycle += 1


async def _watch_ar(dut, size, bus_bytes, bursts, problems):
    while True:
        await ReadOnly()
        fire = dut.axi_arvalid.value == 1 and dut.axi_arready.value == 1
        if fire:
            addr, beats = int(dut.axi_araddr.value), int(dut.axi_arlen.value) + 1
            burst, beat_size = int(dut.axi_arburst.value), int(dut.axi_arsize.value)
        await RisingEdge(dut.clk)
        if fire:
            bursts.append([addr, beats])
            if burst != 1 or 1 << beat_size != bus_bytes:
                problems.append(f"burst at 0x{addr:x}: not INCR of {bus_bytes}-byte beats")
            if addr // 4096 != (addr + beats * bus_bytes - 1) // 4096:
                problems.append(f"burst at 0x{addr:x} of {beats} beats crosses 4 KB")
            if addr + beats * bus_bytes > size:
                problems.append(f"burst at 0x{addr:x} of {beats} beats reads past the memory ({size} bytes)")


@cocotb.test(timeout_time=5, timeout_unit="ms")
async def cached_unit_with_axi_ram(dut):
    with open(os.environ["VQTEX_COCOTB_PLAN"]) as f:
        plan = json.load(f)
    image = bytes.fromhex(plan["image"])
    # Nothing driven at time 0 (Icarus 11 loses VPI writes made then: see cocotb_bus/vqtex_bus_host.py).
    await Timer(1, unit="ns")
    cocotb.start_soon(Clock(dut.clk, 10, unit="ns").start())
    dut.i_valid.value = 0
    for name in ("i_texture", "i_level", "i_i", "i_j", "i_tag"):
        getattr(dut, name).value = 0
    dut.o_ready.value = 0
    dut.rst.value = 1
    ram = AxiRamRead(AxiReadBus.from_prefix(dut, "axi"), dut.clk, dut.rst, size=len(image))
    ram.write(0, image)
    for _ in range(3):
        await RisingEdge(dut.clk)
    dut.rst.value = 0
    await RisingEdge(dut.clk)

    observed = {"responses": [], "bursts": []}
    problems = []
    cocotb.start_soon(_watch_ar(dut, len(image), plan["bus_bytes"], observed["bursts"], problems))
    requests = plan["requests"]
    task = cocotb.start_soon(_responses(dut, len(requests), plan["ready"], observed["responses"]))
    await _requests(dut, requests)
    await task
    for n, (got, want) in enumerate(zip(observed["responses"], plan["texels"])):
        if got != [*want, n % 256]:
            problems.append(f"request {n} {requests[n]}: {got}, expected {[*want, n % 256]}")
    with open(os.environ["VQTEX_COCOTB_OBSERVED"], "w") as f:
        json.dump(observed, f)
    assert not problems, f"{len(problems)} problems:\n" + "\n".join(problems[:40])
