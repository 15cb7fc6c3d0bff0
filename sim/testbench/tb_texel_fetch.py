"""cocotb testbench of the exported vqtex texel-fetch unit (written by ``vqtex export --testbench DIR``).

Run it with ``python run_tb.py`` beside it (``SIM=icarus`` or ``SIM=verilator``; ``--help``). What
it does, in one cocotb test, ``texel_fetch_against_golden``:

1. **Reset** (``rst`` high for three clock edges; nothing is driven at time 0, see :func:`_start`).
2. **Load** (the loadable unit only): every bus write of ``golden.register_map.load_writes(set,
   geometry)`` (colour matrix, every descriptor row, the index, codebook and raw memories) through the
   ``bus_*`` Wishbone port by cocotbext-wishbone's ``WishboneMaster``; every write must be acked.
   The baked units hold the set in their ROMs already (the bench checks the set is the one baked in).
   **Memory** (the external-memory unit, ``unit`` ``external``): cocotbext-axi's ``AxiRamRead``
   answers the ``axi_*`` master from the set's memory image (``golden.memory.system.Layout.image``:
   the index map at 0, the raw levels from the next 4 KB), with its own ``arready`` and R timing.
3. **Random phase**: ``requests`` requests; every bin the set can reach (``vqtex.sim.testbench.bins``)
   gets ``per_bin`` requests drawn from its blocks, the rest are ``golden.fetch.random_requests``,
   shuffled. The **driver** offers them on ``i_*`` with random idle cycles (``gap``), holding valid
   and payload until ``i_ready``; the **backpressure** drops ``o_ready`` with probability ``stall``
   each cycle; the **monitor** takes each response at ``o_valid & o_ready``, checks the stream rule
   (a response held by ``o_ready`` low keeps ``o_valid`` and its payload) and notes whether it was
   held (the ``stall`` bin).
4. **Closure phase**: for every reachable bin not hit yet (a bin whose responses were all held, or
   none held), one request of that bin with ``o_ready`` forced: low for one cycle of its response
   (stall) or high (no stall). The report says how many bins each phase hit.
5. **Scoreboard**: response ``n`` must equal ``vqtex.golden.fetch.fetch`` of request ``n`` with tag
   ``n mod 2**tag_width``, in order; no response may be missing or extra (the bench watches
   ``o_valid`` for ``latency + 8`` cycles after the last one). The strobes: ``stall_output`` must
   equal ``o_valid & ~o_ready`` every cycle, ``straddle`` pulse once per straddling request. The
   external-memory unit: every AR is an INCR burst of the bus width that stays inside a 4 KB page
   and inside the memory image (checked at its handshake; AxiRamRead itself asserts the 4 KB rule
   but wraps an address past its size, so the bench checks that), and the bursts are exactly the
   golden caches' misses of the whole stream, in order (``golden.memory.timing.plan``: the lines,
   each read once while it stays cached); its latency is a lower bound (``latency``, every
   reference a hit), a miss takes what the memory takes.
6. **Coverage** (cocotb-coverage): cover points colour, index width, straddle, level group, stall and
   their cross, whose bins are exactly the ones this set can reach (the others are ``ign_bins``);
   the external-memory unit also covers ``memory``: each request's references all hit, or one missed
   (golden's caches); a hit the random phase lacks is closed by repeating its last request. The
   report is logged and written to ``coverage.xml`` and ``coverage.json`` (reachable, hit,
   missed, per phase) in the build folder.

Configuration: ``tb_config.json`` beside this file (written by the export), overridden by the
environment the runner sets: ``VQTEX_TB_REQUESTS``, ``VQTEX_TB_SEED``, ``VQTEX_TB_STALL``,
``VQTEX_TB_GAP``, ``VQTEX_TB_PER_BIN``, ``VQTEX_TB_SET`` (another texture set: the loadable unit
loads it; a baked unit refuses any set but its own), ``VQTEX_TB_REPORT`` (the coverage JSON).
"""

from __future__ import annotations

import itertools
import json
import os

import cocotb
import numpy as np
from cocotb.clock import Clock
from cocotb.triggers import ReadOnly, RisingEdge, Timer, with_timeout
from cocotb.utils import get_sim_time
from cocotb_coverage.coverage import CoverCross, CoverPoint, coverage_db

from vqtex.golden.fetch import fetch, random_requests
from vqtex.golden.memory.cache import CacheShape
from vqtex.golden.memory.system import Layout, MemoryConfig
from vqtex.golden.memory.timing import plan as memory_plan
from vqtex.golden.format import TextureSet
from vqtex.sim.testbench.bins import DIMENSIONS, bin_name, candidates, request_bins

