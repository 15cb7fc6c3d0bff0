"""Hostile input to every other reader of outside data (issue 12): .dt files, scene TOML, images,
request files. Each refuses with its documented exception, one line, quickly, without a big
allocation."""

import re
import struct
import time
import tracemalloc
import zlib
from pathlib import Path

import numpy as np
import pytest

from tests.support import PVRTEX_DATA
from vqtex.golden.pvr2 import pvr
from vqtex.golden.fetch import RequestError
from vqtex.golden.render.frame import load_requests, save_requests
from vqtex.golden.requests import MAX_CSV_BYTES, read_request_file
from vqtex.golden.render.imageio import ImageIOError, image_info, read_image, write_image
from vqtex.golden.render.scene import SceneError, load_scene, parse_scene

DT = Path(PVRTEX_DATA) / "generated"


def _refused(error, call, *, seconds=1.0, mib=64):
    """``call()`` raises ``error`` with a one-line message within ``seconds`` and ``mib`` MiB."""
    tracemalloc.start()
    t0 = time.perf_counter()
    try:
        with pytest.raises(error) as info:
            call()
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert time.perf_counter() - t0 < seconds and peak < mib << 20, (time.perf_counter() - t0, peak)
    assert "\n" not in str(info.value)
    return str(info.value)


# -- .dt ----------------------------------------------------------------------------------------

def test_dt_mutations_raise_only_pvr_error():
    """600 mutated .dt files (size field kept right so the mutation reaches the parser)."""
    rng = np.random.default_rng(12)
    seeds = [p.read_bytes() for p in sorted(DT.glob("*.dt"))[:6]]
    outcomes = {"ok": 0, "refused": 0}
    for _ in range(600):
        data = bytearray(seeds[int(rng.integers(len(seeds)))])
        for _ in range(int(rng.integers(1, 4))):
            p = int(rng.integers(32 if rng.random() < 0.7 else len(data)))
            data[p] = int(rng.choice([0, 1, 0x7F, 0x80, 0xFF, int(rng.integers(256))]))
        if rng.random() < 0.2:
            data = data[: int(rng.integers(len(data)))]
        if len(data) >= 8 and rng.random() < 0.9:
            data[4:8] = struct.pack("<I", len(data))
        try:
            pvr.parse_dt(bytes(data))
            outcomes["ok"] += 1
        except pvr.PvrError as e:
            assert "\n" not in str(e)
            outcomes["refused"] += 1
    assert outcomes["refused"] > 100 and outcomes["ok"] > 10, outcomes


def test_dt_unreadable_or_huge_file(tmp_path):
    assert "cannot read" in _refused(pvr.PvrError, lambda: pvr.read_dt(tmp_path / "missing.dt"))
    assert "cannot read" in _refused(pvr.PvrError, lambda: pvr.read_dt(tmp_path))
    big = tmp_path / "big.dt"
    with open(big, "wb") as f:
        f.truncate(pvr.MAX_DT_BYTES + 1)
    assert "larger than" in _refused(pvr.PvrError, lambda: pvr.read_dt(big))


# -- scene TOML ----------------------------------------------------------------------------------

_SCENE = """
[scene]
size = [32, 32]
[camera]
position = POSITION
target = [0, 0, 0]
[[texture]]
name = "t"
generator = "checker"
size = [16, 16]
params = PARAMS
[[mesh]]
shape = "SHAPE"
texture = "t"
SEGMENTS
"""


def _scene(position="[0, 0, 3]", params="{ squares = 4 }", shape="quad", segments=""):
    return (_SCENE.replace("POSITION", position).replace("PARAMS", params).replace("SHAPE", shape)
            .replace("SEGMENTS", segments))


def test_scene_template_is_fine():
    parse_scene(_scene())
    parse_scene(_scene(shape="sphere", segments="segments = 64"))


