"""The exported loadable unit's Wishbone port, driven by a third-party bus model: cocotbext-wishbone's
``WishboneMaster`` under cocotb 2 and Icarus Verilog (``iverilog -g2012``, the SystemVerilog export).

One simulation: reset; the whole load of a texture set (every write of ``load_writes``: 326 for
this geometry, a second or two of Icarus, so nothing is sampled away); error responses (regions 5
and 7, offsets past each memory's depth or aliasing into it, a codebook lane past an entry's bytes,
a control word that does not exist, writes to the read-only ID and VERSION registers, whose values
must read back unchanged); a write with ``sel`` low (acknowledged, changes nothing); read-back of
every control and descriptor word and a random sample of the memories (after the refused writes,
so a refused write that reached a memory shows); then texel requests on ``i_*`` compared with
golden.fetch. Expected values come from golden.register_map (``expected_reads``, ``mapped``) and
reach the cocotb module (cocotb_bus/vqtex_bus_host.py) in a JSON plan; it checks them, and this
side checks what it wrote back. The master issues one transfer at a time (see that module), so the
load's cycle count is not golden's ``load_cycles`` (back-to-back writes): only answers are checked.
"""

from __future__ import annotations

import json
import os

import numpy as np
import pytest

from tests.support import need, need_python, texture_set
from vqtex.golden.fetch import fetch, random_requests
from vqtex.golden.geometry import Geometry
from vqtex.golden.register_map import (CONTROL, REGIONS, RegisterMap, expected_reads, load_writes, mapped)
from vqtex.sim.backends.verilog import export_verilog

HERE = os.path.dirname(os.path.abspath(__file__))
HOST = "vqtex_bus_host"                     # tests/sim/backends/cocotb_bus/vqtex_bus_host.py
ACK, ERR = 1, 2                             # cocotbext-wishbone's WBRes.ack codes


