"""``python -m vqtex.sim.cli ...``: the same as the ``vqtex`` command.

Run by ``-m``, CPython (3.8 on) ends the process by SIGINT at exit (status -2, not the 130 that
:func:`~vqtex.sim.cli.entry.main` returns) when a ``KeyboardInterrupt`` ever left an ``exec`` or
``eval`` of a string, even one the program caught: such a call sets the interpreter's "unhandled
KeyboardInterrupt" flag and nothing clears it. Imports run such calls (dataclasses, namedtuple), so
Ctrl-C during a lazy import hit it. Every ``exec`` of a string clears the flag when it starts, so
one empty ``exec`` after the command leaves the exit status to the command. The ``vqtex`` script is
run as a file, where ``sys.exit`` ends the process first. tests/sim/cli/test_signals.py checks it.
"""

import sys

from .entry import main

try:
    code = main()
finally:
    exec("")        # clears CPython's stale unhandled-KeyboardInterrupt flag (see above)
sys.exit(code)
