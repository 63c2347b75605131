"""The README's examples, run as a newcomer would paste them (shortened in simulated time)."""

import re
import shlex
from pathlib import Path

import pytest

from sim.commands import main

README = (Path(__file__).resolve().parent.parent / "README.md").read_text()
SLOW = ("--record", "--video", "hull.stl", "--radiation", "sphere")
"""Lines left to their own tests: a browser, a file the reader brings, a boundary-element solve."""


def run_lines() -> list[str]:
    block = README.split("## Headless runs")[1].split("```bash")[1].split("```")[0]
    lines = [line.split("#")[0].strip() for line in block.splitlines()]
    return [line for line in lines if re.match(r"(python -m sim|floatsim) run ", line) and not any(s in line for s in SLOW)]


def test_the_readme_lists_run_examples():
    assert len(run_lines()) >= 6


@pytest.mark.parametrize("line", run_lines())
def test_every_run_example_in_the_readme_works(line, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)  # their --out files land here
    args = shlex.split(line)[3 if line.startswith("python") else 1 :]
    assert main([*args, "--t-end", "0.2"]) == 0, capsys.readouterr().err
    assert "error" not in capsys.readouterr().err


def test_the_api_example_in_the_readme_runs(capsys):
    code = README.split("### Python API")[1].split("```python")[1].split("```")[0]
    exec(compile(code, "README.md (Python API)", "exec"), {})
    assert re.search(r"\[.*\] \d", capsys.readouterr().out)  # the position and the energy printed
