"""The loadable unit (hw.texel_fetch.TexelFetch(geometry, loadable=True)) in pysim: a set loaded by
bus writes, then fetched bit for bit as golden.fetch does, with backpressure; another set loaded into
the same simulation; reads back what was written; the bus's error response; the drain rule."""

from __future__ import annotations

import numpy as np
import pytest
from amaranth.sim import Simulator

from vqtex.golden.fetch import fetch, random_requests
from vqtex.golden.geometry import Geometry
from vqtex.golden.register_map import (CONTROL, RegisterMap, expected_reads, load_cycles, load_writes,
                                       mapped)
from vqtex.hw.bus_port import READ_LATENCY
from vqtex.hw.texel_fetch import LATENCY, TexelFetch
from vqtex.sim.backends import pysim
from vqtex.sim.backends.interface import simulate

from ..support import adversarial_requests, pvr2_small_sets, texture_set


def _geometry(*sets) -> Geometry:
    g = Geometry.of(sets[0])
    for ts in sets[1:]:
        g = g.union(Geometry.of(ts))
    return g


def _check(ts, req, r, *, stall, seed):
    assert np.array_equal(r.responses, fetch(ts, req[:, 0], req[:, 1], req[:, 2], req[:, 3]))
    golden = simulate(ts, req, backend="golden", stall=stall, seed=seed)
    assert (r.cycles, r.stall_cycles, r.straddles) == (golden.cycles, golden.stall_cycles, golden.straddles)
    assert r.cycles == len(req) + LATENCY + r.stall_cycles["output_backpressure"]


@pytest.mark.parametrize("names", [("rgb_4x4_b8_mip", "yuv_4x4_b12_mip"),
                                   ("rgba_2x2_b7_mip_w16", "rgb_2x2_b16_w16"),
                                   ("i8_4x2_b5_w64", "yuv_2x4_b12_mip_w64"),
                                   ("rgba_8x8_b9_mip", "yuv_dreamcast_4x4_b12_mip")])
def test_load_then_fetch_then_reload(names):
    """Two sets of one word width through one loadable unit: each loaded by bus writes, then random
    and adversarial requests with backpressure, bit for bit and cycle for cycle as golden; the
    load takes golden's ``load_cycles``."""
    a, b = (texture_set(n) for n in names)
    g = _geometry(a, b)
    phases = []
    for n, ts in enumerate((a, b)):
        req = np.concatenate([random_requests(ts, 40, seed=n), adversarial_requests(ts, seed=n)[:40]])
        phases.append((ts, req))
    results = pysim.run_phases(g, phases, stall=0.25, seed=5)
    for (ts, req), r in zip(phases, results):
        _check(ts, req, r, stall=0.25, seed=5)
        assert r.load_cycles == load_cycles(len(load_writes(ts, g)))


def test_pvr2_sets_load():
    """PowerVR2 sets (twiddled maps, 16-bit formats, yuv422 through the loaded Dreamcast matrix)."""
    sets = pvr2_small_sets()
    a, b = sets["rectangles_and_mip8"], sets["crate_argb4444_c_64_m"]
    g = _geometry(a, b)
    phases = [(ts, random_requests(ts, 50, seed=n)) for n, ts in enumerate((a, b))]
    for (ts, req), r in zip(phases, pysim.run_phases(g, phases, stall=0.2, seed=2)):
        _check(ts, req, r, stall=0.2, seed=2)


@pytest.mark.parametrize("bank_depth", [None, 64])
def test_larger_geometry_and_stale_rows(bank_depth):
    """A set loaded into a geometry larger than it (more textures, deeper memories) after a set
    with more textures: the rows the second set does not use are written invalid, and requests of
    the second set are exact. With 64-word banks, every memory has several banks (the pipeline's
    bank select behind the block RAMs' first ports, the bus's writes on the second ports)."""
    big, small = texture_set("rgb_4x4_b8_mip", images=3), texture_set("yuv_4x4_b12_mip")
    g = _geometry(big, small).union(Geometry.of(big))
    g = Geometry(**{**g.to_dict(), "index_words": g.index_words + 100, "codebook_entries": g.codebook_entries + 7,
                    "raw_words": max(g.raw_words + 9, 1100), "textures": 5})
    assert g.raw_words > 1024 >= g.codebook_entries     # both ways of reading back (hw.banked_rom)
    phases = [(big, random_requests(big, 30, seed=1)), (small, random_requests(small, 30, seed=2))]
    for (ts, req), r in zip(phases, pysim.run_phases(g, phases, bank_depth=bank_depth)):
        _check(ts, req, r, stall=0.0, seed=0)


