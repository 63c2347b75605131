"""Every script in examples/ runs as a reader would run it (a subprocess, short flags), and prints the physics it
promises: Archimedes, a known period, the radiation's effect, a custom term's closed form."""

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = sorted((ROOT / "examples").glob("[0-9][0-9]_*.py"))


def run(name: str, *flags: str) -> str:
    done = subprocess.run(
        [sys.executable, str(ROOT / "examples" / name), *flags], capture_output=True, text=True, timeout=600, cwd=ROOT, check=False
    )
    assert done.returncode == 0, done.stderr[-2000:]
    return done.stdout


def numbers(text: str) -> list[float]:
    return [float(v) for v in re.findall(r"-?\d+\.\d+", text)]


def test_every_example_is_numbered_titled_and_tested():
    """Numbered in order, each with a docstring title and a tyro main, and each one run below."""
    names = [p.name for p in EXAMPLES]
    assert [n[:2] for n in names] == [f"{i:02d}" for i in range(1, len(names) + 1)] and len(names) >= 7
    tested = Path(__file__).read_text()
    for path in EXAMPLES:
        text = path.read_text()
        assert text.startswith('"""') and "tyro.cli(" in text and "def main(" in text, path.name
        assert f'"{path.name}"' in tested, f"{path.name} has no test"


def test_01_drop_cube_settles_at_its_archimedes_draft():
    z, archimedes = numbers(run("01_drop_cube.py", "--t-end", "30"))[1:3]
    assert abs(z - archimedes) < 2e-3


def test_02_your_mesh_floats_half_submerged_at_half_the_density():
    out = run("02_your_mesh.py", "--t-end", "10")
    under, archimedes = (float(v) for v in re.findall(r"(\d+\.\d)%", out))
    assert abs(under - archimedes) < 0.5


def test_03_density_sweep_finds_each_draft_face_up_and_the_unstable_band_tilted():
    out = run("03_density_sweep.py", "--densities", "150", "400", "850", "--t-end", "30")
    for line in out.strip().splitlines():
        tilt, draft, archimedes = numbers(line)[-3:]
        if "  400 kg" in line:  # inside the band where face up is unstable: it turned
            assert tilt > 10.0, line
        else:
            assert tilt < 0.1 and abs(draft - archimedes) < 3e-3, line


def test_04_decay_test_rings_at_the_added_mass_period():
    period, dry, start, end = numbers(run("04_decay_test.py", "--t-end", "6"))[:4]
    assert abs(period - 1.38) < 0.03 and period > dry * 1.1 and end < start / 3  # the water's mass, and the waves it radiates


@pytest.mark.slow
def test_05_radiation_tames_the_heave_resonance():
    out = run("05_waves_and_radiation.py", "--t-end", "15")
    ratio = float(out.rsplit("x", 1)[1])
    assert ratio < 0.8  # near resonance, the radiated waves damp the heave


def test_06_a_custom_term_gives_its_closed_form_period():
    out = run("06_custom_force_term.py", "--t-end", "20")
    assert "tether term has no compiled twin" in out
    period, closed = numbers(out.splitlines()[-1])[:2]
    assert abs(period / closed - 1) < 0.01


@pytest.mark.slow
def test_07_dask_sweep_runs_on_a_cluster_and_finds_the_linear_period():
    out = run("07_dask_sweep.py", "--t-end", "8", "--heights", "0.02:0.2:3")
    first = next(line for line in out.splitlines() if line.startswith("dropped"))
    period, linear = numbers(first)[-2:]
    assert "backend dask" in out and abs(period / linear - 1) < 0.01


def test_09_lines_alone_pull_as_the_elastic_catenary():
    """Each fairlead's tension under the slow surge is the catenary's within 1 % (the first row, at rest from MoorDyn's
    own start, 0.8 %)."""
    out = run("09_lines_alone.py")
    rows = [numbers(line) for line in out.splitlines()[1:]]
    assert len(rows) > 5 and rows[-1][0] == pytest.approx(8.0)
    for row in rows:
        for moordyn, catenary in zip(row[1::2], row[2::2]):
            assert moordyn == pytest.approx(catenary, rel=0.01), row


@pytest.mark.slow
def test_10_farm_power_matrix_grows_with_the_waves_height_squared_and_shares_it_evenly(monkeypatch):
    """The sweep's matrix: twice the wave height, about four times the farm's power (linear waves); six identical devices
    without radiation share it evenly."""
    monkeypatch.setenv("FLOATSIM_BACKEND", "numpy")
    out = run("10_farm_power_matrix.py", "--heights", "0.05:0.1:2", "--periods", "2.0:2.4:2", "--t-end", "12", "--backend", "serial")
    lines = out.splitlines()
    low, high = numbers(lines[-3])[1:], numbers(lines[-2])[1:]
    for a, b in zip(low, high):
        assert b / a == pytest.approx(4.0, rel=0.1)
    shares = [float(v) for v in re.findall(r"d\d (\d+\.\d)%", lines[-1])]
    assert len(shares) == 6 and all(abs(v - 100 / 6) < 0.5 for v in shares), lines[-1]


