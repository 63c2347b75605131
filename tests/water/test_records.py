"""Measured seas ([waves] kind = "record"): a record of the elevation at a point, taken apart into components,
gives back the sea that wrote it, moves a body as that sea does, and refuses a bad file in one line."""

import dataclasses
import math
import subprocess
import sys

import numpy as np
import pytest

from sim.scene.config import load_scene
from sim.water.records import describe, repeat_period
from sim.water.seas import jonswap_waves, make_water, wavenumber

G = 9.81
POINT = (3.0, -2.0)


def _on_grid(sea, length):
    """The sea with each frequency moved to the nearest multiple of 2 pi / length (merged where two meet), so that a
    record `length` long holds it exactly."""
    j = np.round(sea.omega * length / (2 * math.pi)).astype(int)
    keep = np.unique(j, return_index=True)[1]
    omega = 2 * math.pi * j[keep] / length
    return dataclasses.replace(sea, amplitude=sea.amplitude[keep], omega=omega, k=wavenumber(omega, G, sea.depth),
                               direction=sea.direction[keep], phase=sea.phase[keep])  # fmt: skip


def _write(path, t, eta, header="time (s), eta (m)"):
    np.savetxt(path, np.c_[t, eta], delimiter=",", header=header, comments="# written by the test\n")


def _scene(path, record, *extra):
    path.write_text("\n".join(["[waves]", 'kind = "record"', f'record = "{record}"', f"record_point = [{POINT[0]}, {POINT[1]}]", *extra]))
    return load_scene(str(path))