def _bus_program(dut, ops):
    """Run ``ops`` ((N, 3): address, data, write) on ``dut`` from reset; (data, err) per op."""
    out = {}

    async def bench(ctx):
        out["data"], out["err"], out["cycles"] = await pysim.bus_transfers(ctx, dut.bus, ops)

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    return np.array(out["data"], np.uint64), np.array(out["err"], bool), out["cycles"]


@pytest.mark.parametrize("bank_depth", [None, 16])
def test_read_back_and_errors(bank_depth):
    """Every kind of word reads back what the load wrote (control registers sign-extended, the
    geometry's read-only registers), and unmapped addresses and read-only writes answer with err
    (and change nothing). With 16-word banks, the reads come from many banks' second ports."""
    ts = texture_set("yuv_dreamcast_4x4_b12_mip")
    g = _geometry(ts)
    # a raw memory deeper than 512 words: the bus reads it on its own port (hw.banked_rom)
    g = Geometry(**{**g.to_dict(), "raw_words": max(g.raw_words, 600)})
    assert g.codebook_entries <= 512 < g.raw_words
    rmap = RegisterMap(g)
    writes = load_writes(ts, g).astype(np.int64)
    rng = np.random.default_rng(0)
    sample = writes[rng.choice(len(writes), 60, replace=False), 0]
    regs = rmap.address("control", [off for off, _, _ in CONTROL.values()]).astype(np.int64)
    ob = rmap.offset_bits
    bad = [5 << ob, (7 << ob) + 3, int(rmap.address("raw", g.raw_words)),
           int(rmap.address("codebook", rmap.used_entry_lanes)) if rmap.used_entry_lanes < rmap.entry_lanes
           else int(rmap.address("codebook", rmap.region_words()["codebook"])),
           int(rmap.address("descriptors", g.descriptor_rows * 4)), int(rmap.address("control", 0x1F))]
    reads = np.concatenate([sample, regs, bad])
    ro_write = int(rmap.address("control", CONTROL["ID"][0]))
    ops = np.concatenate([
        np.stack([writes[:, 0], writes[:, 1], np.ones(len(writes), np.int64)], 1),
        [[ro_write, 0x1234, 1], [bad[0], 7, 1]],
        np.stack([reads, np.zeros(len(reads), np.int64), np.zeros(len(reads), np.int64)], 1)])
    dut = TexelFetch(geometry=g, loadable=True, **({} if bank_depth is None else {"bank_depth": bank_depth}))
    data, err, _ = _bus_program(dut, ops)
    n = len(writes)
    assert not err[:n].any()
    assert err[n] and err[n + 1]                   # a read-only register, an unmapped word
    want, want_err = expected_reads(ts, g, reads)
    assert np.array_equal(err[n + 2:], want_err)
    assert np.array_equal(data[n + 2:][~want_err], want[~want_err])
    assert want_err[-len(bad):].all() and not want_err[:-len(bad)].any()
    assert data[n + 2 + len(sample)] == 0x56515458          # ID unchanged by the refused write
    # the model of what answers agrees with the hardware for every address asked
    assert [not mapped(rmap, a) for a in reads] == err[n + 2:].tolist()


