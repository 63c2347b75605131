"""The README's and the docs' examples, run as a newcomer would paste them (shortened in simulated time)."""

import re
import shlex
from pathlib import Path

import pytest

from sim.commands import main

ROOT = Path(__file__).resolve().parent.parent
README = (ROOT / "README.md").read_text()
HEADLESS = (ROOT / "docs" / "headless.md").read_text()
API = (ROOT / "docs" / "api.md").read_text()
SLOW = ("--record", "--video", "hull.stl", "--radiation")
"""Lines left to their own tests: a browser, a file the reader brings, a boundary-element solve."""


def run_lines() -> list[str]:
    """The `run` lines of the README's tour and of the docs' Headless runs page (their first bash block each)."""
    blocks = [README.split("## A tour")[1].split("```bash")[1].split("```")[0], HEADLESS.split("```bash")[1].split("```")[0]]
    lines = [line.split("#")[0].strip() for block in blocks for line in block.splitlines()]
    return [line for line in lines if re.match(r"(python -m sim|floatsim) run ", line) and not any(s in line for s in SLOW)]


def test_the_readme_lists_run_examples():
    assert len(run_lines()) >= 8


@pytest.mark.parametrize("line", run_lines())
def test_every_run_example_in_the_readme_works(line, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)  # their --out files land here
    args = shlex.split(line)[3 if line.startswith("python") else 1 :]
    assert main([*args, "--t-end", "0.2"]) == 0, capsys.readouterr().err
    assert "error" not in capsys.readouterr().err


def test_the_api_example_in_the_readme_runs(capsys):
    code = API.split("```python")[1].split("```")[0]
    exec(compile(code, "docs/api.md (Python API)", "exec"), {})
    assert re.search(r"\[.*\] \d", capsys.readouterr().out)  # the position and the energy printed


def test_the_readme_is_a_front_door():
    """At most about 150 lines, the two quick-start lines first among its commands, and every page it links there."""
    assert len(README.splitlines()) <= 150
    quick = README.split("## Quick start")[1].split("```bash")[1].split("```")[0].strip().splitlines()
    assert quick[0].startswith("pip install -e . && python -m app") and quick[1].startswith(
        'pip install -e ".[test]" && python -m pytest -q -n 2'
    )
    for link in re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", README):
        assert link.startswith("http") or (ROOT / link).exists(), link


def test_every_public_name_has_a_docstring():
    """What `import sim` exports, and the public methods of its classes, say what they are (the API reference is made
    from these)."""
    import inspect

    import sim

    missing = []
    for name in sim.__all__:
        obj = getattr(sim, name)
        if not (inspect.isclass(obj) or inspect.isfunction(obj)):
            continue  # data (PARAMS, TERMS, CSV_COLUMNS, ...): the pages say what they hold
        if not (obj.__doc__ or "").strip():
            missing.append(name)
        if inspect.isclass(obj):
            for attr, member in vars(obj).items():
                if (
                    not attr.startswith("_")
                    and (inspect.isfunction(member) or isinstance(member, property))
                    and not (member.__doc__ or "").strip()
                ):
                    missing.append(f"{name}.{attr}")
    assert not missing, f"no docstring: {', '.join(missing)}"


def tour_lines(command: str) -> list[str]:
    block = README.split("## A tour")[1].split("```bash")[1].split("```")[0]
    return [line.split("#")[0].strip() for line in block.splitlines() if line.startswith(f"python -m sim {command} ")]


@pytest.mark.parametrize("line", tour_lines("sweep") + [pytest.param(line, marks=pytest.mark.slow) for line in tour_lines("compare")])
def test_the_tours_sweep_and_compare_lines_work(line, tmp_path, monkeypatch, capsys):
    """Shortened in simulated time; `bench` and the viewer lines have their own tests (the benchmark takes minutes)."""
    monkeypatch.chdir(tmp_path)
    args = shlex.split(line)[3:]
    if "--t-end" in args:
        args[args.index("--t-end") + 1] = "0.5"
    else:
        args += ["--t-end", "0.5"]
    assert main(args) == 0, capsys.readouterr().err


@pytest.mark.slow
def test_the_tours_bench_line_works(capsys):
    """`python -m sim bench`, cut to one size, one integrator and no extra tables: its speed table, a row per model."""
    assert tour_lines("bench") == ["python -m sim bench"]
    cut = ["--sizes", "10", "--integrators", "implicit", "--ensemble", "0", "--no-radiation", "--no-waves", "--no-moorings", "--no-systems"]
    assert main(["bench", *cut, "--sweep-cases", "0", "--repeats", "1"]) == 0
    out = capsys.readouterr().out
    assert "| model | samples | integrator | us/step |" in out and out.count("| implicit |") >= 3  # points, cells, panels


