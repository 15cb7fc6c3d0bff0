"""cocotb testbench of the exported vqtex texel-fetch unit (written by ``vqtex export --testbench DIR``).

Run it with ``python run_tb.py`` beside it (``SIM=icarus`` or ``SIM=verilator``; ``--help``). What
it does, in one cocotb test, ``texel_fetch_against_golden``:

1. **Reset** (``rst`` high for three clock edges; nothing is driven at time 0, see :func:`_start`).
2. **Load** (the loadable units only): every bus write of ``golden.register_map.load_writes(set,
   geometry)`` (colour matrix, every descriptor row, the index, codebook and raw memories) through the
   ``bus_*`` Wishbone port by cocotbext-wishbone's ``WishboneMaster``; every write must be acked.
   Then the **port check** (:meth:`Host.check_port`): reads of the control registers and a few
   words answer ``golden.register_map.expected_reads``, addresses beyond the map answer ``err``.
   The baked units hold the set in their ROMs already (the bench checks the set is the one baked in).
   **Memory** (the external-memory units, ``memory`` in the configuration): cocotbext-axi's
   ``AxiRamRead`` answers the ``axi_*`` master, with its own ``arready`` and R timing, from the set's
   memory image (``golden.memory.system.Layout.image``): the baked cached unit's at ``Layout.of``
   (the index map at 0, the raw levels from the next 4 KB); the loadable cached unit's where the
   bench puts it (:func:`placements`) and tells the unit by the ``INDEX_BASE``/``RAW_BASE`` writes
   of its load.
   **Several loads** (the loadable units): steps 2-5 run for each set given (``VQTEX_TB_SET``, a
   path list) in turn, in one simulation, each at other bases overlapping the previous placement;
   the loadable cached unit given one set loads it, then :func:`other_bytes` of it at the same
   bases (:func:`loads`), the probe request (:func:`probe`) the last of the first load and the
   first of the second, so a line kept from the first load is hit and holds other bytes.
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
   golden caches' misses of the stream since the load, in order (``golden.memory.timing.plan`` with
   the load's layout: the lines,
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
``VQTEX_TB_GAP``, ``VQTEX_TB_PER_BIN``, ``VQTEX_TB_SET`` (other texture sets, ``os.pathsep``
between them: the loadable unit loads each in turn; a baked unit refuses any set but its own),
``VQTEX_TB_REPORT`` (the coverage JSON).
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
    given = [p for p in env.get("VQTEX_TB_SET", "").split(os.pathsep) if p]
    cfg["set_paths"] = given or [os.path.join(HERE, cfg["set"])]
    cfg["set_path"] = cfg["set_paths"][0]
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
        self.layout = None                  # where the set lies in external memory (Layout.of by default)
        self.history = np.zeros((0, 4), np.int64)   # every request since the load (the caches' state is the stream's)
        self.bursts: list = []              # (address, beats) of every AR handshake
        self.first_burst = 0                # the first of them since the load
        self.memory_hits = {"hit": 0, "miss": 0}

    def begin(self, ts: TextureSet, layout=None):
        """A set is loaded (or, baked, was there from reset): the scoreboard's set, and empty caches
        (every accepted bus write empties them; golden's model starts each stream empty)."""
        self.ts, self.layout = ts, layout
        self.history = np.zeros((0, 4), np.int64)
        self.first_burst = len(self.bursts)

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
            missed = memory_plan(self.ts, self.history, self.memory, layout=self.layout).misses[-len(req):] > 0
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
        """The bursts since the load are golden's misses of the stream since the load, in order (with
        the layout the base registers give): every line the stream needs is read, none twice while it
        stays in the cache (nor while its burst is in flight), none of the previous set's lines hit."""
        p = memory_plan(self.ts, self.history, self.memory, layout=self.layout)
        want = list(zip(p.address.tolist(), p.beats.tolist()))
        got = self.bursts[self.first_burst:]
        if got != want:
            first = next((n for n, (a, b) in enumerate(zip(got, want)) if a != b), min(len(got), len(want)))
            self.mismatches.append(f"{len(got)} bursts, golden's caches miss {len(want)} times; first "
                                   f"difference at burst {first}: "
                                   f"{got[first] if first < len(got) else None} != "
                                   f"{want[first] if first < len(want) else None} (address, beats)")
        return {"bursts": len(got), "golden_bursts": len(want),
                "references": {"index": int(p.references[0]), "raw": int(p.references[1])},
                "hits": {"index": int(p.hits[0]), "raw": int(p.hits[1])},
                "hit_rate": {"index": round(p.hits[0] / max(1, p.references[0]), 4),
                             "raw": round(p.hits[1] / max(1, p.references[1]), 4)}}

    def check_latency(self, latency: int) -> dict:
        """A response shows ``latency`` cycles after its request was taken when no output stall or
        one-port bubble came between (hw.texel_fetch: "presented on o in cycle t + LATENCY"), and never sooner.
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


async def _start(dut, memory_bytes: int = 0):
    """Clock and reset; with ``memory_bytes``, cocotbext-axi's AxiRamRead of that size answers the
    ``axi_*`` master (returned: the host writes the sets' images into it). Nothing is driven at time
    0: Icarus 11 does not propagate a VPI write made then to the logic that reads the port (iverilog
    issues #1041/#1111, cocotb #4886)."""
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
    ram = None
    if memory_bytes:
        from cocotbext.axi import AxiRamRead, AxiReadBus
        ram = AxiRamRead(AxiReadBus.from_prefix(dut, "axi"), dut.clk, dut.rst, size=memory_bytes)
    for _ in range(3):
        await RisingEdge(dut.clk)
    dut.rst.value = 0
    await RisingEdge(dut.clk)
    return ram


def placements(sets: list, rng, reload: bool = False) -> list:
    """Where the host puts each load's set in external memory (the loadable cached unit; its
    ``INDEX_BASE`` and ``RAW_BASE``): ``Layout.at`` with the index base an odd number of index words
    past 4 KB and the raw base an odd number of 4-byte words past the next 64-byte boundary after the
    index memory (so neither is on a cache line of two words or more), both moving from one load to
    the next while the regions overlap: the host reuses its buffer, so a line the caches kept from
    the previous load holds other bytes at the same address, and only emptied caches give golden's
    texels and golden's bursts. ``reload`` (``sets`` a set and its :func:`other_bytes`): the second
    load at the first one's bases, so every line the caches kept holds the first set's bytes at an
    address the second set reads, other bytes there (:func:`probe`)."""
    out = []
    for k, ts in enumerate(sets):
        if reload and k:
            out.append(Layout.at(ts, out[0].index_base, out[0].raw_base))
            continue
        wb = ts.word_bits // 8
        index_base = 4096 + wb * int(1 + 8 * k + 2 * rng.integers(0, 4))
        index_end = index_base + len(ts.index_words) * wb
        raw_base = -(-index_end // 64) * 64 + 4 * int(1 + 8 * k + 2 * rng.integers(0, 4))
        out.append(Layout.at(ts, index_base, raw_base))
    return out


def other_bytes(ts: TextureSet) -> TextureSet:
    """``ts`` with other bytes in external memory and the same geometry, layout and on-chip memories
    (descriptors, codebook, colour matrix): every index ``x`` of a codebook of ``n`` entries becomes
    ``n - 1 - x`` (still inside its codebook), every raw word is inverted. The loadable cached unit's
    reload (:func:`loads`): a line kept from ``ts`` at the same bases answers ``ts``'s words, so a
    request reading it gets ``fetch(ts, ...)`` where ``fetch(other_bytes(ts), ...)`` is due."""
    from dataclasses import replace
    from vqtex.golden.format import pack_indices, unpack_indices
    words = np.array(ts.index_words, copy=True)
    done = set()
    for _t, _level, base, b, n, size in ts.index_maps():
        if base in done:
            continue                    # a map shared by two textures once
        done.add(base)
        packed = pack_indices(size - 1 - unpack_indices(ts.index_words, b, n, base, ts.word_bits), b, ts.word_bits)
        last = np.asarray(ts.index_words[base + len(packed) - 1]).astype(np.uint64)
        spare = np.uint64(((1 << ts.word_bits) - 1) ^ ((1 << ((n * b - 1) % ts.word_bits + 1)) - 1))
        packed[-1] |= (last & spare).astype(packed.dtype)      # the bits past the map's last index kept
        words[base: base + len(packed)] = packed
    out = replace(ts, index_words=words, raw_words=~np.asarray(ts.raw_words))
    out.check_indices()
    return out


def probe(ts: TextureSet, reload: TextureSet, rng, n: int = 256) -> np.ndarray:
    """A request (1, 4) whose texel differs between ``ts`` and ``reload`` (:func:`other_bytes`):
    the last request of ``ts``'s load and the first of the reload's, at the same bases. Its lines
    are in the caches when the reload starts (nothing was read after them), so a reader the reload
    did not empty answers it with ``ts``'s texel and fails the scoreboard; an emptied one misses."""
    cand = random_requests(ts, n, seed=int(rng.integers(0, 2**31)))
    differ = np.flatnonzero((fetch(ts, *cand.T) != fetch(reload, *cand.T)).any(axis=1))
    assert len(differ), f"no request of {n} reads other texels after the reload (other_bytes)"
    return cand[differ[:1]]


class Host:
    """The host side of a loadable unit's Wishbone port ``bus_*``: cocotbext-wishbone's
    ``WishboneMaster`` (one for the whole run) with the register map (``RegisterMap(geometry,
    external)``: the loadable cached unit's map when ``external``)."""

    SIGNALS = {"cyc": "cyc", "stb": "stb", "we": "we", "adr": "adr", "datwr": "dat_w", "datrd": "dat_r",
               "ack": "ack", "err": "err", "stall": "stall", "sel": "sel"}

    def __init__(self, dut, geometry, external: bool):
        from cocotbext.wishbone.driver import WishboneMaster
        from vqtex.golden.register_map import RegisterMap
        self.wb = WishboneMaster(dut, "bus", dut.clk, width=32, timeout=BUS_TIMEOUT, signals_dict=self.SIGNALS)
        self.geometry, self.rmap = geometry, RegisterMap(geometry, external=external)

    async def load(self, ts: TextureSet, name: str, layout, log) -> int:
        """Every write of ``load_writes(ts, geometry, layout)``; each must be acked. Returns their number."""
        from cocotbext.wishbone.driver import WBOp
        from vqtex.golden.register_map import load_writes
        writes = load_writes(ts, self.geometry, layout)
        ops = [WBOp(adr=int(a), dat=int(d), sel=1, acktimeout=BUS_TIMEOUT) for a, d in writes.tolist()]
        results = await self.wb.send_cycle(ops)
        refused = [f"0x{int(r.adr):x}" for r in results if int(r.ack) != 1]
        assert len(results) == len(ops) and not refused, f"bus load: {len(refused)} write(s) not acked: {refused[:8]}"
        log.info("loaded %s: %d Wishbone writes, all acked%s", name, len(ops),
                 f"; index base 0x{layout.index_base:x}, raw base 0x{layout.raw_base:x}" if layout else "")
        return len(ops)

    def probe_addresses(self, written) -> tuple:
        """(reads, writes): every control register, the first descriptor row, the first codebook
        entry's first word, the index and raw regions' first words, a word of regions 5 and 7 (unmapped),
        each either unmapped or ``written`` by the load (another word holds what an earlier load left);
        and writes to what answers ``err`` to a write (the read-only ``ID``, region 5, the index and raw
        regions of the loadable cached unit: its words are in external memory)."""
        from vqtex.golden.register_map import mapped_words
        rmap, top = self.rmap, (1 << self.rmap.offset_bits) - 1
        control = rmap.address("control", [off for off, _, _ in rmap.control.values()])
        reads = np.concatenate([rmap.address("control", sorted(off for off, _, _ in rmap.control.values())),
                                rmap.address("descriptors", np.arange(4)), rmap.address("codebook", [0]),
                                rmap.address("index", [0]), rmap.address("raw", [0]),
                                np.array([5 << rmap.offset_bits, (7 << rmap.offset_bits) | top], np.uint64)])
        writes = np.concatenate([rmap.address("control", [rmap.control["ID"][0]]), rmap.address("index", [0]),
                                 rmap.address("raw", [0]), np.array([5 << rmap.offset_bits], np.uint64)])
        known = np.isin(reads, control) | np.isin(reads, np.asarray(written, np.uint64)) | ~mapped_words(rmap, reads)
        return reads[known], writes[~mapped_words(rmap, writes, write=True)]

    async def check_port(self, ts: TextureSet, layout, mismatches: list) -> dict:
        """After a load: the reads of :meth:`probe_addresses` answer ``golden.register_map.expected_reads``
        (data, or ``err`` where the map holds no word: an address out of range), and the writes to
        addresses that take none answer ``err``. The writes go first (they change nothing)."""
        from cocotbext.wishbone.driver import WBOp
        from vqtex.golden.register_map import expected_reads, load_writes
        reads, writes = self.probe_addresses(load_writes(ts, self.geometry, layout)[:, 0])
        data, err = expected_reads(ts, self.geometry, reads, layout)
        ops = [WBOp(adr=int(a), dat=0, sel=1, acktimeout=BUS_TIMEOUT) for a in writes.tolist()]
        ops += [WBOp(adr=int(a), dat=None, sel=1, acktimeout=BUS_TIMEOUT) for a in reads.tolist()]
        results = await self.wb.send_cycle(ops)
        want = [(2, None)] * len(writes) + [(2, None) if e else (1, int(d)) for d, e in zip(data.tolist(), err.tolist())]
        for op, res, (code, value) in zip(ops, results, want):
            got = (int(res.ack), _int(res.datrd) if code == 1 and op.dat is None else None)
            if got != (code, value):
                kind = "write" if op.dat is not None else "read"
                mismatches.append(f"bus {kind} of 0x{op.adr:x}: answered {'ack' if got[0] == 1 else 'err' if got[0] == 2 else got[0]}"
                                  f"{'' if got[1] is None else f' 0x{got[1]:x}' if isinstance(got[1], int) else ' ' + got[1]}, "
                                  f"expected {'ack' if code == 1 else 'err'}{'' if value is None else f' 0x{value:x}'} "
                                  "(golden.register_map)")
        return {"reads": len(reads), "writes": len(writes), "errors_expected": int(err.sum()) + len(writes),
                "errors": sum(int(r.ack) == 2 for r in results)}


def _check_set(ts: TextureSet, cfg: dict, path: str):
    """A baked unit answers for the set it was exported with only; a loadable one for any set that
    fits its geometry."""
    if cfg["unit"] == "loadable":
        from vqtex.golden.geometry import Geometry
        misfit = Geometry.loads(cfg["geometry"], "tb_config.json").fits(ts)
        assert not misfit, f"{path} does not fit the unit's geometry: {'; '.join(misfit)}"
        return
    from vqtex.sim.testbench.write import set_digest
    assert set_digest(ts) == cfg["set_digest"], (
        f"{path} is not the texture set baked into this {cfg['unit']} unit (its ROMs hold "
        f"{cfg['set']}); export the Verilog for it, or export --unit loadable")


def loads(cfg: dict, sets: list) -> list:
    """The sets the run serves, in turn: a baked unit its own (no load); a loadable unit each set
    given, loaded over the bus one after the other in one simulation; the loadable cached unit given
    one set loads it, then reloads it with :func:`other_bytes` at the same bases (:func:`placements`,
    :func:`probe`)."""
    if cfg["unit"] == "loadable" and cfg["memory"] is not None and len(sets) == 1:
        return [sets[0], other_bytes(sets[0])]
    return sets


@cocotb.test()
async def texel_fetch_against_golden(dut):
    cfg = settings()
    sets, names = [], {}
    for path in cfg["set_paths"]:
        ts = TextureSet.load(path)
        _check_set(ts, cfg, path)
        sets.append(ts)
        names[id(ts)] = os.path.basename(path)
    run = loads(cfg, sets)
    reload = len(run) > len(sets)           # the loadable cached unit's one set, then its other_bytes
    if reload:
        names[id(run[1])] = names[id(sets[0])] + " (other bytes)"
    rng = np.random.default_rng(cfg["seed"])
    cands = [candidates(ts) for ts in run]
    reachable = {(*key, stall) for c in cands for key in c for stall in (False, True)}
    coverage = Coverage(reachable)
    loadable, external = cfg["unit"] == "loadable", cfg["memory"] is not None
    dut._log.info("%s: %d load(s) of %d set(s), %d reachable bins; %d requests per load, seed %d, stall %.2f, gap %.2f",
                  ", ".join(cfg["set_paths"]), len(run), len(sets), len(reachable), cfg["requests"], cfg["seed"],
                  cfg["stall"], cfg["gap"])
    # where each set lies in external memory: the loadable cached unit's bases, else Layout.of
    layouts = (placements(run, rng, reload) if loadable else [Layout.of(ts) for ts in run]) if external else [None] * len(run)
    size = max((-(-lay.end // 4096) * 4096 for lay in layouts if lay is not None), default=0)
    ram = await _start(dut, size)
    host = None
    if loadable:
        from vqtex.golden.geometry import Geometry
        host = Host(dut, Geometry.loads(cfg["geometry"], "tb_config.json"), external)
    bench = Bench(dut, run[0], cfg, coverage, rng)
    strobes = cocotb.start_soon(bench.count_strobes()) if hasattr(dut, "straddle") else None
    ar = cocotb.start_soon(bench.watch_ar(size)) if external else None

    per_load, closure_total, random_total, reload_total, after_random = [], 0, 0, 0, set()
    last = probe(run[0], run[1], rng) if reload else None
    for k, (ts, layout, cand) in enumerate(zip(run, layouts, cands)):
        entry = {"set": names[id(ts)]}
        if ram is not None:                 # the host writes the set's bytes where its bases say
            ram.write(layout.index_base, layout.image(ts)[layout.index_base:layout.end])
            entry.update(index_base=layout.index_base, raw_base=layout.raw_base)
        if host is not None:
            entry["writes"] = await host.load(ts, entry["set"], layout if external else None, dut._log)
            entry["port"] = await host.check_port(ts, layout if external else None, bench.mismatches)
        bench.begin(ts, layout)
        entry["first_response"] = bench.received
        if reload and k == 1:               # the reload's first request: the lines the first load read last
            await bench.run(last, [None])
            reload_total += 1
        req = random_phase(ts, cand, cfg["requests"], cfg["per_bin"], rng)
        await bench.run(req, [None] * len(req))
        after_random |= coverage.hit() & reachable
        # Closure: one request per bin of this set still missed, its backpressure forced to the bin's stall value.
        mine = {(*key, stall) for key in cand for stall in (False, True)}
        holes = sorted(mine - coverage.hit(), key=str)
        closure = [(_inside_blocks(ts, cand[key[:4]][rng.integers(0, len(cand[key[:4]]), 1)], rng)[0], key[4])
                   for key in holes]
        if external and bench.memory_hits["hit"] == 0 and len(bench.history):
            # a request's lines stay cached after it is read: its repeat hits (golden says whether it did)
            closure.append((closure[-1][0] if closure else bench.history[-1], False))
        if closure:
            creq = np.array([c[0] for c in closure], np.int64)
            await bench.run(creq, [c[1] for c in closure])
        if reload and k == 0:               # the first load's last request: its lines stay in the caches
            await bench.run(last, [None])
            reload_total += 1
        random_total, closure_total = random_total + len(req), closure_total + len(closure)
        if external:
            entry.update(bench.check_bursts())
        per_load.append(entry)
    await bench.quiet(cfg["latency"] + 8)
    memory = {}
    if ar is not None:
        ar.cancel()
        refs = {c: sum(e["references"][c] for e in per_load) for c in ("index", "raw")}
        hits = {c: sum(e["hits"][c] for e in per_load) for c in ("index", "raw")}
        memory = {"bursts": sum(e["bursts"] for e in per_load), "golden_bursts": sum(e["golden_bursts"] for e in per_load),
                  "hit_rate": {c: round(hits[c] / max(1, refs[c]), 4) for c in refs},      # (golden's, over every load)
                  "memory_bins": dict(bench.memory_hits)}
        for outcome, count in bench.memory_hits.items():
            if not count:
                bench.mismatches.append(f"memory coverage: no request {'missed' if outcome == 'miss' else 'hit'}")
    if strobes is not None:
        strobes.cancel()
        bench.check_strobes()
    timing = bench.check_latency(cfg["latency"])

    phases = {"requests": {"random": random_total, "closure": closure_total, "reload": reload_total},
              "hit_by_random": len(after_random), "hit_by_closure": len((coverage.hit() & reachable) - after_random),
              "mismatches": len(bench.mismatches), "responses": bench.received,
              "straddling_requests": bench.straddling, "straddle_strobes": bench.strobes["straddle"], **timing,
              "set": os.path.basename(cfg["set_path"]), "sets": [names[id(ts)] for ts in sets],
              "unit": cfg["unit"], "seed": cfg["seed"], "stall": cfg["stall"], "simulator": cocotb.SIM_NAME,
              **memory, **({"loads": per_load} if loadable else {})}
    summary = coverage.report(dut._log, cfg["report"], phases)
    dut._log.info("coverage: %d of %d reachable bins (%.1f %%): %d by the random phase, %d by closure; %d responses, "
                  "%d mismatches", summary["hit"], summary["reachable"], summary["percent"], summary["hit_by_random"],
                  summary["hit_by_closure"], bench.received, len(bench.mismatches))
    assert not bench.mismatches, f"{len(bench.mismatches)} mismatches:\n" + "\n".join(bench.mismatches[:20])
    assert summary["hit"] == summary["reachable"], f"coverage holes: {summary['missed']}"