HERE = os.path.dirname(os.path.abspath(__file__))
CONFIG = os.path.join(HERE, "tb_config.json")
#: Clock period (ns) and the cycles a transfer may wait before the test fails.
PERIOD_NS = 10
BUS_TIMEOUT = 64


def settings() -> dict:
    """The bench's settings: ``tb_config.json`` with the ``VQTEX_TB_*`` environment on top."""
    with open(CONFIG) as f:
        cfg = json.load(f)
    env = os.environ
    cfg["requests"] = int(env.get("VQTEX_TB_REQUESTS", cfg["requests"]))
    cfg["seed"] = int(env.get("VQTEX_TB_SEED", cfg["seed"]))
    cfg["stall"] = float(env.get("VQTEX_TB_STALL", cfg["stall"]))
    cfg["gap"] = float(env.get("VQTEX_TB_GAP", cfg["gap"]))
    cfg["per_bin"] = int(env.get("VQTEX_TB_PER_BIN", cfg["per_bin"]))
    cfg["set_path"] = env.get("VQTEX_TB_SET") or os.path.join(HERE, cfg["set"])
    cfg["report"] = env.get("VQTEX_TB_REPORT") or os.path.join(os.getcwd(), "coverage.json")
    cfg.setdefault("memory", None)
    return cfg


def memory_config(cfg: dict) -> MemoryConfig | None:
    """The external-memory unit's caches, FIFO depth and bus width (``tb_config.json``'s ``memory``)."""
    m = cfg.get("memory")
    if m is None:
        return None
    return MemoryConfig(index_cache=CacheShape(**m["index_cache"]), raw_cache=CacheShape(**m["raw_cache"]),
                        prefetch=m["prefetch"], bus_bytes=m["bus_bytes"])


def random_phase(ts: TextureSet, cands: dict, n: int, per_bin: int, rng) -> np.ndarray:
    """``n`` requests (at least ``per_bin`` per reachable bin, the rest golden's random ones), shuffled."""
    parts = []
    for key in sorted(cands, key=str):
        pool = cands[key]
        parts.append(_inside_blocks(ts, pool[rng.integers(0, len(pool), per_bin)], rng))
    directed = np.concatenate(parts) if parts else np.zeros((0, 4), np.int64)
    rest = random_requests(ts, max(0, n - len(directed)), seed=int(rng.integers(0, 2**31)))
    req = np.concatenate([directed, rest])
    return req[rng.permutation(len(req))]


def _inside_blocks(ts: TextureSet, origins: np.ndarray, rng) -> np.ndarray:
    """A random texel of the block (or raw texel) at each origin request."""
    d = ts.descriptors[origins[:, 0], origins[:, 1]]
    comp = d["compressed"].astype(bool)
    bw = np.where(comp, 1 << d["log2bw"].astype(np.int64), 1)
    bh = np.where(comp, 1 << d["log2bh"].astype(np.int64), 1)
    out = origins.copy()
    out[:, 2] += rng.integers(0, 1 << 16, len(out)) % bw
    out[:, 3] += rng.integers(0, 1 << 16, len(out)) % bh
    return out


class Coverage:
    """cocotb-coverage's cover points and cross over :data:`DIMENSIONS`, with bins for every value
    of the set and ``ign_bins`` for the combinations the set cannot reach."""

    def __init__(self, reachable: set):
        self.reachable = set(reachable)
        values = [sorted({key[n] for key in reachable}, key=str) for n in range(len(DIMENSIONS))]
        names = [f"vqtex.{dim}" for dim in DIMENSIONS]
        ignore = [key for key in itertools.product(*values) if key not in self.reachable]
        points = [CoverPoint(name, xf=lambda *key, n=n: key[n], bins=values[n]) for n, name in enumerate(names)]
        # The cross reads what its points sampled in this call, so it wraps the function innermost.
        sample = CoverCross("vqtex.cross", items=names, ign_bins=ignore)(lambda *key: None)
        for point in reversed(points):
            sample = point(sample)
        self.sample = sample
        self.cross = coverage_db["vqtex.cross"]
        self.sample_memory = CoverPoint("vqtex.memory", xf=lambda outcome: outcome, bins=["hit", "miss"])(
            lambda outcome: None)

    def hit(self) -> set:
        return {key for key, count in self.cross.detailed_coverage.items() if count > 0}

    def report(self, log, path: str, phases: dict) -> dict:
        coverage_db.report_coverage(log.info, bins=True)
        coverage_db.export_to_xml(filename=os.path.join(os.path.dirname(path) or ".", "coverage.xml"))
        hit = self.hit()
        summary = {"reachable": len(self.reachable), "hit": len(hit & self.reachable),
                   "percent": round(100.0 * len(hit & self.reachable) / max(1, len(self.reachable)), 2),
                   "missed": sorted(bin_name(k) for k in self.reachable - hit),
                   "bins": {bin_name(k): int(self.cross.detailed_coverage.get(k, 0)) for k in sorted(self.reachable, key=str)},
                   **phases}
        with open(path, "w") as f:
            json.dump(summary, f, indent=1)
        return summary


