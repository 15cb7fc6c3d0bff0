"""Reading and writing 8-bit images with OpenImageIO.

The renderer's only image I/O. Images are numpy ``uint8`` arrays of shape (H, W, C) with C in
{1, 3, 4} (grey, RGB, RGBA); row 0 is the top of the picture. Alpha is straight (unassociated) both
ways: OpenImageIO would otherwise premultiply RGB by alpha when reading a PNG, and un-premultiply
when writing one.

Writing goes through a temporary file in the destination folder that is renamed over the target
once complete, so an interrupted or failed write never leaves a half-written image behind.
"""

from __future__ import annotations

import os
import tempfile

import numpy as np

__all__ = ["ImageIOError", "read_image", "image_info", "write_image", "MAX_IMAGE_SIDE", "MAX_IMAGE_PIXELS"]

#: Largest image read: a file may claim any size in its header, so the size is checked before the
#: pixels are decoded (16384 per side, 2^26 pixels = 256 MiB of RGBA8).
MAX_IMAGE_SIDE = 16384
MAX_IMAGE_PIXELS = 1 << 26


class ImageIOError(OSError):
    """An image file could not be read or written (the message names the file)."""


def _oiio():
    import OpenImageIO as oiio  # imported lazily: only the image helpers need it

    return oiio


def _unassociated(oiio):
    """Open hint: keep alpha straight (unassociated); by default OIIO premultiplies RGB on read."""
    cfg = oiio.ImageSpec()
    cfg.attribute("oiio:UnassociatedAlpha", 1)
    return cfg


def _line(message: str) -> str:
    """OpenImageIO's error text on one line (it may span several)."""
    return " ".join(message.split())[:300]


def _checked_spec(inp, path: str):
    """The spec of an open image, refused (ImageIOError) if its size or channel count is absurd."""
    spec = inp.spec()
    w, h, c = int(spec.width), int(spec.height), int(spec.nchannels)
    if not (1 <= w <= MAX_IMAGE_SIDE and 1 <= h <= MAX_IMAGE_SIDE and w * h <= MAX_IMAGE_PIXELS and 1 <= c <= 4):
        raise ImageIOError(f"{path}: {w}x{h} with {c} channels is outside what vqtex reads "
                           f"(sides 1..{MAX_IMAGE_SIDE}, at most {MAX_IMAGE_PIXELS} pixels, 1..4 channels)")
    return spec


def image_info(path: str | os.PathLike) -> tuple[int, int, int]:
    """(width, height, channels) of an image file, read from its header only.

    Raises:
        ImageIOError: the file is missing, not an image OpenImageIO can read, or of absurd size
            (over :data:`MAX_IMAGE_SIDE` a side or :data:`MAX_IMAGE_PIXELS`, or over 4 channels).
    """
    oiio = _oiio()
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise ImageIOError(f"{path}: no such file")
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise ImageIOError(f"{path}: cannot open image ({_line(oiio.geterror()) or 'unknown format'})")
    try:
        spec = _checked_spec(inp, path)
        return int(spec.width), int(spec.height), int(spec.nchannels)
    finally:
        inp.close()


def read_image(path: str | os.PathLike) -> np.ndarray:
    """Read an image file as ``uint8`` (H, W, C).

    Raises:
        ImageIOError: the file is missing, unreadable or corrupt, or its header claims an absurd
            size (checked before any pixel is decoded; see :func:`image_info`).
    """
    oiio = _oiio()
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise ImageIOError(f"{path}: no such file")
    inp = oiio.ImageInput.open(path, _unassociated(oiio))
    if inp is None:
        raise ImageIOError(f"{path}: cannot open image ({_line(oiio.geterror()) or 'unknown format'})")
    try:
        spec = _checked_spec(inp, path)
        data = inp.read_image(0, 0, 0, spec.nchannels, "uint8")
        if data is None or inp.has_error:
            raise ImageIOError(f"{path}: cannot read image ({_line(inp.geterror()) or 'corrupt data'})")
    finally:
        inp.close()
    arr = np.asarray(data, dtype=np.uint8)
    return np.ascontiguousarray(arr.reshape(spec.height, spec.width, spec.nchannels))


def write_image(path: str | os.PathLike, image: np.ndarray) -> None:
    """Write a ``uint8`` image (H, W) or (H, W, C), C in {1, 2, 3, 4}, atomically.

    The format follows the file extension (PNG for ``.png``). The data goes to a temporary file
    beside ``path`` that is renamed over ``path`` only once it is complete.

    Raises:
        ValueError: the array is not a uint8 image.
        ImageIOError: the file cannot be written.
    """
    oiio = _oiio()
    arr = np.asarray(image)
    if arr.dtype != np.uint8:
        raise ValueError(f"write_image: expected a uint8 image, got {arr.dtype}")
    if arr.ndim == 2:
        arr = arr[:, :, None]
    if arr.ndim != 3 or arr.shape[2] not in (1, 2, 3, 4) or arr.shape[0] < 1 or arr.shape[1] < 1:
        raise ValueError(f"write_image: expected (H, W) or (H, W, C<=4), got shape {arr.shape}")
    arr = np.ascontiguousarray(arr)
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    suffix = os.path.splitext(path)[1] or ".png"
    fd, tmp = tempfile.mkstemp(prefix=".tmp-", suffix=suffix, dir=folder)
    os.close(fd)
    try:
        out = oiio.ImageOutput.create(tmp)
        if out is None:
            raise ImageIOError(f"{path}: no writer for this file type ({_line(oiio.geterror())})")
        spec = oiio.ImageSpec(arr.shape[1], arr.shape[0], arr.shape[2], "uint8")
        spec.attribute("oiio:UnassociatedAlpha", 1)  # our RGBA is straight alpha: store it as is
        if not out.open(tmp, spec):
            raise ImageIOError(f"{path}: cannot write ({_line(out.geterror())})")
        ok = out.write_image(arr)
        out.close()
        if not ok:
            raise ImageIOError(f"{path}: cannot write ({_line(out.geterror())})")
        os.chmod(tmp, 0o644)  # mkstemp makes 0600; an image is an ordinary file
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
