"""The mooring lines' energy ([moorings] energy, sim/lines/line_energy.py): what the lines store and dissipate closes the energy of
the bodies and lines together, through the CLI's CSV."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("moordyn")

ROOT = Path(__file__).resolve().parents[2]


def run(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "sim", "run", *args], cwd=cwd, capture_output=True, text=True, timeout=600)


def released_buoy(tmp_path: Path, dtm_divisor: int) -> Path:
    """moored-buoy's spread as a MoorDyn file (MoorDyn's own step divided by dtm_divisor), without waves or radiation,
    the buoy released 1 m downstream and 0.1 m high of where it rests."""
    from sim import load_scene
    from sim.lines.moorings import lines_of

    scene = load_scene("moored-buoy")
    start = np.array([1.0, 0.3, -0.3])
    text = lines_of(scene.moorings).input_file(start, np.eye(3), scene.fluid.rho, scene.fluid.g, 0.01)
    dtm = float(re.search(r"^(\S+) dtM$", text, re.M).group(1))
    text = re.sub(r"^\S+ dtM$", f"{dtm / dtm_divisor:.9g} dtM", text, flags=re.M)
    (tmp_path / f"lines{dtm_divisor}.txt").write_text(text)
    path = tmp_path / f"released{dtm_divisor}.toml"
    path.write_text(f"""[body]
shape = "cube"
size = 1.0
density = 900.0
[fluid]
forces = "panels"
[moorings]
line_file = "lines{dtm_divisor}.txt"
energy = true
[initial]
position = [{start[0]}, {start[1]}, {start[2]}]
[step]
dt = 0.01
t_end = 20.0
""")
    return path


@pytest.mark.slow
def test_a_moored_body_and_its_lines_keep_their_energy(tmp_path):
    """The buoy released off its rest in still water (no damping, no radiation): what the body loses the lines store or
    dissipate. E_total + E_lines + D_lines stays within 1 % of what the lines dissipate in 20 s (100 J: a balance without
    their drag, internal damping and seabed would miss all of it). Measured: 0.5 % at most, in the first seconds while the
    lines move fast, at either MoorDyn step; at the end 0.5 % at MoorDyn's step and 0.03 % at a quarter of it (MoorDyn's
    own RK2 error): at least five times closer."""
    end = {}
    for divisor in (1, 4):
        out = tmp_path / f"run{divisor}.csv"
        done = run(["--scene", str(released_buoy(tmp_path, divisor)), "--every", "10", "--out", str(out)], tmp_path)
        assert done.returncode == 0, done.stderr[-2000:]
        d = np.genfromtxt(out, delimiter=",", names=True)
        total = d["E_total"] + d["E_lines"] + d["D_lines"]
        dissipated = d["D_lines"][-1]
        assert dissipated > 50.0 and np.all(np.diff(d["D_lines"]) >= 0)  # the lines only take energy away
        assert np.abs(total - total[0]).max() < 0.01 * dissipated, (divisor, np.abs(total - total[0]).max(), dissipated)
        end[divisor] = abs(total[-1] - total[0])
    assert end[4] < end[1] / 5, end
    assert "lines' energy: stored" in done.stdout and "bodies, take-offs and lines together" in done.stdout


@pytest.mark.slow
def test_bodies_joined_by_lines_through_buoys_keep_their_energy(tmp_path):
    """absorber-pair in still water without the floats' damping: two bodies on sliding take-offs, a line between them,
    anchors they share and Free buoys. The bodies' energy, the take-offs' and the lines' together stay within 2 % of the
    energy exchanged (the bodies' change; measured 0.6 %)."""
    out = tmp_path / "pair.csv"
    done = run(["--scene", "absorber-pair", "--waves", "still", "--damping", "0", "--t-end", "10", "--line-energy", "True", "--every", "20",
                "--out", str(out)], ROOT)  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    d = np.genfromtxt(out, delimiter=",", names=True)
    body = d["E_total"] + d["E_pto"]
    total = body + d["E_lines"] + d["D_lines"]
    exchanged = np.abs(body - body[0]).max()
    assert exchanged > 20.0
    assert np.abs(total - total[0]).max() < 0.02 * exchanged, (np.abs(total - total[0]).max(), exchanged)


def test_without_the_switch_the_csv_is_as_before(tmp_path):
    out = tmp_path / "plain.csv"
    done = run(["--scene", "moored-buoy", "--t-end", "0.1", "--out", str(out)], ROOT)
    assert done.returncode == 0, done.stderr[-2000:]
    from sim import CSV_COLUMNS

    assert out.read_text().splitlines()[0].split(",") == list(CSV_COLUMNS)
    assert "lines' energy" not in done.stdout


def test_a_nonlinear_line_is_refused_in_one_line(tmp_path):
    text = (
        (ROOT / "assets" / "moorings" / "absorber_pair.txt").read_text().replace("line 0.02 1.0 1.0e5 -1.0", "line 0.02 1.0 curve.dat -1.0")
    )
    (tmp_path / "lines.txt").write_text(text)
    (tmp_path / "curve.dat").write_text(
        "a nonlinear EA\nstrain tension\n(-) (N)\n0.0 0.0\n0.01 1000.0\n0.1 1.0e4"
    )  # three headings, no newline at the end
    scene = (ROOT / "assets" / "scenes" / "absorber-pair.toml").read_text().replace('"../moorings/absorber_pair.txt"', '"lines.txt"')
    (tmp_path / "pair.toml").write_text(scene.replace("\n[moorings]\n", "\n[moorings]\nenergy = true\n"))
    done = run(["--scene", "pair.toml", "--t-end", "0.1"], tmp_path)
    assert done.returncode == 2 and "nonlinear EA or BA" in done.stderr and len(done.stderr.strip().splitlines()) == 1, done.stderr
