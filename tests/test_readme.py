"""The README starts with exactly two commands, and CI runs the second one verbatim."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _commands():
    text = (ROOT / "README.md").read_text()
    return re.findall(r"```sh\n(.*?)\n```", text, flags=re.S)


def test_readme_two_commands_first():
    text = (ROOT / "README.md").read_text()
    cmds = _commands()
    assert len(cmds) >= 2
    first_para = text.split("\n\n", 3)
    assert cmds[0] == "pip install . && vqtex demo"
    assert text.index(cmds[1]) < text.index("The first installs")


def test_ci_runs_readme_test_command():
    ci = (ROOT / ".ci" / "run").read_text().splitlines()
    assert _commands()[1] in ci