def _plan(ts, g):
    """The bus cycles (operations with expected answers) and texel requests with golden texels."""
    rmap = RegisterMap(g)
    words = rmap.region_words()
    addr = lambda region, offset: int(rmap.address(region, offset))
    writes = load_writes(ts, g).astype(np.int64)
    known = dict(writes.tolist())

    def read(a):
        data, err = expected_reads(ts, g, [a])
        assert a in known or err[0] or (a >> rmap.offset_bits) == REGIONS["control"], hex(a)
        return [a, None, 1, ERR if err[0] else ACK, None if err[0] else int(data[0])]

    def write(a, d, sel=1):
        return [a, int(d), sel, ACK if mapped(rmap, a, write=True) else ERR, None]

    load = [write(a, d) for a, d in writes.tolist()]
    assert all(op[3] == ACK for op in load)

    # Refused transfers: a read and a write of each.
    ob = rmap.offset_bits
    bad = [5 << ob, (5 << ob) | 3, (7 << ob) | ((1 << ob) - 1), addr("control", 0x08), addr("control", 0x1F)]
    for region in ("descriptors", "index", "raw"):
        n = words[region]
        bad.append(addr(region, n))                                      # one past the depth
        alias = 1 << max(0, (n - 1).bit_length())                        # would alias word 1 if truncated
        if alias + 1 < 1 << ob:
            bad.append(addr(region, alias + 1 if alias + 1 >= n else n + 1))
    if rmap.used_entry_lanes < rmap.entry_lanes:
        bad.append(addr("codebook", rmap.used_entry_lanes))               # a lane past entry 0's bytes
        bad.append(addr("codebook", rmap.entry_lanes + rmap.entry_lanes - 1))
    assert not any(mapped(rmap, a) or mapped(rmap, a, write=True) for a in bad)
    ro = [addr("control", CONTROL[n][0]) for n in ("ID", "VERSION", "TEXTURES")]
    assert not any(mapped(rmap, a, write=True) for a in ro) and all(mapped(rmap, a) for a in ro)
    errors = []
    for a in bad:
        errors += [read(a), write(a, 0xDEADBEEF)]
    errors += [write(a, 0xFFFFFFFF) for a in ro] + [read(a) for a in ro]
    # sel low: acknowledged, and the register keeps its loaded value (read back below)
    frac = addr("control", CONTROL["MATRIX_FRAC_BITS"][0])
    errors += [write(frac, known[frac] ^ 0x7, sel=0), read(frac)]
    assert sum(op[3] == ERR for op in errors) == 2 * len(bad) + len(ro)

    # Read-back: every control register (the geometry's and the matrix), every descriptor word, and
    # a random sample of the index, codebook and raw memories (their every raw word).
    rng = np.random.default_rng(7)
    control = [addr("control", off) for off, _, _ in CONTROL.values()]
    desc = [a for a in known if a >> ob == REGIONS["descriptors"]]
    mem = [a for a in known if a >> ob in (REGIONS["index"], REGIONS["codebook"])]
    raw = [a for a in known if a >> ob == REGIONS["raw"]]
    # (index word 1 always: a refused write above would land there if the offset were truncated)
    sample = sorted(set(rng.choice(mem, 80, replace=False).tolist()) | {addr("index", 1), addr("codebook", 1)})
    reads = [read(a) for a in control + desc + sample + raw]
    reads.insert(len(reads) // 2, read(ro[0]))                          # the ID once more, mid-cycle
    assert reads[0][4] == 0x56515458                                     # ID, control offset 0

    # Texel requests: golden's random ones plus the deepest (raw) levels of every texture.
    req = random_requests(ts, 20, seed=11)
    deep = [[t, tex.levels - lv, 0, 0] for t, tex in enumerate(ts.textures) for lv in (1, 2)]
    req = np.concatenate([req, np.array(deep, np.int64)])
    texels = fetch(ts, req[:, 0], req[:, 1], req[:, 2], req[:, 3])
    return {"cycles": [load, errors, reads], "requests": req.tolist(), "texels": texels.tolist()}


def test_cocotbext_wishbone_master_icarus(tmp_path, monkeypatch):
    need("iverilog", "vvp")
    need_python("cocotb", "cocotb_tools.runner", "cocotb_bus", "cocotbext.wishbone.driver")
    from cocotb_tools.runner import get_runner

    ts = texture_set("yuv_dreamcast_4x4_b12_mip")
    g = Geometry.of(ts)
    src = tmp_path / "texel_fetch.sv"
    src.write_text(export_verilog(None, geometry=g, dialect="sv"))
    plan = _plan(ts, g)
    plan_file, observed_file = tmp_path / "plan.json", tmp_path / "observed.json"
    plan_file.write_text(json.dumps(plan))

    # The simulator's Python finds the cocotb module on sys.path (the runner passes it as PYTHONPATH).
    monkeypatch.syspath_prepend(os.path.join(HERE, "cocotb_bus"))
    monkeypatch.setenv("VQTEX_COCOTB_PLAN", str(plan_file))
    monkeypatch.setenv("VQTEX_COCOTB_OBSERVED", str(observed_file))
    runner = get_runner("icarus")
    build_log, test_log = tmp_path / "build.log", tmp_path / "sim.log"
    try:
        runner.build(sources=[src], hdl_toplevel="texel_fetch", build_dir=tmp_path / "sim_build",
                     timescale=("1ns", "1ps"), always=True, log_file=build_log)
        results = runner.test(test_module=HOST, hdl_toplevel="texel_fetch", build_dir=tmp_path / "sim_build",
                              test_dir=tmp_path, results_xml=str(tmp_path / "results.xml"), log_file=test_log)
    except (SystemExit, RuntimeError) as e:   # the runner exits on a failed cocotb test under pytest
        log = test_log if test_log.exists() else build_log
        pytest.fail(f"cocotb/Icarus run failed ({e!r}); {log}:\n" + (log.read_text()[-8000:] if log.exists() else ""))

    from cocotb_tools.check_results import get_results
    assert get_results(results) == (1, 0)
    # What the master saw, checked again here against golden.
    observed = json.loads(observed_file.read_text())
    assert len(observed["cycles"]) == len(plan["cycles"])
    for cycle, got in zip(plan["cycles"], observed["cycles"]):
        assert len(got) == len(cycle)
        for (adr, _, _, code, data), (radr, rcode, rdata, _, _) in zip(cycle, got):
            assert (radr, rcode) == (adr, code), hex(adr)
            if data is not None:
                assert rdata == data, hex(adr)
    load, errors, reads = observed["cycles"]
    assert all(r[1] == ACK for r in load) and sum(r[1] == ERR for r in errors) > 10
    assert any(r[3] > 0 for r in load)          # the first transfer waited on stall (the drain rule)
    assert observed["responses"] == [[*t, n % 256] for n, t in enumerate(plan["texels"])]
