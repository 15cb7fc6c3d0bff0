"""sim/bench/encoding/pvr2_quality.py: the quality table against pvrtex (one row here; the whole table is in
docs/pvr2.md)."""

import json
from pathlib import Path

import numpy as np

from tests.support import PVRTEX_DATA
from vqtex.golden.pvr2 import pvr
from vqtex.golden.render.imageio import read_image
from vqtex.sim.bench.encoding import pvr2_quality

DATA = Path(PVRTEX_DATA)


def test_one_row_against_the_dt_itself(capsys):
    rows = pvr2_quality.run(str(DATA), formats=("argb1555",), variants=(("c_64_m", 64, True),))
    assert len(rows) == 1
    r = rows[0]
    assert (r["format"], r["codebook"], r["mipmaps"]) == ("argb1555", 64, True)
    # pvrtex's figure from its preview is the figure of its .dt decoded (the preview is that decode)
    src = read_image(DATA / "crate.png").astype(float)
    d = pvr.read_dt(DATA / "generated" / "crate_argb1555_c_64_m.dt").levels[0][..., :3] - src
    assert abs(r["pvrtex_db"] - 10 * np.log10(255 ** 2 / (d * d).mean())) < 1e-3
    assert r["gain_db"] == round(r["ours_db"] - r["pvrtex_db"], 3) and r["gain_db"] > 0 and r["ours_seconds"] > 0


def test_main_prints_one_json_object(capsys):
    assert pvr2_quality.main(["--data", str(DATA), "--format", "rgb565", "--codebook", "64", "--json"]) == 0
    out = capsys.readouterr().out
    rows = json.loads(out)["rows"]
    assert out.count("\n") == 1 and [(r["format"], r["codebook"]) for r in rows] == [("rgb565", 64)] * 2