@pytest.mark.parametrize("text, match", [
    (_scene(position="[inf, 0, 3]"), "position"),
    (_scene(position="[nan, 0, 3]"), "position"),
    (_scene(position="[1e300, 0, 3]"), "position"),
    (_scene(position="[" * 5000 + "]" * 5000), "nests|position"),
    (_scene(params="{ squares = inf }"), "squares"),
    (_scene(params="{ squares = 1000000000 }"), "squares"),
    (_scene(params='{ squares = "many" }'), "squares"),
    (_scene(segments="segments = [100000, 100000]"), "segments"),
    (_scene(shape="sphere", segments="segments = 100000"), "segments"),
    ("[scene]\nsize = [8, 8]\n" + "[camera]\nposition=[0,0,1]\ntarget=[0,0,0]\n"
     + '[[texture]]\nname = "t"\ngenerator = "checker"\nsize = [8, 8]\n' * 1025, "textures|duplicate"),
    ("x = 1\n" + "#" * (1 << 20), "at most"),
])
def test_scene_hostile(text, match):
    message = _refused(SceneError, lambda: parse_scene(text, "evil.toml"))
    assert __import__("re").search(match, message), message


def test_scene_file_too_big(tmp_path):
    p = tmp_path / "big.toml"
    with open(p, "wb") as f:
        f.truncate((1 << 20) + 1)
    assert "at most" in _refused(SceneError, lambda: load_scene(p))


# -- images --------------------------------------------------------------------------------------

def _png_claiming(width, height):
    """A PNG whose header (right CRC) claims ``width x height`` RGBA, with a tiny IDAT."""
    def chunk(kind, payload):
        return struct.pack(">I", len(payload)) + kind + payload + struct.pack(">I", zlib.crc32(kind + payload))
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(b"\0" * 64))
            + chunk(b"IEND", b""))


@pytest.mark.parametrize("name, data, match", [
    # OpenImageIO opens a PNM header as it is: the size check is ours
    ("bomb.pgm", b"P5\n20000 20000\n255\n" + bytes(100), "outside what vqtex reads"),
    ("wide.pgm", b"P5\n16384 8192\n255\n" + bytes(100), "outside what vqtex reads"),
    ("tall.pgm", b"P5\n1 20000\n255\n" + bytes(100), "outside what vqtex reads"),
    # libpng and OpenImageIO refuse these themselves; the message is still ours, one line
    ("bomb.png", _png_claiming(100000, 100000), "cannot open image"),
    ("tall.png", _png_claiming(1, 1 << 20), "cannot open image"),
])
def test_image_of_absurd_size_is_refused_before_decoding(tmp_path, name, data, match):
    p = tmp_path / name
    p.write_bytes(data)
    assert match in _refused(ImageIOError, lambda: read_image(p))
    assert match in _refused(ImageIOError, lambda: image_info(p))


def test_image_small_still_reads(tmp_path):
    p = tmp_path / "ok.png"
    img = np.arange(4 * 8 * 3, dtype=np.uint8).reshape(4, 8, 3)
    write_image(p, img)
    assert np.array_equal(read_image(p), img) and image_info(p) == (8, 4, 3)


# -- request files -------------------------------------------------------------------------------

def _npy(path, header: dict, data: bytes = b""):
    text = repr(header).encode()
    text += b" " * ((64 - (10 + len(text) + 1) % 64) % 64) + b"\n"
    path.write_bytes(b"\x93NUMPY\x01\x00" + struct.pack("<H", len(text)) + text + data)
    return path


def test_requests_round_trip_and_other_integer_types(tmp_path):
    reqs = np.array([[0, 1, 2, 3], [4, 5, 6, 7]])
    save_requests(tmp_path / "r.npy", reqs)
    assert np.array_equal(load_requests(tmp_path / "r.npy"), reqs)
    np.save(tmp_path / "u2.npy", reqs.astype(">u2"))
    assert np.array_equal(load_requests(tmp_path / "u2.npy"), reqs)
    np.save(tmp_path / "f.npy", np.asfortranarray(reqs))
    assert np.array_equal(load_requests(tmp_path / "f.npy"), reqs)


