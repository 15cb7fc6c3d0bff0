"""The ``vqtex`` command line: ``main`` (the console script) and one module per subcommand."""

from .entry import main

__all__ = ["main"]
