"""golden.memory.external and golden.memory.dram: the read contract, fixed latency and bandwidth,
and the DDR3 part's banks, rows and refresh."""

import numpy as np
import pytest

from vqtex.golden.memory.dram import MT41K256M16_125, DramMemory
from vqtex.golden.memory.external import FixedMemory, beat_interval


def bursts(rng, n, spread):
    t = np.cumsum(rng.integers(0, spread, n))
    beats = rng.choice([1, 2, 4, 8], n)
    address = rng.integers(0, 1 << 20, n) * 64
    return t, address, beats


@pytest.mark.parametrize("latency,bw,bus", [(1, 16, 16), (5, 4, 16), (100, 16, 16), (300, 1, 4), (7, 64, 16)])
def test_fixed_reads_equal_one_at_a_time(latency, bw, bus):
    rng = np.random.default_rng(latency)
    t, address, beats = bursts(rng, 300, 12)
    a = FixedMemory(latency, bw, bus)
    b = FixedMemory(latency, bw, bus)
    one = [a.read(x, y, z) for x, y, z in zip(t.tolist(), address.tolist(), beats.tolist())]
    assert b.reads(t, address, beats).tolist() == one
    # the rule, written out: the R channel is never busy twice, and never early
    d = a.beat_interval
    free = 0
    for x, z, f in zip(t.tolist(), beats.tolist(), one):
        assert f == max(x + latency, free)
        free = f + z * d


def test_fixed_memory_bandwidth_bounds_the_stream():
    m = FixedMemory(10, 4, 16)                   # a 16-byte beat every 4 cycles
    first = m.reads(np.zeros(10, np.int64), np.zeros(10, np.int64), np.full(10, 2))
    assert np.diff(first).tolist() == [8] * 9    # 32 bytes at 4 bytes/clock
    assert first[0] == 10


@pytest.mark.parametrize("bus,bw", [(16, 3), (16, 0), (0, 4), (16, 2.5)])
def test_bad_bandwidths_are_refused(bus, bw):
    with pytest.raises(ValueError):
        beat_interval(bus, bw)


def test_zero_latency_is_refused():
    with pytest.raises(ValueError):
        FixedMemory(0, 16, 16)


def test_ddr3_1600_timings_at_200_mhz():
    """The datasheet's nanoseconds and clocks in 5 ns controller cycles, rounded up."""
    m = DramMemory(MT41K256M16_125, bus_bytes=16, clock_mhz=200)
    t = m.timings
    # CL 11 x 1.25 = 13.75 ns; tRCD = tRP = 13.75 ns; tRAS 35; tRC 48.75; tRFC 260; tREFI 7800
    assert (t["CL"], t["tRCD"], t["tRP"], t["tRAS"], t["tRC"]) == (3, 3, 3, 7, 10)
    assert (t["tRFC"], t["tREFI"], t["tFAW"]) == (52, 1560, 8)
    assert (t["tRRD"], t["tRTP"]) == (2, 2)        # max(4 tCK = 5 ns, 7.5 ns)
    assert m.dram_bytes_per_clock == 16 and m.beat_interval == 1
    assert DramMemory(bus_bytes=64, clock_mhz=200).beat_interval == 4


def test_dram_rows_and_banks():
    m = DramMemory(bus_bytes=16, clock_mhz=200)
    T = m.timings
    page = MT41K256M16_125.page_bytes
    row_stride = page * MT41K256M16_125.banks
    # bank 0 closed: ACT, tRCD, CL
    f0 = m.read(0, 0, 2)
    assert f0 == T["tRCD"] + T["CL"] and m.row_misses == 1
    # same row: a column command as soon as the previous burst's data has left
    f1 = m.read(f0 + 10, 64, 2)
    assert f1 == f0 + 10 + T["CL"] and m.row_hits == 1
    # another row of bank 0: precharge (tRAS from the ACT is long past), tRP, ACT, tRCD
    t2 = f1 + 20
    f2 = m.read(t2, row_stride, 2)
    assert f2 == t2 + T["tRP"] + T["tRCD"] + T["CL"] and m.row_conflicts == 1
    # bank 1 while bank 0 stays open: no precharge
    t3 = f2 + 20
    f3 = m.read(t3, page, 2)
    assert f3 == t3 + T["tRCD"] + T["CL"]
    # a row conflict right after its ACT waits for tRAS
    m.reset()
    a = m.read(0, 0, 1) - T["CL"] - T["tRCD"]          # the ACT's cycle (0)
    f = m.read(1, row_stride, 1)
    assert f == a + T["tRAS"] + T["tRP"] + T["tRCD"] + T["CL"]
    # in order: a burst arriving together with another waits for its data to leave
    m.reset()
    f = m.reads(np.zeros(3, np.int64), np.array([0, 64, 128]), np.array([4, 4, 4]))
    assert np.diff(f).tolist() == [4, 4]
    assert m.queued == f[-1] - T["CL"]                # a row hit at cycle 0 but for the two before it


def test_dram_refresh_closes_rows_and_delays():
    m = DramMemory(bus_bytes=16, clock_mhz=200)
    T = m.timings
    m.read(0, 0, 2)                                  # bank 0 row 0 open
    t = T["tREFI"]                                    # a burst when the first refresh falls due
    f = m.read(t, 64, 2)                              # the same row, but refresh closed it
    assert m.refreshes == 1 and m.row_misses == 2
    assert f == t + T["tRP"] + T["tRFC"] + T["tRCD"] + T["CL"]
    # idle for ten refresh intervals: all done in the background, the burst only finds rows closed
    t = 12 * T["tREFI"] + 100
    f = m.read(t, 64, 2)
    assert m.refreshes == 12 and f == t + T["tRCD"] + T["CL"]


def test_dram_reads_equal_one_at_a_time_and_refuse_far_addresses():
    rng = np.random.default_rng(3)
    t, address, beats = bursts(rng, 400, 40)
    a, b = DramMemory(), DramMemory()
    one = [a.read(x, y, z) for x, y, z in zip(t.tolist(), address.tolist(), beats.tolist())]
    assert b.reads(t, address, beats).tolist() == one
    assert all(f >= x + 1 for f, x in zip(one, t.tolist()))
    assert a.refreshes >= 1
    with pytest.raises(ValueError, match="beyond"):
        DramMemory().read(0, MT41K256M16_125.bytes, 1)
