"""The headless command line: CSV contract, overrides, clear one-line errors, divergence handling."""

import csv
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from sim.commands import main

HEADER = "t,x,y,z,qw,qx,qy,qz,ux,uy,uz,wx,wy,wz,Lx,Ly,Lz,Fx,Fy,Fz,Tx,Ty,Tz,E_kin,E_grav,E_hyd,E_total".split(",")


def read_csv(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    return rows[0], np.array(rows[1:], dtype=float)


def test_run_writes_the_promised_columns_and_rows(tmp_path, capsys):
    out = tmp_path / "rest.csv"
    assert main(["run", "--scene", "rest", "--t-end", "1", "--dt", "0.01", "--every", "5", "--out", str(out)]) == 0
    header, data = read_csv(out)
    assert header[: len(HEADER)] == HEADER
    assert data.shape == (21, len(header))  # t = 0 and every 5 of 100 steps
    np.testing.assert_allclose(data[:, 0], np.linspace(0, 1, 21), atol=1e-12)
    np.testing.assert_allclose(data[:, header.index("z")], -0.4, atol=1e-9)
    np.testing.assert_allclose(
        data[:, header.index("E_total")],
        data[:, header.index("E_kin")] + data[:, header.index("E_grav")] + data[:, header.index("E_hyd")],
        rtol=1e-12,
    )
    summary = capsys.readouterr().out
    assert "z = -0.400000 m" in summary and "100 steps" in summary


SPEEDS = re.compile(r"(\d+) steps in ([\d.e+-]+) s wall: ([\d.e+-]+)x real time for the whole run with its (\d+) rows; "
                    r"stepping alone ([\d.e+-]+) s \(([\d,.e+-]+) us a step, ([\d.e+-]+)x real time; the rest: ")  # fmt: skip


@pytest.mark.parametrize(
    "flags",
    [
        ["--scene", "rest", "--t-end", "2", "--dt", "0.01", "--every", "1"],
        ["--scene", "rm3", "--hydro", "linear", "--dt", "0.01", "--t-end", "10", "--every", "1"],
    ],  # fmt: skip
    ids=["one body", "several bodies"],
)
def test_the_summary_gives_the_whole_runs_speed_and_the_stepping_alone(flags, tmp_path):
    """The summary's speed line (issue 39: the README's speeds are the stepping's, the tour's run printed the whole run's)
    says both, labelled: the whole run with its rows, and the stepping alone (the time in the steps, as `bench` times it),
    each consistent with its own seconds, the stepping taking part of the wall time; a row per step is in the CSV."""
    out = tmp_path / "o.csv"
    done = subprocess.run([sys.executable, "-m", "sim", "run", *flags, "--out", str(out)], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    m = SPEEDS.search(done.stdout)
    assert m, done.stdout
    steps, wall, whole, rows, stepping, us, alone = (float(v.replace(",", "")) for v in m.groups())
    t = float(flags[flags.index("--t-end") + 1])
    assert steps == round(t / 0.01) and rows == steps + 1 == len(out.read_text().splitlines()) - 1
    assert 0 < stepping < wall and alone > whole
    assert whole == pytest.approx(t / wall, rel=1.5e-2) and alone == pytest.approx(t / stepping, rel=1.5e-2)  # 3 digits each
    assert us * 1e-6 * steps == pytest.approx(stepping, rel=1.5e-2)


def test_flags_override_the_scene(tmp_path):
    out = tmp_path / "o.csv"
    args = ["run", "--scene", "drop", "--density", "500", "--damping", "20", "--dt", "0.002", "--t-end", "0.01", "--integrator", "rk4",
            "--points-per-edge", "4", "--z0", "1.5", "--q0", "0", "1", "0", "0", "--u0", "0.1", "0.2", "0.3", "--omega0", "1", "2", "3",
            "--every", "1", "--out", str(out)]  # fmt: skip
    assert main(args) == 0
    header, data = read_csv(out)
    first = dict(zip(header, data[0]))
    assert (first["z"], first["qw"], first["qx"]) == (1.5, 0.0, 1.0)
    assert (first["ux"], first["uy"], first["uz"]) == (0.1, 0.2, 0.3)
    np.testing.assert_allclose([first["wx"], first["wy"], first["wz"]], [1, 2, 3], rtol=1e-14)
    mass = 500.0  # 1 m^3 cube
    assert first["Fz"] == pytest.approx(-mass * 9.81)  # above water: gravity alone
    inertia = 5 / 18 * mass * (1 - 2 / (5 * 4**2))  # the samples' exact inertia for N = 4 (see test_body)
    np.testing.assert_allclose([first["Lx"], first["Ly"], first["Lz"]], inertia * np.array([1, 2, 3]), rtol=1e-11)  # CSV keeps 12 digits
    assert data.shape[0] == 6


@pytest.mark.parametrize(
    "flags, message",
    [
        (["--scene", "nope"], "unknown scene 'nope'"),
        (["--scene", "missing.toml"], "scene file not found"),
        (["--integrator", "leapfrog"], "unknown integrator 'leapfrog'"),
        (["--density", "-900"], "density must be >= 0.001"),
        (["--density", "nan"], "density must be finite"),
        (["--damping", "-1"], "damping must be >= 0"),
        (["--dt", "0"], "dt must be >= 1e-07"),
        (["--dt", "-0.1"], "dt must be >= 1e-07"),
        (["--dt", "inf"], "dt must be finite"),
        (["--scene", "waves", "--g", "0"], "need gravity"),  # (dispersion divides by g)
        (["--t-end", "nan"], "t_end must be finite"),
        (["--points-per-edge", "0"], "points per edge must be >= 1"),
        (["--q0", "1", "1", "0", "0"], "unit quaternion"),
        (["--every", "0"], "--every must be >= 1"),
        (["--density", "abc"], "--density: could not convert string to float: 'abc'"),  # tyro's own parse errors, one line too
        (["--densty", "3"], "did you mean --density?"),
        (["--q0", "1", "2"], "--q0: input length 2 did not match expected argument count 4"),
        (["--density"], "Missing value for argument '--density'"),
    ],
)
def test_user_mistakes_get_one_clear_line(flags, message, capsys):
    try:
        code = main(["run", *flags])
    except SystemExit as e:  # a parse error exits from the parser
        code = e.code
    assert code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err and "Traceback" not in err


def test_no_gravity_is_a_torque_free_run_not_a_traceback(capsys):
    """g = 0 in still water: no weight and no buoyancy, so the body stays where it is put and its rest line says so
    (the rest height divided by g: a ZeroDivisionError traceback before)."""
    assert main(["run", "--scene", "drop", "--g", "0", "--t-end", "0.5"]) == 0
    out = capsys.readouterr().out
    assert "without gravity (g = 0) it neither floats nor sinks" in out and "|u| = 0 m/s" in out


def test_a_hand_typed_quaternion_is_normalised_with_a_note(capsys):
    """Four digits give a norm of 0.99997: close enough to be meant as a rotation, so normalised and said."""
    assert main(["run", "--scene", "rest", "--t-end", "0.01", "--q0", "0.9659", "0.2588", "0", "0"]) == 0
    err = capsys.readouterr().err
    assert "had norm 0.99997: normalised" in err
    assert main(["run", "--scene", "rest", "--t-end", "0.01", "--q0", "0.9", "0.2", "0", "0"]) == 2  # norm 0.92: no rotation
    assert "within 0.001 of 1 is normalised" in capsys.readouterr().err


def test_help_says_where_unset_flags_come_from(capsys):
    with pytest.raises(SystemExit) as e:
        main(["run", "--help"])
    assert e.value.code == 0
    text = capsys.readouterr().out
    assert "(default: from the scene)" in text and "{None}" not in text and "(default: None)" not in text


@pytest.mark.parametrize("command", ["run", "sweep"])
def test_help_lists_every_preset(command):
    """`python -m sim run --help` (and sweep's) names the presets --scene takes, each one (issue 39)."""
    from sim.scene.config import available_scenes

    done = subprocess.run(
        [sys.executable, "-m", "sim", command, "--help"], capture_output=True, text=True, env={**os.environ, "COLUMNS": "400"}
    )
    assert done.returncode == 0, done.stderr
    line = next(line for line in done.stdout.splitlines() if "--scene" in line)
    assert f"({', '.join(available_scenes())})" in line and len(available_scenes()) >= 10


def test_missing_mesh_file_gets_one_clear_line(tmp_path, capsys):
    scene = tmp_path / "m.toml"
    scene.write_text('[body]\nshape = "mesh"\nmesh = "no-such.stl"\n')
    assert main(["run", "--scene", str(scene)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "mesh file not found" in err


def test_a_mesh_flag_is_read_where_it_was_typed(tmp_path, monkeypatch, capsys):
    """`run --mesh FILE` reads FILE from the shell's folder, and names that path when it is missing (not the scene folder's)."""
    monkeypatch.chdir(tmp_path)
    assert main(["run", "--mesh", "nothere.stl", "--t-end", "0.01"]) == 2
    assert f"mesh file not found: {tmp_path / 'nothere.stl'}" in capsys.readouterr().err
    (tmp_path / "here.stl").write_bytes((Path(__file__).resolve().parents[2] / "assets" / "meshes" / "log.stl").read_bytes())
    out = tmp_path / "run.csv"
    assert main(["run", "--mesh", "here.stl", "--t-end", "0.01", "--out", str(out)]) == 0
    assert len(out.read_text().splitlines()) > 1


def test_unknown_key_in_a_scene_file_is_named(tmp_path, capsys):
    scene = tmp_path / "typo.toml"
    scene.write_text("[fluid]\ndamp = 3\n")
    assert main(["run", "--scene", str(scene)]) == 2
    assert "unknown key 'damp'" in capsys.readouterr().err


def test_divergence_stops_with_the_time_and_cause_and_keeps_rows(tmp_path, capsys):
    out = tmp_path / "boom.csv"
    code = main(
        [
            "run",
            "--scene",
            "damped",
            "--damping",
            "1e6",
            "--integrator",
            "euler",
            "--dt",
            "0.01",
            "--t-end",
            "5",
            "--every",
            "1",
            "--out",
            str(out),
        ]
    )
    assert code == 3
    err = capsys.readouterr().err
    assert "diverged at t =" in err and "--integrator implicit" in err
    header, data = read_csv(out)
    assert len(data) >= 1 and np.isfinite(data).all()  # never NaN rows
    assert data[-1, 0] < 5.0


def test_a_light_cube_under_stiff_damping_runs_the_same_compiled_as_on_numpy(tmp_path):
    """Issue 23: the compiled implicit step sent a 1 kg cube at d = 1e7 to 1e106 m/s in one step when a corner
    first touched the water (a zero damping mode came out of eigh at -4e-11, which the kernel read as its flag
    for the mild case and summed a divergent series), then wrote z = -8.6e211 and E nan rows with exit 0. The
    numpy reference creeps: both paths now agree, and write only finite rows."""

    def run(backend: str) -> np.ndarray:
        out = tmp_path / f"{backend}.csv"
        args = ["run", "--scene", "damped", "--density", "1", "--damping", "1e7", "--dt", "0.05", "--integrator", "implicit", "--z0", "0.87",
                "--u0", "0", "0", "-1", "--omega0", "-1", "1", "0", "--t-end", "3", "--every", "10", "--out", str(out)]  # fmt: skip
        done = subprocess.run([sys.executable, "-m", "sim", *args], capture_output=True, text=True, timeout=120, check=False,
                              env={**os.environ, "FLOATSIM_BACKEND": backend})  # fmt: skip
        assert done.returncode == 0, done.stderr
        assert "past the heave limit" in done.stderr  # dt omega_heave = 4.95: warned before the run
        return read_csv(out)[1]

    compiled, reference = run("numba"), run("numpy")
    assert compiled.shape == reference.shape == (7, compiled.shape[1]) and np.isfinite(compiled).all()
    np.testing.assert_allclose(compiled, reference, rtol=1e-9, atol=1e-9)


def test_python_dash_m_sim_and_console_script_exit_codes():
    ok = subprocess.run([sys.executable, "-m", "sim", "run", "--scene", "rest", "--t-end", "0.05"], capture_output=True, text=True)
    assert ok.returncode == 0 and "z = -0.400000 m" in ok.stdout
    assert ok.stderr == ""  # no progress bar when not on a terminal
    bad = subprocess.run([sys.executable, "-m", "app.cli", "run", "--density", "-1"], capture_output=True, text=True)
    assert bad.returncode == 2 and bad.stderr.strip() == "floatsim: error: density must be >= 0.001, got -1.0"


def test_tyro_panels_become_one_line_in_both_renderings():
    """rich draws tyro's error in a box on a terminal and plain elsewhere: the same line from both."""
    from sim.commands.tyro_errors import one_line

    boxed = ("╭─ Unrecognized options ─────╮\n│ Unrecognized options: --densty, 3 │\n│ ────────── │\n│ Perhaps you meant: │\n"
             "│     --density FLOAT │\n╰────────────╯\n")  # fmt: skip
    plain = " Unrecognized options \n ---------- \n Unrecognized options: --densty, 3 \n ---------- \n Perhaps you meant: \n     --density FLOAT \n"
    for panel in (boxed, plain):
        assert one_line(panel) == "Unrecognized options: --densty, 3 (did you mean --density?)"


@pytest.mark.slow  # over 4 s (the marker's rule)
def test_a_first_run_knows_the_kernels_are_not_compiled_yet(tmp_path):
    """`run` announces the one-time compile before it starts (not after a silent minute): it can tell."""
    probe = "import sim, sim.compiling as k; print(k.cached(sim.Simulation(sim.load_scene('drop')).spec))"
    fresh = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, env={**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    )
    assert fresh.stdout.strip() == "False"
    from sim import Simulation, load_scene
    from sim.compiling import cached, warm_up

    spec = Simulation(load_scene("drop")).spec
    warm_up(spec)
    assert cached(spec) and not cached(spec._replace(terms=()))  # a specialisation no scene uses: never compiled


@pytest.mark.slow
def test_compare_says_what_it_does_before_it_starts_and_orders_the_errors(capsys):
    """`compare` announces its runs (it takes a while before any row), then one row per integrator and
    dt; on the damped scene rk4's error falls as dt halves."""
    assert main(["compare", "--scene", "damped", "--t-end", "1", "--dts", "0.02", "0.01", "--integrators", "rk4", "--repeats", "1"]) == 0
    out, err = capsys.readouterr()
    assert err.startswith("compare: two DOP853 references, then 2 runs of 'damped'")
    rows = [line.split("|") for line in out.splitlines() if line.startswith("| rk4 |")]
    errors = [float(row[4]) for row in rows]
    assert len(rows) == 2 and errors[1] < errors[0]


def test_an_output_never_overwrites_the_runs_own_input(tmp_path, capsys):
    scene = tmp_path / "mine.toml"
    scene.write_text((Path(__file__).resolve().parents[2] / "assets" / "scenes" / "rest.toml").read_text())
    before = scene.read_text()
    assert main(["run", "--scene", str(scene), "--out", str(scene), "--t-end", "0.1"]) == 2
    assert "this run's own input file" in capsys.readouterr().err and scene.read_text() == before
    other = tmp_path / "other.toml"
    other.write_text("# a scene of mine\n")
    assert main(["run", "--scene", "rest", "--out", str(other), "--t-end", "0.1"]) == 2
    assert "is not overwritten" in capsys.readouterr().err and other.read_text() == "# a scene of mine\n"


@pytest.mark.parametrize("flags, says", [
    (["--density", "1e-320"], "density must be >= 0.001"),
    (["--mass", "1e-320"], "mass must be >= 1e-06"),
    (["--size", "1e-320"], "cube size must be >= 0.001"),
    (["--dt", "1e-320"], "dt must be >= 1e-07"),
    (["--dt", "1e-7", "--t-end", "1e5"], "more than --max-steps 1e+08"),
    (["--max-steps", "0"], "--max-steps must be >= 1"),
])  # fmt: skip
def test_absurd_numbers_are_one_line_each(flags, says):
    """Issue 23: subnormal sizes, masses and steps gave tracebacks (LinAlgError, OverflowError); a 1e-300 s step
    ran on after a 600-digit estimate. Now each is refused in one line, exit 2, before any work."""
    done = subprocess.run(
        [sys.executable, "-m", "sim", "run", "--scene", "drop", *flags], capture_output=True, text=True, timeout=60, check=False
    )
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.count("\n") == 1 and says in done.stderr, done.stderr


def test_a_scene_file_nested_5000_deep_is_one_line(tmp_path):
    scene = tmp_path / "deep.toml"
    scene.write_text("a = " + "[" * 5000 + "]" * 5000 + "\n")
    done = subprocess.run(
        [sys.executable, "-m", "sim", "run", "--scene", str(scene)], capture_output=True, text=True, timeout=60, check=False
    )
    assert done.returncode == 2 and "nested too deeply" in done.stderr and done.stderr.count("\n") == 1, done.stderr[-300:]


def test_max_steps_lets_a_long_run_go_when_asked(tmp_path):
    done = subprocess.run([sys.executable, "-m", "sim", "run", "--scene", "rest", "--dt", "0.001", "--t-end", "0.05", "--max-steps", "10"],
                          capture_output=True, text=True, timeout=60, check=False)  # fmt: skip
    assert done.returncode == 2 and "50 steps, more than --max-steps 10" in done.stderr
    done = subprocess.run([sys.executable, "-m", "sim", "run", "--scene", "rest", "--dt", "0.001", "--t-end", "0.05", "--max-steps", "50"],
                          capture_output=True, text=True, timeout=60, check=False)  # fmt: skip
    assert done.returncode == 0 and "50 steps in" in done.stdout


@pytest.mark.parametrize("integrator", ["rk45", "dop853"])
def test_a_stiff_adaptive_run_stops_within_its_step_budget_naming_a_better_integrator(integrator):
    """Issue 23: a 1 kg cube at d = 1e7 kept rk45, dop853 and radau busy for 10 minutes with nothing said: the
    evaluation cap allowed a minute per step. The CLI gives each output step a wall budget (30 s; here 1 s). (radau
    now runs this case: 600 steps in 2.5 s.)"""
    args = [
        "run",
        "--scene",
        "damped",
        "--density",
        "1",
        "--damping",
        "1e7",
        "--integrator",
        integrator,
        "--t-end",
        "3",
        "--step-budget",
        "1",
    ]
    done = subprocess.run([sys.executable, "-m", "sim", *args], capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 3, done.stderr
    assert f"'{integrator}' took over 1 s of wall time (its budget)" in done.stderr and "use --integrator implicit" in done.stderr


def test_a_slow_run_says_how_long_it_will_take_at_its_pace(monkeypatch, capsys):
    """After 10 s a run that needs more than a minute says so, from its measured pace, and again every 5 min."""
    from sim.commands import run as run_module

    clock = iter([0.0, 5.0, 12.0, 100.0, 330.0])
    monkeypatch.setattr(run_module.time, "perf_counter", lambda: next(clock))
    pace = run_module.Pace(1000)
    for done in (10, 20, 30, 200):  # at 5 s nothing; at 12 s 20 steps: 588 s left; at 100 s none (within 5 min); at 330 s, 200 steps
        pace.tell(done)
    notes = capsys.readouterr().err.strip().splitlines()
    assert len(notes) == 2
    assert "20 of 1,000 steps in 12 s" in notes[0] and "about 10 min more" in notes[0]
    assert "200 of 1,000 steps in 330 s" in notes[1] and "about 22 min more" in notes[1]


@pytest.mark.slow  # a compile from an empty kernel cache: 20-60 s
def test_bench_startup_says_how_each_cold_run_ran_in_whole_parentheses():
    """`python -m sim bench --startup --presets drop`: its progress line closes every parenthesis it opens (it cut the
    run's note at 100 characters, inside one) and says the cold run stayed on numpy; the table has the preset's row."""
    env = {k: v for k, v in os.environ.items() if k != "FLOATSIM_BACKEND"}
    done = subprocess.run([sys.executable, "-m", "sim", "bench", "--startup", "--presets", "drop"], capture_output=True, text=True, env=env)
    assert done.returncode == 0, done.stderr[-2000:]
    line = next(line for line in done.stderr.splitlines() if line.strip().startswith("drop:"))
    assert line.count("(") == line.count(")") and "(on the numpy reference" in line, line
    assert "| drop |" in done.stdout