@pytest.mark.slow
def test_bench_says_how_long_it_takes_and_quick_is_the_first_table_alone():
    """`python -m sim bench --quick` (issue 39): says first, before any row, what it runs and how long the whole benchmark
    takes; then only the first table at N = 10, a row per model and integrator (4 points, 1 cells, 4 panels)."""
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-m", "sim", "bench", "--quick"], capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stderr.startswith("bench: the first table at N = 10 only (--quick): about"), done.stderr[:300]
    rows = [line for line in done.stdout.splitlines() if re.match(r"\| (points|cells|panels) \|", line)]
    assert len(rows) == 9 and all(r.split("|")[2].strip() in ("600", "12 triangles") for r in rows), rows
    assert "ensemble of" not in done.stdout and "sweep of" not in done.stdout and "sea states" not in done.stdout


def test_the_tours_bench_line_says_it_takes_minutes_and_how_to_cut_it():
    """The README's bench line says how long it takes, and --quick (issue 39)."""
    line = next(line for line in README.split("## A tour")[1].splitlines() if line.startswith("python -m sim bench"))
    assert "min" in line and "--quick" in README.split("## A tour")[1]


@pytest.mark.parametrize(
    "line",
    [line.split("#")[0].strip() for line in README.split("## A tour")[1].split("```")[1].splitlines() if line.startswith("python -m app")],
)
def test_the_tours_viewer_lines_serve_their_scene_and_run(line):
    """`python -m app --scene NAME` as the tour gives it: the viewer (one body or several) serves the scene and its run
    goes on (on the numpy reference here: nothing compiled)."""
    import contextlib
    import io
    import time

    from app.args import ViewArgs
    from app.main import start

    scene = shlex.split(line)[shlex.split(line).index("--scene") + 1]
    with contextlib.redirect_stdout(io.StringIO()):
        app = start(ViewArgs(scene=scene, port=0), kernels=False)
    try:
        deadline = time.monotonic() + 30.0
        while app.sync().frame.t <= 0.2 and time.monotonic() < deadline:
            time.sleep(0.1)
        assert app.sync().frame.t > 0.2 and app.address().startswith("http://")
    finally:
        app.stop()


def test_the_viewer_page_answers_questions_and_leaves_measurements_to_performance():
    """docs/viewer.md is sections a user looks for ("How do I ...", "What do ..."), none a wall of text, and the viewer's
    costs (bandwidth, CPU, soak runs) sit in docs/performance.md (issue 39: one heading over ~6000 px of measurements)."""
    viewer = (ROOT / "docs" / "viewer.md").read_text()
    headings = re.findall(r"^## (.+)$", viewer, flags=re.M)
    assert len(headings) >= 6 and all(h.startswith(("How do I", "What do")) for h in headings), headings
    for section in viewer.split("\n## ")[1:]:
        assert len(section.split()) < 700, section.splitlines()[0]
    assert not re.search(r"MB/s|server CPU|app\.soak|cores", viewer)
    costs = (ROOT / "docs" / "performance.md").read_text().split("## The viewer's costs")[1]
    assert "MB/s" in costs and "app.tools.soak" in costs and "server CPU" in costs


QUOTED = re.compile(r"`(?:floatsim: error: )?((\w+) must be [^`]*?, got (-?[\d.e+-]+))`")
"""A parameter's message quoted in the docs: `density must be >= 0.001, got -5.0` (with or without the CLI's prefix)."""


def test_the_docs_quote_the_messages_the_code_gives():
    """Every "KEY must be ..., got VALUE" the README and the docs quote is the message that value gets from the code, word
    for word (issue 39: the API page quoted "density must be > 0" where the code says "density must be >= 0.001")."""
    from sim.scene.config import PARAMS, ConfigError, load_scene, with_overrides

    pages = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
    quoted = [(page.name, *m) for page in pages for m in QUOTED.findall(page.read_text())]
    assert len(quoted) >= 2, quoted  # the API page's and the sweeps page's at least
    for page, message, key, value in quoted:
        (param,) = [p for p in PARAMS.values() if p.key == key]
        with pytest.raises(ConfigError) as e:
            with_overrides(load_scene("rest"), **{f"{param.section}__{key}": float(value)})
        assert str(e.value) == message, f"{page} quotes {message!r}; the code says {str(e.value)!r}"


def test_the_tours_lines_say_which_extra_a_moored_scene_needs():
    """A tour line running a scene with mooring lines says it needs `.[moorings]` (issue 39: the moored buoy's did not;
    MoorDyn stays optional, see pyproject.toml)."""
    from sim.scene.config import load_scene

    block = README.split("## A tour")[1].split("```bash")[1].split("```")[0]
    moored = [line for line in block.splitlines() if (m := re.search(r"--scene (\S+)", line)) and load_scene(m.group(1)).moorings.lines]
    assert moored and all('pip install -e ".[moorings]"' in line for line in moored), moored
