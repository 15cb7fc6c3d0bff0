"""``vqtex cache info|clean``: the build cache of the compiled backends (CXXRTL, Verilator).

The cache (``$VQTEX_CACHE``, default ``~/.cache/vqtex``) is bounded by ``$VQTEX_CACHE_MAX_MB``
(default 1024 MB) with least-recently-used eviction after every build
(:mod:`vqtex.sim.backends.toolchain`); ``clean`` empties it, or trims it to ``--keep-mb``.
"""

from __future__ import annotations

import time

from . import limits
from .common import CliError, add_json, emit, number_help

__all__ = ["add_parser", "cmd_cache"]


def _mb(n: int) -> str:
    return f"{n / 2**20:.1f} MB"


def cmd_cache(args) -> int:
    from vqtex.sim.backends import toolchain
    if args.action == "info":
        if args.keep_mb is not None:
            raise CliError("--keep-mb is an option of 'vqtex cache clean'")
        rep = toolchain.cache_info()
        bound = "no bound" if rep["max_bytes"] == 0 else f"bound {_mb(rep['max_bytes'])} ($VQTEX_CACHE_MAX_MB)"
        lines = [f"{rep['folder']}: {rep['entries']} builds, {_mb(rep['bytes'])} ({bound})"]
        for kind, k in sorted(rep["kinds"].items()):
            lines.append(f"  {kind:<18} {k['entries']:>4} builds {_mb(k['bytes']):>10}")
        if rep["failed_builds"]:
            lines.append(f"  failed builds kept  {rep['failed_builds']:>3}      {_mb(rep['failed_bytes']):>10}")
        if rep["oldest_use"] is not None:
            lines.append("  least recently used " + time.strftime("%Y-%m-%d %H:%M", time.localtime(rep["oldest_use"])))
        emit(rep, args.json, "\n".join(lines))
        return 0
    rep = toolchain.cache_clean(int((args.keep_mb or 0.0) * 2**20))
    emit(rep, args.json, f"removed {rep['removed']} builds, freed {_mb(rep['freed_bytes'])}; "
                         f"{_mb(rep['bytes_left'])} left in {toolchain.cache_dir()}")
    return 0


def add_parser(sub) -> None:
    c = sub.add_parser("cache", help="the build cache of the compiled backends: info, clean")
    c.add_argument("action", choices=["info", "clean"],
                   help="info: what the cache holds; clean: delete builds (they are rebuilt when needed)")
    c.add_argument("--keep-mb", type=limits.KEEP_MB, default=None,
                   help=number_help("clean: keep the most recently used builds up to this many MB; "
                                    "0 deletes everything", limits.KEEP_MB, 0))
    add_json(c)
    c.set_defaults(func=cmd_cache)
