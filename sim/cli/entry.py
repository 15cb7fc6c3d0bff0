"""The ``vqtex`` command line (see ``docs/usage.md``): the parser and the entry point.

One module per subcommand (``encode``, ``info``, ``decode``, ``simulate`` for ``sim``, ``render``,
``need``, ``prune``, ``demo``, ``export``, ``report``, ``verify``, ``bench``, ``experiments``, ``cache``), each with ``add_parser(sub)``; the
helpers they share are in :mod:`vqtex.sim.cli.common`. This module imports the subcommands, never the
other way round.

Every command that reports takes ``--json`` and then prints exactly one JSON object on stdout.
Bad input, and an allocation that fails (``MemoryError``, numpy's ``_ArrayMemoryError`` among them),
end with a one-line error on stderr and exit status 2, never a traceback and never a partly written
output file: every command's outputs are checked before any work and appear together or not at all
(:class:`vqtex.sim.cli.common.Outputs`). Warnings are one line each on stderr.
"""

from __future__ import annotations

import sys

from . import (bench, cache, decode, demo, encode, experiments, export, import_dt, info, need, prune, render, report,
               simulate, verify)
from .common import CliError, Parser, check_ended, ending_message, ending_signals, exit_status

__all__ = ["main", "build_parser", "version", "memory_message", "COMMANDS"]

#: The subcommand modules, in the order ``vqtex --help`` lists them.
COMMANDS = (encode, import_dt, info, decode, simulate, render, need, prune, demo, export, report, verify, bench,
            experiments, cache)


def build_parser() -> Parser:
    """The ``vqtex`` argument parser with every subcommand."""
    p = Parser(prog="vqtex", description="VQ texture compression and the texel-fetch hardware model "
                                         "(docs/usage.md)")
    p.add_argument("--version", action="version", version=f"vqtex {version()}", help="print the version and exit")
    sub = p.add_subparsers(dest="command", required=True, parser_class=Parser)
    for command in COMMANDS:
        command.add_parser(sub)
    return p


def version() -> str:
    """The installed distribution's version (``pyproject.toml``), or ``unknown`` when not installed."""
    from importlib.metadata import PackageNotFoundError
    from importlib.metadata import version as dist_version
    try:
        return dist_version("vqtex")
    except PackageNotFoundError:
        return "unknown"


def _user_errors():
    from vqtex.golden.encode import EncodeError
    from vqtex.golden.fetch import RequestError
    from vqtex.golden.format import FormatError
    from vqtex.golden.codebook.workers import ThreadSettingError
    from vqtex.golden.render.scene import SceneError
    return (CliError, FormatError, EncodeError, RequestError, SceneError, ThreadSettingError, OSError)


def memory_message(e: MemoryError) -> str:
    """One line for an allocation that failed (numpy says how much and of what shape)."""
    text = " ".join(str(e).split())
    return "out of memory" + (f": {text}" if text else "") + " (free memory, or a smaller input or level)"


def main(argv=None) -> int:
    """Run ``vqtex`` with ``argv``; returns the exit status: 2 for a user error or a failed allocation
    (``MemoryError``: one line, no traceback), 128 + signum when
    SIGINT, SIGTERM or SIGHUP ended it (130, 143, 129; :func:`~vqtex.sim.cli.common.ending_signals`:
    outputs removed as at any error, one line on stderr)."""
    with ending_signals():
        try:
            args = build_parser().parse_args(argv)
            code = args.func(args) or 0
            check_ended()                       # a signal whose exception Python lost on the way
            return code
        except _user_errors() as e:
            msg = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
            print(f"vqtex: error: {msg}", file=sys.stderr)
            return 2
        except MemoryError as e:                # numpy's _ArrayMemoryError among them; outputs removed as at any error
            print(f"vqtex: error: {memory_message(e)}", file=sys.stderr)
            return 2
        except KeyboardInterrupt as e:
            print(ending_message(e), file=sys.stderr)
            return exit_status(e)


if __name__ == "__main__":
    sys.exit(main())
