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

__all__ = ["ImageIOError", "read_image", "image_info", "write_image"]


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


def image_info(path: str | os.PathLike) -> tuple[int, int, int]:
    """(width, height, channels) of an image file, read from its header only.

    Raises:
        ImageIOError: the file is missing or not an image OpenImageIO can read.
    """
    oiio = _oiio()
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise ImageIOError(f"{path}: no such file")
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise ImageIOError(f"{path}: cannot open image ({oiio.geterror().strip() or 'unknown format'})")
    try:
        spec = inp.spec()
        return int(spec.width), int(spec.height), int(spec.nchannels)
    finally:
        inp.close()


def read_image(path: str | os.PathLike) -> np.ndarray:
    """Read an image file as ``uint8`` (H, W, C).

    Raises:
        ImageIOError: the file is missing, unreadable or corrupt.
    """
    oiio = _oiio()
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise ImageIOError(f"{path}: no such file")
    inp = oiio.ImageInput.open(path, _unassociated(oiio))
    if inp is None:
        raise ImageIOError(f"{path}: cannot open image ({oiio.geterror().strip() or 'unknown format'})")
    try:
        spec = inp.spec()
        data = inp.read_image(0, 0, 0, spec.nchannels, "uint8")
        if data is None or inp.has_error:
            raise ImageIOError(f"{path}: cannot read image ({inp.geterror().strip() or 'corrupt data'})")
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
            raise ImageIOError(f"{path}: no writer for this file type ({oiio.geterror().strip()})")
        spec = oiio.ImageSpec(arr.shape[1], arr.shape[0], arr.shape[2], "uint8")
        spec.attribute("oiio:UnassociatedAlpha", 1)  # our RGBA is straight alpha: store it as is
        if not out.open(tmp, spec):
            raise ImageIOError(f"{path}: cannot write ({out.geterror().strip()})")
        ok = out.write_image(arr)
        out.close()
        if not ok:
            raise ImageIOError(f"{path}: cannot write ({out.geterror().strip()})")
        os.chmod(tmp, 0o644)  # mkstemp makes 0600; an image is an ordinary file
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