def test_write_timing_and_read_latency():
    """Writes go back to back (one per cycle after the first), a read answers READ_LATENCY cycles
    after it is accepted (and the next read is accepted then), and a load of N writes takes N + 3
    cycles."""
    ts = texture_set("rgb_4x4_b8_mip")
    g = _geometry(ts)
    writes = load_writes(ts, g).astype(np.int64)[:50]
    ops = np.stack([writes[:, 0], writes[:, 1], np.ones(len(writes), np.int64)], 1)
    _, _, cycles = _bus_program(TexelFetch(geometry=g, loadable=True), ops)
    assert cycles == load_cycles(50) == 53
    reads = np.stack([writes[:4, 0], np.zeros(4, np.int64), np.zeros(4, np.int64)], 1)
    _, _, cycles = _bus_program(TexelFetch(geometry=g, loadable=True), reads)
    # one cycle before the first acceptance; a read every READ_LATENCY cycles (the next is accepted
    # in the cycle the previous one answers); the last answer; the cycle after cyc drops
    assert cycles == 1 + 4 * READ_LATENCY + 1 + 1


def test_drain_rule():
    """A bus write while requests are in flight and the output is stalled: the write waits
    (``stall`` high) until every response in flight has left, no request is accepted while ``cyc``
    is high (but in its first cycle: ``pause`` is a flip-flop), the responses of the requests
    accepted before the write come from the old codeword and those after it from the new one, in
    order, none lost."""
    ts = texture_set("rgb_4x4_b8_mip")
    g = _geometry(ts)
    rmap = RegisterMap(g)
    # texel (0, 0) of level 0 reads codeword index[0]: find it, and rewrite that entry's first word
    req = np.array([[0, 0, 0, 0]] * 6, np.int64)
    old = fetch(ts, req[:, 0], req[:, 1], req[:, 2], req[:, 3])
    from vqtex.golden.fetch import lookup_descriptor, block_address, read_index
    dd = lookup_descriptor(ts, req[:1, 0], req[:1, 1])
    k, _, _ = block_address(dd, req[:1, 2], req[:1, 3])
    entry = int(dd["cb_base"][0]) + int(read_index(ts, dd, k)[0])
    new_word = 0x00332211
    addr = int(rmap.address("codebook", entry * rmap.entry_lanes))
    changed = ts.codebook.copy()
    changed[entry, :4] = [0x11, 0x22, 0x33, 0x00]
    from dataclasses import replace
    ts_new = replace(ts, codebook=changed)
    new = fetch(ts_new, req[:, 0], req[:, 1], req[:, 2], req[:, 3])
    assert not np.array_equal(old[0], new[0])
    dut = TexelFetch(ts, geometry=g, loadable=True)
    log = {"accepted_during_cyc": [], "responses": [], "write_accepted": None}

    async def bench(ctx):
        ctx.set(dut.o.ready, 0)
        # three requests enter, the output is stalled
        for n in range(3):
            ctx.set(dut.i.payload, {"texture": 0, "level": 0, "i": 0, "j": 0, "tag": n})
            ctx.set(dut.i.valid, 1)
            await ctx.tick()
        ctx.set(dut.i.valid, 0)
        # the host starts a write; requests keep being offered (tag 3 enters with cyc's first cycle)
        ctx.set(dut.bus.cyc, 1); ctx.set(dut.bus.stb, 1); ctx.set(dut.bus.we, 1); ctx.set(dut.bus.sel, 1)
        ctx.set(dut.bus.adr, addr); ctx.set(dut.bus.dat_w, new_word)
        ctx.set(dut.i.payload, {"texture": 0, "level": 0, "i": 0, "j": 0, "tag": 3})
        ctx.set(dut.i.valid, 1)
        cycle = 0
        pending = True
        while cycle < 200:
            if cycle == 40:
                ctx.set(dut.o.ready, 1)                # let the responses in flight leave
            if ctx.get(dut.i.ready) and ctx.get(dut.i.valid) and ctx.get(dut.bus.cyc):
                log["accepted_during_cyc"].append((cycle, ctx.get(dut.i.payload.tag)))
            if ctx.get(dut.o.valid) and ctx.get(dut.o.ready):
                log["responses"].append((cycle, ctx.get(dut.o.payload.tag), ctx.get(dut.o.payload.r),
                                         ctx.get(dut.o.payload.g)))
            if pending and not ctx.get(dut.bus.stall):
                log["write_accepted"] = cycle
                pending = False
                await ctx.tick()
                cycle += 1
                ctx.set(dut.bus.stb, 0)
                assert ctx.get(dut.bus.ack)
                ctx.set(dut.bus.cyc, 0)
                continue
            if not pending and ctx.get(dut.i.ready) and ctx.get(dut.i.valid):
                tag = ctx.get(dut.i.payload.tag)
                if tag >= 5:
                    ctx.set(dut.i.valid, 0)
                else:
                    ctx.set(dut.i.payload, {"texture": 0, "level": 0, "i": 0, "j": 0, "tag": tag + 1})
            await ctx.tick()
            cycle += 1

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    assert log["accepted_during_cyc"] == [(0, 3)]       # the first cycle of cyc only
    tags = [t for _, t, _, _ in log["responses"]]
    assert tags == list(range(len(tags))) and len(tags) == 6, tags
    # the four in flight left first (from cycle 40), and only then was the write accepted
    assert log["write_accepted"] > max(c for c, t, _, _ in log["responses"] if t < 4) >= 40
    for c, t, r, gch in log["responses"]:
        want = old[t] if t < 4 else new[t]
        assert (r, gch) == (int(want[0]), int(want[1])), (t, r, gch, want)


