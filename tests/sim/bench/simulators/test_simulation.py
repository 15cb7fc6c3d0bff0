"""``vqtex bench sim`` on a short stream: every backend agrees with golden and every rate is reported."""

import json

from vqtex.hw.texel_fetch import LATENCY
from vqtex.sim.bench.simulators import simulation as bench_sim

from tests.support import need


def test_bench_sim_reports_agreeing_rates(capsys, monkeypatch):
    need("g++")
    monkeypatch.setenv("VQTEX_SIM_THREADS", "2")       # both thread counts, whatever the machine
    report = bench_sim.run(json_out=True, n_compiled=3000, n_pysim=40, backends=("pysim", "cxxrtl"))
    printed = json.loads(capsys.readouterr().out)
    assert printed == json.loads(json.dumps(report, sort_keys=True))
    rows = report["backends"]
    assert rows["pysim"]["agrees_with_golden"] and rows["cxxrtl"]["agrees_with_golden"]
    assert rows["cxxrtl"]["cycles"] == 3000 + LATENCY
    assert rows["cxxrtl"]["cycles_per_s"] > 0 and rows["cxxrtl"]["cycles_per_s_in_library"] > 0
    assert rows["cxxrtl"]["speedup_vs_pysim"] > 1
    assert rows["cxxrtl"]["threads"] == 2 and rows["cxxrtl 1t"]["threads"] == 1
    assert rows["cxxrtl 1t"]["agrees_with_golden"] and rows["cxxrtl 1t"]["cycles_per_s"] > 0