@pytest.mark.parametrize("make, match", [
    (lambda p: np.save(p, np.array([[object()] * 4], dtype=object), allow_pickle=True), "integer"),
    (lambda p: np.save(p, np.zeros((3, 4), np.float64)), "integer"),
    (lambda p: np.save(p, np.zeros((3, 3), np.int64)), "integer"),
    (lambda p: np.save(p, np.zeros((3, 4, 1), np.int64)), "integer"),
    (lambda p: _npy(p, {"descr": "<i8", "fortran_order": False, "shape": (1 << 40, 4)}), "requests"),
    (lambda p: _npy(p, {"descr": "<i8", "fortran_order": False, "shape": (3, 4)}, bytes(8 * 11)), "requests"),
    (lambda p: _npy(p, {"descr": "<i8,<i8", "fortran_order": False, "shape": (1, 4)}, bytes(64)), "integer"),
    (lambda p: _npy(p, {"descr": "<i8", "fortran_order": False, "shape": "evil"}), "npy|integer"),
    (lambda p: p.write_bytes(b"id,level,i,j\n0,0,0,0\n"), "npy"),
    (lambda p: p.write_bytes(b"\x93NUMPY\x01\x00\xff\xff{'descr': '<i8'"), "npy"),
    (lambda p: np.save(p, np.array([[2 ** 64 - 1, 0, 0, 0]], np.uint64)), "int64"),
    (lambda p: None, "cannot read"),
])
def test_hostile_request_file(tmp_path, make, match):
    p = tmp_path / "r.npy"
    make(p)
    message = _refused(RequestError, lambda: read_request_file(p))
    assert re.search(match, message) and str(p) in message, message
    with pytest.raises(RequestError):           # the renderer's reader is the same one
        load_requests(p)


def test_csv_requests_with_and_without_header(tmp_path):
    reqs = np.array([[0, 1, 2, 3], [4, 5, 6, 7], [-1, 0, 2 ** 40, 9]])
    body = "\n".join(",".join(map(str, r)) for r in reqs) + "\n"
    for name, text in [("plain.csv", body), ("head.csv", "texture,level,i,j\n" + body),
                       ("bom.txt", "\ufefftex, level, i, j\r\n" + body.replace("\n", "\r\n")),
                       ("comment.csv", "# a stream\n" + body + "\n\n")]:
        (tmp_path / name).write_text(text, newline="")
        assert np.array_equal(read_request_file(tmp_path / name), reqs), name
        assert read_request_file(tmp_path / name).dtype == np.int64
    for name, text in [("empty.csv", ""), ("header_only.csv", "texture,level,i,j\n")]:
        (tmp_path / name).write_text(text)
        assert read_request_file(tmp_path / name).shape == (0, 4)


@pytest.mark.parametrize("text, match", [
    ("0,0,0\n", "3 columns"),
    ("0,0,0,0,0\n", "5 columns"),
    ("0,0,0,0\n1,1,1\n", "columns"),
    ("0,0,1.5,0\n", "integer"),
    ("0,0,1e3,0\n", "integer"),
    ("0,0,99999999999999999999,0\n", "integer"),
    ("0,0,0,0\nx,y,z,w\n", "integer"),
    (b"0,0,\xff\xfe,0\n", "CSV"),
    ("0;0;0;0\n", "integer"),
])
def test_hostile_csv_request_file(tmp_path, text, match):
    p = tmp_path / "r.csv"
    p.write_bytes(text if isinstance(text, bytes) else text.encode())
    message = _refused(RequestError, lambda: read_request_file(p))
    assert re.search(match, message) and str(p) in message, message


def test_csv_request_file_too_big(tmp_path):
    p = tmp_path / "big.csv"
    with open(p, "wb") as f:
        f.truncate(MAX_CSV_BYTES + 1)               # sparse: no disk used, nothing read
    assert "use .npy" in _refused(RequestError, lambda: read_request_file(p))
