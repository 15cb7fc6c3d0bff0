"""``python -m vqtex.sim.cli ...``: the same as the ``vqtex`` command."""

import sys

from .entry import main

sys.exit(main())
