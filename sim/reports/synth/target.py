"""What every part of the synthesis flow shares: the target part, the names Yosys sees, the error."""

from __future__ import annotations

__all__ = ["SynthError", "INSTALL_HINT", "DEVICE", "HARNESS_NAME", "UNIT_NAME"]

INSTALL_HINT = "pip install '.[synth]'"

#: The target part: Lattice LFE5U-85F, speed grade 8, CABGA381 package.
DEVICE = {"family": "ecp5", "device": "LFE5U-85F", "nextpnr_device": "--85k", "speed": 8,
          "package": "CABGA381"}

#: The module names Yosys sees (Amaranth names submodules ``top.sub``).
HARNESS_NAME = "vqtex_harness"
UNIT_NAME = f"{HARNESS_NAME}.unit"


class SynthError(OSError):
    """A synthesis / place-and-route tool is missing or failed. ``str()`` is one line."""