class Bench:
    """The driver, backpressure, monitor and scoreboard around one DUT."""

    def __init__(self, dut, ts: TextureSet, cfg: dict, coverage: Coverage, rng):
        self.dut, self.ts, self.cfg, self.coverage, self.rng = dut, ts, cfg, coverage, rng
        self.tag_mask = (1 << cfg["tag_width"]) - 1
        self.fields = ("o_r", "o_g", "o_b", "o_a") + (("o_tag",) if cfg["tag_width"] else ())   # --tag-width 0: no tag ports
        self.mismatches: list = []
        self.sent = 0                       # requests driven so far (over both phases)
        self.received = 0
        self.straddling = 0                 # golden: requests whose index straddles a word
        self.strobes = {"straddle": 0}
        self.accepted: list = []            # cycle each request was taken (i_valid & i_ready)
        self.presented: list = []           # cycle its response first showed o_valid
        self.stalls: set = set()            # cycles of output backpressure or a one-port bubble
        self.memory = memory_config(cfg)    # the external-memory unit's caches (None on chip)
        self.history = np.zeros((0, 4), np.int64)   # every request so far (the caches' state is the stream's)
        self.bursts: list = []              # (address, beats) of every AR handshake
        self.memory_hits = {"hit": 0, "miss": 0}

    async def drive(self, req: np.ndarray):
        """Offer ``req`` on ``i_*``: valid and payload held until ``i_ready``, random idle cycles between."""
        dut, n, offering = self.dut, 0, False
        while n < len(req):
            if not offering and self.rng.random() < self.cfg["gap"]:
                dut.i_valid.value = 0
            else:
                offering = True
                tex, level, i, j = (int(v) for v in req[n])
                dut.i_texture.value, dut.i_level.value, dut.i_i.value, dut.i_j.value = tex, level, i, j
                if self.tag_mask:
                    dut.i_tag.value = (self.sent + n) & self.tag_mask
                dut.i_valid.value = 1
            await ReadOnly()
            fire = offering and dut.i_ready.value == 1
            if fire:
                self.accepted.append(_cycle())
            await RisingEdge(dut.clk)
            if fire:
                n, offering = n + 1, False
        dut.i_valid.value = 0
        self.sent += len(req)

    async def collect(self, req: np.ndarray, force: list):
        """Take ``len(req)`` responses; ``o_ready`` random (``stall``) or forced per response
        (``force[n]``: True hold it one cycle, False never hold it); check each against golden."""
        dut, base = self.dut, self.received
        expected = fetch(self.ts, req[:, 0], req[:, 1], req[:, 2], req[:, 3])
        keys = request_bins(self.ts, req)
        missed = np.zeros(len(req), bool)
        if self.memory is not None:
            self.history = np.concatenate([self.history, req])
            missed = memory_plan(self.ts, self.history, self.memory).misses[-len(req):] > 0
        self.straddling += sum(key[2] for key in keys)
        n, held, last = 0, False, None
        while n < len(req):
            want = force[n]
            ready = held if want is True else True if want is False else self.rng.random() >= self.cfg["stall"]
            dut.o_ready.value = int(ready)
            await ReadOnly()
            valid = dut.o_valid.value == 1
            if hasattr(dut, "stall_output") and (dut.stall_output.value == 1) != (valid and not ready):
                self.mismatches.append(f"cycle with response {base + n} at the head: stall_output "
                                       f"{dut.stall_output.value}, o_valid {int(valid)}, o_ready {int(ready)}")
            if valid and not ready:
                self.stalls.add(_cycle())
            if valid and len(self.presented) == base + n:
                self.presented.append(_cycle())
            if valid:
                payload = tuple(_int(getattr(dut, p).value) for p in self.fields)
                if last is not None and payload != last:
                    self.mismatches.append(f"response {base + n}: payload changed while held: {last} -> {payload}")
                if ready:
                    want_payload = (*(int(v) for v in expected[n]), (base + n) & self.tag_mask)[:len(self.fields)]
                    if payload != want_payload:
                        self.mismatches.append(f"response {base + n} to request {req[n].tolist()}: got {payload}, "
                                               f"expected {want_payload} (golden.fetch)")
                    self.coverage.sample(*keys[n], held)
                    if self.memory is not None:
                        self.memory_hits["miss" if missed[n] else "hit"] += 1
                        self.coverage.sample_memory("miss" if missed[n] else "hit")
                    n, held, last = n + 1, False, None
                else:
                    held, last = True, payload
            elif last is not None:
                self.mismatches.append(f"response {base + n}: o_valid dropped while held by o_ready")
                last = None
            await RisingEdge(dut.clk)
        self.received += len(req)

    async def run(self, req: np.ndarray, force: list):
        """Drive ``req`` and collect its responses (a timeout fails the test: a lost response)."""
        budget = (len(req) + 64) * 8 / max(0.05, 1.0 - max(self.cfg["stall"], self.cfg["gap"]))
        task = cocotb.start_soon(self.drive(req))
        await with_timeout(self.collect(req, force), int(budget * PERIOD_NS), "ns")
        await task

    async def count_strobes(self):
        """Count the ``straddle`` strobe (once per straddling request, hw.texel_fetch) every cycle."""
        while True:
            await ReadOnly()
            self.strobes["straddle"] += int(self.dut.straddle.value == 1)
            if self.dut.stall_one_port.value == 1:
                self.stalls.add(_cycle())
            await RisingEdge(self.dut.clk)

    def check_strobes(self):
        if self.strobes["straddle"] != self.straddling:
            self.mismatches.append(f"straddle strobe: {self.strobes['straddle']} pulses, golden has "
                                   f"{self.straddling} straddling requests")

    async def watch_ar(self, size: int):
        """The external-memory unit's AR channel: every handshake an INCR burst of the bus width,
        inside a 4 KB page and inside the memory (``size`` bytes); recorded for :meth:`check_bursts`."""
        dut, bus = self.dut, self.memory.bus_bytes
        while True:
            await ReadOnly()
            if dut.axi_arvalid.value == 1 and dut.axi_arready.value == 1:
                addr, beats = int(dut.axi_araddr.value), int(dut.axi_arlen.value) + 1
                burst, beat_size = int(dut.axi_arburst.value), int(dut.axi_arsize.value)
                self.bursts.append((addr, beats))
                if burst != 1 or 1 << beat_size != bus:
                    self.mismatches.append(f"AR 0x{addr:x}: burst type {burst}, {1 << beat_size}-byte beats "
                                           f"(expected INCR of {bus})")
                if addr // 4096 != (addr + beats * bus - 1) // 4096:
                    self.mismatches.append(f"AR 0x{addr:x} of {beats} beats crosses a 4 KB boundary")
                if addr + beats * bus > size:
                    self.mismatches.append(f"AR 0x{addr:x} of {beats} beats reads past the memory ({size} bytes)")
            await RisingEdge(dut.clk)

    def check_bursts(self):
        """The bursts are golden's misses of the whole stream, in order: every line the stream needs is
        read, none twice while it stays in the cache (nor while its burst is in flight)."""
        p = memory_plan(self.ts, self.history, self.memory)
        want = list(zip(p.address.tolist(), p.beats.tolist()))
        if self.bursts != want:
            first = next((n for n, (a, b) in enumerate(zip(self.bursts, want)) if a != b), min(len(self.bursts), len(want)))
            self.mismatches.append(f"{len(self.bursts)} bursts, golden's caches miss {len(want)} times; first "
                                   f"difference at burst {first}: "
                                   f"{self.bursts[first] if first < len(self.bursts) else None} != "
                                   f"{want[first] if first < len(want) else None} (address, beats)")
        return {"bursts": len(self.bursts), "golden_bursts": len(want),
                "hit_rate": {"index": round(p.hits[0] / max(1, p.references[0]), 4),
                             "raw": round(p.hits[1] / max(1, p.references[1]), 4)}}

    def check_latency(self, latency: int) -> dict:
        """A response shows ``latency`` cycles after its request was taken when no output stall or
        one-port bubble came between (hw.texel_fetch: "presented on o in cycle t + 14"), and never sooner.
        The external-memory unit: never sooner (``latency`` is its latency when every reference hits;
        a miss waits for the memory, whose timing is the bus model's)."""
        taken, shown = np.array(self.accepted, np.int64), np.array(self.presented, np.int64)
        if len(taken) != len(shown):
            self.mismatches.append(f"{len(taken)} requests taken, {len(shown)} responses shown")
            return {}
        stalls = np.array(sorted(self.stalls), np.int64)
        between = np.searchsorted(stalls, shown) - np.searchsorted(stalls, taken)
        lat = shown - taken
        free = (between == 0) & (self.memory is None)
        for n in np.flatnonzero((lat < latency) | (free & (lat != latency)))[:10]:
            self.mismatches.append(f"response {n}: shown {lat[n]} cycles after its request was taken, latency "
                                   f"{latency}{' (no stall between)' if free[n] else ''}")
        return {"unstalled_responses": int(free.sum()), "latency_min": int(lat.min()) if len(lat) else None,
                "latency_max": int(lat.max()) if len(lat) else None}

    async def quiet(self, cycles: int):
        """No response may appear after the last one (``o_ready`` high, ``cycles`` cycles)."""
        self.dut.o_ready.value = 1
        for _ in range(cycles):
            await ReadOnly()
            if self.dut.o_valid.value == 1:
                self.mismatches.append("an extra response after the last request's")
                return
            await RisingEdge(self.dut.clk)