def test_load_over_bus_counts_cycles_and_refuses_err():
    """``pysim.load_over_bus``, the host's load of every pysim run: the writes of a set take
    ``golden.register_map.load_cycles`` of them; a write answered with err (an unmapped word) is a
    SimulationError naming the write, not a silently half-loaded unit."""
    ts = texture_set("yuv_4x4_b12_mip")
    g = _geometry(ts)
    writes = load_writes(ts, g).astype(np.int64)
    bad = np.array([[5 << RegisterMap(g).offset_bits, 7]], np.int64)
    out = {}

    async def bench(ctx):
        out["cycles"] = await pysim.load_over_bus(ctx, dut.bus, writes)
        with pytest.raises(pysim.SimulationError, match=f"bus write {len(writes[:3])} of the load answered with err"):
            await pysim.load_over_bus(ctx, dut.bus, np.concatenate([writes[:3], bad]))

    dut = TexelFetch(geometry=g, loadable=True)
    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    assert out["cycles"] == load_cycles(len(writes))


def test_descriptor_table_in_block_ram(monkeypatch):
    """The presets' descriptor tables (more than ``hw.descriptor.BLOCK_RAM_ROWS`` rows) are block
    RAM, the bus on their second port; forced here on small geometries: load, fetch and reload bit
    for bit and cycle for cycle, read back and errors, and the drain rule, as with LUT RAM."""
    import vqtex.hw.descriptor as descriptor
    monkeypatch.setattr(descriptor, "BLOCK_RAM_ROWS", 0)
    test_load_then_fetch_then_reload(("rgba_2x2_b7_mip_w16", "rgb_2x2_b16_w16"))
    test_read_back_and_errors(None)
    test_drain_rule()


def test_split_codebook_picks(monkeypatch):
    """A loadable codebook ROM of wide entries (``max``'s: more than
    ``hw.codebook_rom.SPLIT_PICK_WORDS`` words) picks its words over two stages; forced here on
    small geometries (every entry split, groups of 4 and of 2): load, fetch and reload bit for bit
    and cycle for cycle, yuv411's U and V and PowerVR2's yuv422 included."""
    import vqtex.hw.codebook_rom as codebook_rom
    monkeypatch.setattr(codebook_rom, "SPLIT_PICK_WORDS", 0)
    test_load_then_fetch_then_reload(("rgb_4x4_b8_mip", "yuv_4x4_b12_mip"))
    monkeypatch.setattr(codebook_rom, "PICK_GROUP", 2)
    test_pvr2_sets_load()


def test_split_lane_pick(monkeypatch):
    """A memory of more than ``hw.bus_port.SPLIT_LANES`` 32-bit lanes (``max``'s codebook) picks a
    bus read's lane over two cycles; forced here on every wide memory: the reads back and errors
    with the same answers and READ_LATENCY (the bus transfers' timing is checked by the bench)."""
    import vqtex.hw.bus_port as bus_port
    monkeypatch.setattr(bus_port, "SPLIT_LANES", 0)
    test_read_back_and_errors(None)
    test_write_timing_and_read_latency()