@pytest.mark.slow  # two 40 s runs in waves
def test_11_wamit_files_heave_as_linear_theory_says_from_either_file():
    """The ellipsoid's heave from WAMIT's numeric files within 2 % of the frequency-domain heave of the same files' A33,
    B33, X3 and C33, and the run from the .out within 1 % of it."""
    out = run("11_wamit_files.py", "--t-end", "40")
    simulated, linear, apart, percent = numbers(out)[-4:]
    assert simulated == pytest.approx(linear, rel=0.02) and 0.3 < simulated < 0.7, out
    assert percent < 1.0 and apart < 0.01 * simulated, out


@pytest.mark.slow
def test_08_take_off_control_absorbs_what_the_frequency_domain_says():
    """Each run's mean power beside its frequency-domain value: the best damper and the reactive optimum within 2 %, the
    damper as a Python function as the scene's; latching many times the damper's."""
    out = run("08_take_off_control.py", "--t-end", "105")
    rows = {line.split()[0] + line.split()[1]: numbers(line)[-2:] for line in out.splitlines()[2:]}
    for key in ("bestdamper", "reactivek", "thebest"):
        power, predicted = rows[key]
        assert power == pytest.approx(predicted, rel=0.02), key
    assert numbers(next(line for line in out.splitlines() if line.startswith("latching")))[-1] > 5 * rows["bestdamper"][0]


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_every_examples_help_says_what_it_demonstrates(path):
    """`python examples/NN_x.py --help` shows the script's docstring (issue 39: it showed the flags alone)."""
    done = subprocess.run([sys.executable, str(path), "--help"], capture_output=True, text=True, timeout=120, cwd=ROOT, check=False)
    title, body = path.read_text().split('"""')[1].split("\n", 1)
    assert done.returncode == 0 and title.strip() in done.stdout and " ".join(body.split()[:8]) in " ".join(done.stdout.split())


@pytest.mark.parametrize("name", ["04_decay_test.py", "06_custom_force_term.py"])
def test_a_run_too_short_to_measure_says_so(name):
    """A run with no whole period in it says it is too short and how long to run, instead of printing "nan" (issue 39)."""
    out = run(name, "--t-end", "0.3")
    assert "too short a run to measure" in out and "give --t-end" in out and "nan" not in out, out


def test_a_swell_run_too_short_to_measure_is_one_line_and_exit_2():
    """05's amplitude needs a wave period in the run's last third: a shorter run is one line and exit 2, not a traceback."""
    done = subprocess.run([sys.executable, str(ROOT / "examples" / "05_waves_and_radiation.py"), "--t-end", "1"], capture_output=True,
                          text=True, timeout=120, cwd=ROOT, check=False)  # fmt: skip
    assert done.returncode == 2 and done.stderr.count("\n") == 1 and "too short a run to measure" in done.stderr, done.stderr


@pytest.mark.slow  # the decay of tests/io/test_bemio_h5.py, as a reader runs it
def test_12_bemio_sphere_heaves_as_sea_stacks_run_of_the_same_file():
    """The IEA sphere's decay from its BEMIO file within 1 % of the release of SEA-Stack's run with nonlinear hydrostatics,
    farther from its run with linear ones, and swinging past rest as a decay does."""
    out = run("12_bemio_sphere.py", "--t-end", "20")
    nonlinear, linear = (numbers(line)[0] for line in out.splitlines() if "against SEA-Stack" in line)
    assert nonlinear < 0.01 and linear > 0.02, out
    assert numbers(out.splitlines()[-1])[0] < -2.8, out


@pytest.mark.slow  # the runs of tests/io/test_nemoh.py, as a reader runs them
def test_13_nemoh_run_heaves_as_wamits_run_of_the_same_body():
    """The ellipsoid's heave from NEMOH's run within 2 % of its amplitude from WAMIT's."""
    out = run("13_nemoh_run.py", "--t-end", "40")
    amplitude, apart, percent = numbers(out)[-3:]
    assert 0.4 < amplitude < 0.6 and percent < 2.0, out


@pytest.mark.slow  # a Capytaine solve
def test_14_capytaine_netcdf_decays_as_floatsims_own_solve():
    """The sphere's decay from the user's own Capytaine solve within 2 % of the release of the preset's (0.94 %)."""
    out = run("14_capytaine_netcdf.py", "--t-end", "10")
    apart, percent = numbers(out)[-2:]
    assert percent < 2.0, out
