"""Request files from outside: texel-fetch requests ``(texture, level, i, j)`` as int64 rows.

Two formats, told apart by their first bytes (a ``.npy`` name without the ``.npy`` magic is refused):

* ``.npy`` -- an integer array of shape (N, 4), any integer dtype and byte order, C or Fortran order.
  The header is read and checked before any data: no pickles or object dtypes, no structured (comma)
  dtypes, shape (N, 4), and N exactly what the file's remaining bytes hold, so a file cannot make the
  reader allocate more than about 4x its size (int64 of a narrower dtype).
* CSV -- four integer columns, one request per line, an optional header row (a first line with a
  field that starts with a letter), ``#`` comments; at most :data:`MAX_CSV_BYTES` bytes (the result is at most 4x the
  text: a row is at least 8 bytes, its int64s 32).

The same reader takes the texture filter's per-pixel inputs (``columns=7``: :data:`PIXEL_COLUMNS`,
``vqtex sim --filter-lanes``): the same formats with seven columns.

Any failure raises :class:`~golden.fetch.RequestError` with a one-line message naming the file. The
values are not checked against a texture set here: that is :func:`golden.fetch.check_requests`.
"""

from __future__ import annotations

import io
import os
import warnings

import numpy as np

from .fetch import RequestError

__all__ = ["read_request_file", "MAX_REQUESTS", "MAX_CSV_BYTES", "REQUEST_COLUMNS", "PIXEL_COLUMNS"]

#: Most requests a ``.npy`` header may claim (2^28 requests, 8 GiB of int64).
MAX_REQUESTS = 1 << 28
#: Largest CSV request file (bigger streams belong in ``.npy``).
MAX_CSV_BYTES = 1 << 30
_NPY_MAGIC = b"\x93NUMPY"
#: A texel-fetch request's columns.
REQUEST_COLUMNS = ("texture", "level", "i", "j")
#: The texture filter's per-pixel inputs, one row a pixel (``sim.backends.filter.FIELDS``' order; ``s``
#: and ``t`` in fixed point, ``golden.filter``'s codes for ``mode`` and the addressing).
PIXEL_COLUMNS = ("texture", "s", "t", "lod", "mode", "address_s", "address_t")
_WORDS = {4: "four", 7: "seven"}


def read_request_file(path: str | os.PathLike, columns: tuple = REQUEST_COLUMNS) -> np.ndarray:
    """The requests of ``path`` (``.npy`` or CSV, see the module docstring) as int64 (N, 4); with
    ``columns`` :data:`PIXEL_COLUMNS`, the filter's pixels as int64 (N, 7).

    Raises:
        RequestError: one line naming the file: unreadable, not an ``.npy`` array / CSV of four
            integer columns, a pickle or non-integer dtype, a header whose N disagrees with the
            file's size, a value that does not fit in int64, or a CSV larger than :data:`MAX_CSV_BYTES`.
    """
    path = os.fspath(path)
    try:
        with open(path, "rb") as f:
            size = os.fstat(f.fileno()).st_size
            if f.read(len(_NPY_MAGIC)) == _NPY_MAGIC:
                f.seek(0)
                return _read_npy(f, size, path, columns)
            if path.endswith(".npy"):
                raise RequestError(f"{path}: not an .npy file (no .npy magic)")
            if size > MAX_CSV_BYTES:
                raise RequestError(f"{path}: a CSV of {size} bytes, more than {MAX_CSV_BYTES} (use .npy)")
            f.seek(0)
            text = f.read(size + 1)                   # sized by the checked length, not the bound
            if len(text) > size:
                raise RequestError(f"{path}: the file grew while it was read")
    except OSError as e:
        raise RequestError(f"{path}: cannot read: {e.strerror or e}") from None
    return _parse_csv(text, path, columns)


def _read_npy(f, size: int, path: str, columns: tuple) -> np.ndarray:
    fmt = np.lib.format
    try:
        version = fmt.read_magic(f)
        shape, fortran, dtype = (fmt.read_array_header_1_0(f) if version == (1, 0)
                                 else fmt.read_array_header_2_0(f))
    except (ValueError, SyntaxError, TypeError, EOFError, KeyError, OverflowError) as e:
        raise RequestError(f"{path}: not an .npy request array ({_line(e)})") from None
    c = len(columns)
    if dtype.hasobject or dtype.kind not in "iu" or len(shape) != 2 or shape[1] != c:
        raise RequestError(f"{path}: not an integer request array of shape (N, {c}) (it holds {dtype.str} of shape {shape})")
    n, data = shape[0], size - f.tell()
    if not 0 <= n <= MAX_REQUESTS or data != n * c * dtype.itemsize:
        raise RequestError(f"{path}: header says {n} requests of {c * dtype.itemsize} bytes, "
                           f"the file holds {data} bytes of data")
    reqs = np.fromfile(f, dtype=dtype, count=n * c)
    if len(reqs) != n * c:
        raise RequestError(f"{path}: the file changed while it was read")
    reqs = reqs.reshape((c, n)).T if fortran else reqs.reshape(n, c)
    if dtype.kind == "u" and dtype.itemsize == 8 and n and int(reqs.max()) >> 63:
        raise RequestError(f"{path}: a request field does not fit in int64")
    return reqs.astype(np.int64)


def _parse_csv(raw: bytes, path: str, columns: tuple) -> np.ndarray:
    c = len(columns)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        raise RequestError(f"{path}: not a CSV request file ({_line(e)})") from None
    first, _, rest = text.partition("\n")
    if any(f.strip(" \t\r\"'")[:1].isalpha() for f in first.split(",")):
        text = rest                                             # a header row: a field is a word
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)          # "input contained no data"
            reqs = np.loadtxt(io.StringIO(text), delimiter=",", dtype=np.int64, ndmin=2)
    except (ValueError, OverflowError, TypeError) as e:
        raise RequestError(f"{path}: not a CSV of {_WORDS.get(c, c)} integer columns ({_line(e)})") from None
    if reqs.size == 0:
        return np.zeros((0, c), np.int64)
    if reqs.shape[1] != c:
        raise RequestError(f"{path}: {reqs.shape[1]} columns, not {c} ({', '.join(columns)})")
    return reqs


def _line(e: BaseException) -> str:
    """The first line of an exception's message (its type if it has none), at most 120 characters."""
    s = str(e).strip()
    return s.splitlines()[0][:120] if s else type(e).__name__