def _cycle() -> int:
    """The current clock cycle (rising edges at 1 + PERIOD_NS * k ns): one count for every coroutine."""
    return int(get_sim_time("ns") // PERIOD_NS)


def _int(value):
    """A sampled value as an int, or its text if it holds X or Z (then it cannot equal golden)."""
    return int(value) if value.is_resolvable else str(value)


async def _start(dut, image: bytes | None = None):
    """Clock and reset; with ``image``, cocotbext-axi's AxiRamRead holding it answers the ``axi_*``
    master. Nothing is driven at time 0: Icarus 11 does not propagate a VPI write made then to the
    logic that reads the port (iverilog issues #1041/#1111, cocotb #4886)."""
    await Timer(1, unit="ns")
    cocotb.start_soon(Clock(dut.clk, PERIOD_NS, unit="ns").start())
    for name in ("i_valid", "i_texture", "i_level", "i_i", "i_j", "i_tag"):
        if name != "i_tag" or hasattr(dut, "i_tag"):
            getattr(dut, name).value = 0
    dut.o_ready.value = 0
    dut.rst.value = 1
    if hasattr(dut, "bus_cyc"):
        for name in ("bus_cyc", "bus_stb", "bus_we", "bus_adr", "bus_dat_w"):
            getattr(dut, name).value = 0
        dut.bus_sel.value = 1
    if image is not None:
        from cocotbext.axi import AxiRamRead, AxiReadBus
        ram = AxiRamRead(AxiReadBus.from_prefix(dut, "axi"), dut.clk, dut.rst, size=len(image))
        ram.write(0, image)
    for _ in range(3):
        await RisingEdge(dut.clk)
    dut.rst.value = 0
    await RisingEdge(dut.clk)


async def _load(dut, ts: TextureSet, geometry_toml: str, log):
    """The loadable unit: every write of ``load_writes`` through the Wishbone port (cocotbext-wishbone)."""
    from cocotbext.wishbone.driver import WBOp, WishboneMaster
    from vqtex.golden.geometry import Geometry
    from vqtex.golden.register_map import load_writes
    signals = {"cyc": "cyc", "stb": "stb", "we": "we", "adr": "adr", "datwr": "dat_w", "datrd": "dat_r",
               "ack": "ack", "err": "err", "stall": "stall", "sel": "sel"}
    wb = WishboneMaster(dut, "bus", dut.clk, width=32, timeout=BUS_TIMEOUT, signals_dict=signals)
    writes = load_writes(ts, Geometry.loads(geometry_toml, "tb_config.json"))
    ops = [WBOp(adr=int(a), dat=int(d), sel=1, acktimeout=BUS_TIMEOUT) for a, d in writes.tolist()]
    results = await wb.send_cycle(ops)
    refused = [f"0x{int(r.adr):x}" for r in results if int(r.ack) != 1]
    assert len(results) == len(ops) and not refused, f"bus load: {len(refused)} write(s) not acked: {refused[:8]}"
    log.info("loaded the set: %d Wishbone writes, all acked", len(ops))
    await RisingEdge(dut.clk)


def _check_set(ts: TextureSet, cfg: dict):
    """A baked unit answers for the set it was exported with only."""
    if cfg["unit"] == "loadable":
        from vqtex.golden.geometry import Geometry
        misfit = Geometry.loads(cfg["geometry"], "tb_config.json").fits(ts)
        assert not misfit, f"{cfg['set_path']} does not fit the unit's geometry: {'; '.join(misfit)}"
        return
    from vqtex.sim.testbench.write import set_digest
    assert set_digest(ts) == cfg["set_digest"], (
        f"{cfg['set_path']} is not the texture set baked into this {cfg['unit']} unit (its ROMs hold "
        f"{cfg['set']}); export the Verilog for it, or export --unit loadable")


@cocotb.test()
async def texel_fetch_against_golden(dut):
    cfg = settings()
    ts = TextureSet.load(cfg["set_path"])
    _check_set(ts, cfg)
    rng = np.random.default_rng(cfg["seed"])
    cands = candidates(ts)
    reachable = {(*key, stall) for key in cands for stall in (False, True)}
    coverage = Coverage(reachable)
    dut._log.info("set %s: %d textures, %d reachable bins; %d requests, seed %d, stall %.2f, gap %.2f",
                  cfg["set_path"], ts.n_textures, len(reachable), cfg["requests"], cfg["seed"], cfg["stall"], cfg["gap"])
    image = Layout.of(ts).image(ts) if cfg["memory"] is not None else None
    await _start(dut, image)
    if cfg["unit"] == "loadable":
        await _load(dut, ts, cfg["geometry"], dut._log)
    bench = Bench(dut, ts, cfg, coverage, rng)
    strobes = cocotb.start_soon(bench.count_strobes()) if hasattr(dut, "straddle") else None
    ar = cocotb.start_soon(bench.watch_ar(len(image))) if image is not None else None

    req = random_phase(ts, cands, cfg["requests"], cfg["per_bin"], rng)
    await bench.run(req, [None] * len(req))
    after_random = coverage.hit() & reachable
    # Closure: one request per missed bin, its backpressure forced to the bin's stall value.
    holes = sorted(reachable - coverage.hit(), key=str)
    closure = [(_inside_blocks(ts, cands[key[:4]][rng.integers(0, len(cands[key[:4]]), 1)], rng)[0], key[4])
               for key in holes]
    if bench.memory is not None and bench.memory_hits["hit"] == 0 and bench.sent:
        # a request's lines stay cached after it is read: its repeat hits (golden says whether it did)
        closure.append((closure[-1][0] if closure else bench.history[-1], False))
    if closure:
        creq = np.array([c[0] for c in closure], np.int64)
        await bench.run(creq, [c[1] for c in closure])
    await bench.quiet(cfg["latency"] + 8)
    memory = {}
    if ar is not None:
        ar.cancel()
        memory = {**bench.check_bursts(), "memory_bins": dict(bench.memory_hits)}
        for outcome, count in bench.memory_hits.items():
            if not count:
                bench.mismatches.append(f"memory coverage: no request {'missed' if outcome == 'miss' else 'hit'}")
    if strobes is not None:
        strobes.cancel()
        bench.check_strobes()
    timing = bench.check_latency(cfg["latency"])

    phases = {"requests": {"random": int(len(req)), "closure": len(closure)},
              "hit_by_random": len(after_random), "hit_by_closure": len((coverage.hit() & reachable) - after_random),
              "mismatches": len(bench.mismatches), "responses": bench.received,
              "straddling_requests": bench.straddling, "straddle_strobes": bench.strobes["straddle"], **timing,
              "set": os.path.basename(cfg["set_path"]), "unit": cfg["unit"], "seed": cfg["seed"],
              "stall": cfg["stall"], "simulator": cocotb.SIM_NAME, **memory}
    summary = coverage.report(dut._log, cfg["report"], phases)
    dut._log.info("coverage: %d of %d reachable bins (%.1f %%): %d by the random phase, %d by closure; %d responses, "
                  "%d mismatches", summary["hit"], summary["reachable"], summary["percent"], summary["hit_by_random"],
                  summary["hit_by_closure"], bench.received, len(bench.mismatches))
    assert not bench.mismatches, f"{len(bench.mismatches)} mismatches:\n" + "\n".join(bench.mismatches[:20])
    assert summary["hit"] == summary["reachable"], f"coverage holes: {summary['missed']}"
