"""What every ``vqtex`` subcommand shares: the user-error exception, the argument parser class,
JSON or text output, checked atomic output files and loading a texture set with clean errors.

Outputs are written to a temporary file in the destination folder and renamed over the target, so a
failing or interrupted command never leaves a partly written file. The subcommand modules import
this module; it imports none of them.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile

__all__ = ["CliError", "Parser", "block_size", "emit", "check_output", "atomic_write", "write_bytes",
           "write_json", "load_set"]


class CliError(Exception):
    """A user error: printed as one line, exit status 2."""


class Parser(argparse.ArgumentParser):
    """An ``ArgumentParser`` whose errors are one line and exit 2 (argparse would print the usage too)."""

    def error(self, message):
        raise CliError(f"{self.prog}: {message}")


def block_size(text: str) -> tuple[int, int]:
    """``WxH`` (e.g. ``4x4``) as ``(w, h)``; an ``argparse`` type."""
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"block {text!r} is not WxH (e.g. 4x4)") from None
    return w, h


def emit(obj: dict, as_json: bool, text: str) -> None:
    """Print ``obj`` as one JSON object (``--json``) or ``text``."""
    if as_json:
        print(json.dumps(obj, sort_keys=True))
    else:
        print(text)


def check_output(path: str) -> str:
    """The folder of an output file; a CliError if it does not exist."""
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise CliError(f"output folder {folder} does not exist")
    return folder


def atomic_write(path: str, write) -> None:
    """Call ``write(tmp_path)`` then rename over ``path``; never leave a partial file."""
    folder = check_output(path)
    suffix = os.path.splitext(path)[1]
    fd, tmp = tempfile.mkstemp(prefix=".vqtex-", suffix=suffix, dir=folder)
    os.close(fd)
    try:
        write(tmp)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def write_bytes(path: str, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically."""
    def write(tmp):
        with open(tmp, "wb") as f:
            f.write(data)
    atomic_write(path, write)


def write_json(path: str, obj) -> None:
    """Write ``obj`` as indented JSON to ``path`` atomically."""
    write_bytes(path, json.dumps(obj, indent=2, sort_keys=True).encode())


def load_set(path: str):
    """The ``TextureSet`` in ``path``; ``golden.format.FormatError`` (one line) if it is not a valid one."""
    from vqtex.golden.format import TextureSet
    return TextureSet.load(path)