@pytest.mark.parametrize("depth", [math.inf, 30.0], ids=["deep", "depth 30 m"])
def test_a_record_of_a_sea_on_its_grid_gives_back_that_sea(tmp_path, depth):
    """A JONSWAP sea travelling at 30 degrees, its frequencies on the grid of a 200 s record, written at a point off the
    origin (with a header, a comment and a time origin of 5 s): the record's components are the sea's (amplitude,
    frequency, phase referred to the origin) and its elevation matches the sea's anywhere, at any time, to 1e-12."""
    length, dt = 200.0, 0.1
    sea = jonswap_waves(1025.0, G, 2.0, 8.0, components=64, seed=3, direction_deg=30.0, depth=depth)
    sea = _on_grid(sea, length)
    t = np.arange(round(length / dt)) * dt
    eta = np.array([sea.elevation(np.array([POINT]), ti)[0] for ti in t])
    _write(tmp_path / "rec.csv", t + 5.0, eta + 0.25)  # a gauge offset: the mean is not a wave
    depth_line = [] if math.isinf(depth) else [f"depth = {depth}"]
    scene = _scene(tmp_path / "s.toml", "rec.csv", "direction = 30.0", "ramp = 0", *depth_line)
    got = make_water(scene.waves, 1025.0, G, base_dir=scene.base_dir)
    order = np.argsort(sea.omega)
    np.testing.assert_allclose(got.omega, sea.omega[order], rtol=1e-12)
    np.testing.assert_allclose(got.amplitude, sea.amplitude[order], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(np.exp(1j * got.phase), np.exp(1j * sea.phase[order]), atol=1e-9)
    rng = np.random.default_rng(0)
    xy = rng.uniform(-50, 50, (20, 2))
    for ti in (0.0, 13.37, 151.9, 700.0):
        np.testing.assert_allclose(got.elevation(xy, ti), sea.elevation(xy, ti), atol=1e-12 * sea.amplitude.sum())
    points = np.c_[xy, rng.uniform(-10, -0.5, 20)]
    np.testing.assert_allclose(got.pressure(points, 42.0), sea.pressure(points, 42.0), atol=1e-9 * 1025 * G * sea.amplitude.sum())


def test_the_record_is_its_periodic_extension_exact_at_every_sample(tmp_path):
    """A record not on any grid (noise and a tone between bins), every component kept (a cut-off at the Nyquist
    period): the sea equals it at every sample, less its mean and its Nyquist component, and repeats after the
    record's length; with a cut-off only the longer waves remain; unset, the cut-off is at 4 times the peak frequency."""
    rng = np.random.default_rng(1)
    n, dt = 600, 0.2
    t = np.arange(n) * dt
    eta = 0.3 * np.sin(0.913 * t) + 0.05 * rng.standard_normal(n) + 0.1
    _write(tmp_path / "rec.csv", t, eta)
    scene = _scene(tmp_path / "s.toml", "rec.csv", "ramp = 0", f"cutoff_period = {2 * dt}")  # every component kept
    sea = make_water(scene.waves, 1025.0, G, base_dir=scene.base_dir)
    assert len(sea.omega) == n // 2 - 1
    default = make_water(dataclasses.replace(scene.waves, cutoff_period=None), 1025.0, G, base_dir=scene.base_dir)
    np.testing.assert_allclose(default.omega.max(), 4 * 2 * math.pi * round(0.913 * n * dt / (2 * math.pi)) / (n * dt), rtol=0.02)
    nyquist = np.fft.rfft(eta)[-1].real / n * np.cos(np.pi * np.arange(n))
    at = np.array([sea.elevation(np.array([POINT]), ti)[0] for ti in t])
    np.testing.assert_allclose(at, eta - eta.mean() - nyquist, atol=1e-12)
    later = np.array([sea.elevation(np.array([POINT]), ti + n * dt)[0] for ti in t[:50]])
    np.testing.assert_allclose(later, at[:50], atol=1e-9)
    cut = make_water(dataclasses.replace(scene.waves, cutoff_period=4.0), 1025.0, G, base_dir=scene.base_dir)
    assert cut.omega.max() <= 2 * math.pi / 4.0 + 1e-12 and len(cut.omega) == int(n * dt / 4.0)
    assert describe(sea, scene.waves).endswith(f"repeats after {n * dt:.4g} s")  # the record's length, not its longest wave's period
    assert repeat_period(sea.omega[1::2]) == pytest.approx(n * dt / 2, rel=1e-12)  # only the even multiples: half of it
    assert repeat_period(np.array([3.0, 4.5, 7.5])) == pytest.approx(2 * math.pi / 1.5, rel=1e-12)


def _run(*flags, cwd):
    return subprocess.run([sys.executable, "-m", "sim", "run", *flags], capture_output=True, text=True, timeout=600, cwd=cwd)


def test_a_body_in_the_record_of_a_jonswap_sea_moves_as_in_that_sea(tmp_path):
    """The path a tank user takes: the default JONSWAP sea of the `waves` scene's cube (off the record's grid), its
    elevation at the origin written every 0.1 s for 300 s to a CSV, run again from the record (--waves record
    --wave-record FILE, a cut-off at 1 s; panels; density 150, GM 0.13 m, from rest): over the first 60 s the cube's heave and pitch follow the JONSWAP run's
    within 1 % of their range (the record's sea differs from the original only away from the gauge, by the spread of
    wavenumbers its leaked bins carry, and by the ringing of the record's wrap, far from these times)."""
    scene = load_scene("waves")
    flags = ["--scene", "waves", "--waves", "jonswap", "--hs", "1.0", "--tp", "6.0", "--t-end", "60", "--dt", "0.01", "--every", "10",
             "--wave-ramp", "20", "--forces", "panels", "--density", "150", "--z0", "0.35"]  # fmt: skip
    sea = make_water(dataclasses.replace(scene.waves, kind="jonswap", hs=1.0, tp=6.0, ramp=0.0), scene.fluid.rho, scene.fluid.g)
    t = np.arange(3000) * 0.1
    _write(tmp_path / "gauge.csv", t, np.array([sea.elevation(np.zeros((1, 2)), ti)[0] for ti in t]))
    first = _run(*flags, "--out", "jonswap.csv", cwd=tmp_path)
    second = _run(
        *flags, "--waves", "record", "--wave-record", "gauge.csv", "--wave-cutoff-period", "1.0", "--out", "record.csv", cwd=tmp_path
    )
    assert first.returncode == 0 and second.returncode == 0, (first.stderr + second.stderr)[-2000:]
    from tests.commands.test_cli import read_csv

    header, a = read_csv(tmp_path / "jonswap.csv")
    _, b = read_csv(tmp_path / "record.csv")
    for column in ("z", "qy", "x"):
        i = header.index(column)
        span = np.ptp(a[:, i])
        assert span > 1e-3, column  # the sea moves the cube
        assert np.max(np.abs(a[:, i] - b[:, i])) < 0.01 * span, column


@pytest.mark.parametrize(
    "rows, flags, says",
    [
        (None, ["--wave-record", "missing.csv"], "no such file"),
        ("t,eta\n0,0\n0.1,1\n", [], "at least 8 rows"),
        ("t,eta\n" + "".join(f"{0.1 * i * (1 + 0.1 * (i % 2))},{i % 3}\n" for i in range(20)), [], "equal steps"),
        ("t,eta\n" + "".join(f"{0.1 * i},0.1\n" for i in range(20)) + "x,y\n", [], "is not two numbers"),
        ("".join(f"{0.1 * i},{1000 * math.sin(i / 4)},3\n" for i in range(20)), [], "3 columns"),
        ("".join(f"{0.1 * i},{1000 * math.sin(i / 4)}\n" for i in range(200)), [], "breaking limit"),
        ("".join(f"{0.01 * i},{0.1 * math.sin(i * i)}\n" for i in range(10000)), ["--wave-cutoff-period", "0.02"], "--wave-cutoff-period"),
        ("".join(f"{0.1 * i},{0.1 * math.sin(i / 50)}\n" for i in range(400)), ["--current", "0.5", "0"], "with a current"),
        ("".join(f"{0.1 * i},{1e308 if i == 7 else 0.1}\n" for i in range(200)), [], "no sea rises"),  # (4 overflow warnings first before)
    ],
    ids=[
        "missing",
        "too short",
        "uneven times",
        "text after numbers",
        "three columns",
        "millimetres read as metres",
        "too many components",
        "current",
        "a damaged value",
    ],  # fmt: skip
)
def test_a_bad_record_is_one_line_and_exit_2(tmp_path, rows, flags, says):
    if rows is not None:
        (tmp_path / "rec.csv").write_text(rows)
    done = _run("--scene", "waves", "--waves", "record", "--wave-record", "rec.csv", *flags, "--t-end", "0.1", cwd=tmp_path)
    assert done.returncode == 2 and says in done.stderr, done.stderr[-1000:]
    assert "Traceback" not in done.stderr and len(done.stderr.strip().splitlines()) == 1
