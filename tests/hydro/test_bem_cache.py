"""The BEM cache trusts nothing it finds (issue 23, item 8), through `python -m sim run`: a damaged,
wrongly shaped or non-passive coefficients file is refused in one line naming it (Capytaine is blocked
here: no solve of tens of seconds), or solved again when a solver is there; so is a file whose content
is not the sha256 recorded beside it when it was cached (a damping 100 times too large passes every other
check); the cache's temporary file is never written through a link someone placed; an unwritable cache
costs a warning, not the run; an XDG_CACHE_HOME that is a file is one line naming it.
The solver, where one is needed, is a stand-in returning the shipped sphere's coefficients."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from sim.hydro.bem import Coefficients, check, verify_digest
from tests.scenes import shipped_solve

ROOT = Path(__file__).resolve().parents[2]
RUN = ["run", "--scene", "sphere", "--density", "400", "--t-end", "0.1"]
"""The sphere preset made lighter: a rest pose whose coefficients are not shipped, so the cache is asked."""
FAKE_SOLVE = ("import sys, sim.hydro.bem as bem\n"
              f"bem.solve = lambda *a, **k: bem.Coefficients.load(bem.SHIPPED / '{shipped_solve('sphere').name}')\n"
              "from sim.commands import main\nsys.exit(main(sys.argv[1:]))")  # fmt: skip


@pytest.fixture(scope="module")
def no_solver(tmp_path_factory) -> Path:
    """A folder that, first on the path, makes `import capytaine` fail."""
    folder = tmp_path_factory.mktemp("block")
    (folder / "capytaine").mkdir()
    (folder / "capytaine" / "__init__.py").write_text("raise ImportError('blocked by the test: no BEM solve here')\n")
    return folder


def cli(cache: Path, solver: Path | None = None) -> subprocess.CompletedProcess:
    """`python -m sim run` with the BEM cache in `cache`; Capytaine blocked by `solver` (a folder), else the stand-in solve."""
    env = {**os.environ, "FLOATSIM_BEM_CACHE": str(cache), "PYTHONPATH": os.pathsep.join(([str(solver)] if solver else []) + [str(ROOT)])}
    command = [sys.executable, "-m", "sim", *RUN] if solver else [sys.executable, "-c", FAKE_SOLVE, *RUN]
    return subprocess.run(command, capture_output=True, text=True, timeout=120, env=env)


@pytest.fixture(scope="module")
def key_name(no_solver, tmp_path_factory) -> str:
    """The cache file name of RUN's body, from the line that says where its coefficients would be."""
    done = cli(tmp_path_factory.mktemp("empty"), no_solver)
    assert done.returncode == 2 and done.stderr.count("\n") == 1 and "Traceback" not in done.stderr, done.stderr
    return Path(re.search(r"its coefficients in (\S+\.npz)", done.stderr).group(1)).name


def sphere(**changes) -> Coefficients:
    c = Coefficients.load(shipped_solve("sphere"))
    fields = {k: getattr(c, k) for k in ("omega", "added_mass", "damping", "added_mass_inf", "rho", "depth", "panels")}
    return Coefficients(**{**fields, **changes})


GOOD = sphere()
DAMAGED = {
    "garbage": lambda p: p.write_bytes(b"not a zip file\n" * 40),
    "empty file": lambda p: p.write_bytes(b""),
    "empty arrays": lambda p: sphere(omega=np.empty(0), added_mass=np.empty((0, 6, 6)), damping=np.empty((0, 6, 6))).save(p),
    "wrong shape": lambda p: sphere(added_mass=GOOD.added_mass[:, :5, :5]).save(p),
    "zero added mass": lambda p: sphere(added_mass=0 * GOOD.added_mass, added_mass_inf=0 * GOOD.added_mass_inf).save(p),
    "negative damping": lambda p: sphere(damping=-GOOD.damping).save(p),
    "not a number": lambda p: sphere(damping=np.where(GOOD.damping > 1.0, np.nan, GOOD.damping)).save(p),
    "frequencies out of order": lambda p: sphere(omega=GOOD.omega[::-1].copy()).save(p),
}


@pytest.mark.parametrize("damage", list(DAMAGED))
def test_a_bad_cache_file_is_refused_in_one_line_naming_it(damage, key_name, no_solver, tmp_path):
    path = tmp_path / key_name
    DAMAGED[damage](path)
    done = cli(tmp_path, no_solver)
    assert done.returncode == 2 and done.stderr.count("\n") == 1 and "Traceback" not in done.stderr, done.stderr
    assert f"{path} is not usable" in done.stderr and "solving again needs Capytaine" in done.stderr


def test_a_good_cache_file_is_used(key_name, no_solver, tmp_path):
    GOOD.save(tmp_path / key_name)
    done = cli(tmp_path, no_solver)
    assert done.returncode == 0 and "floatsim:" not in done.stderr and "t = 0.1 s:" in done.stdout, done.stderr


def test_a_bad_cache_file_is_solved_again_and_replaced(key_name, tmp_path):
    path = tmp_path / key_name
    DAMAGED["negative damping"](path)
    done = cli(tmp_path)
    assert done.returncode == 0, done.stderr
    assert f"note: {path} is not usable (damping not positive semi-definite" in done.stderr and "solving again" in done.stderr
    np.testing.assert_array_equal(Coefficients.load(path).damping, GOOD.damping)


def test_a_link_at_the_old_temporary_name_is_not_written_through(key_name, tmp_path):
    cache, victim = tmp_path / "cache", tmp_path / "victim.txt"
    cache.mkdir()
    victim.write_text("precious")
    link = cache / key_name.replace(".npz", ".tmp.npz")
    link.symlink_to(victim)
    done = cli(cache)
    assert done.returncode == 0, done.stderr
    assert victim.read_text() == "precious" and link.is_symlink()
    path = cache / key_name
    assert not path.is_symlink() and Coefficients.load(path).panels == GOOD.panels
    record = key_name.replace(".npz", ".sha256")
    assert sorted(p.name for p in cache.iterdir()) == sorted([key_name, record, link.name])  # no temporary left behind


def tamper(path: Path) -> None:
    """The damping times 100, saved in the same format (plausible: it passes the check)."""
    with np.load(path) as f:
        arrays = {k: f[k] for k in f.files}
    arrays["damping"] = 100 * arrays["damping"]
    check(sphere(damping=arrays["damping"]))
    np.savez_compressed(path, **arrays)


def said(done: subprocess.CompletedProcess) -> list[str]:
    """What a run that solved says on stderr besides the solve's estimate (which it must say once, before it)."""
    lines = [line for line in done.stderr.splitlines() if line.startswith("floatsim:")]
    estimates = [line for line in lines if "note: a boundary-element solve (Capytaine) of " in line]
    assert len(estimates) == 1 and "wet panels" in estimates[0] and "Ctrl-C stops it" in estimates[0], done.stderr
    return [line for line in lines if line not in estimates]


@pytest.mark.parametrize("change", ["damping x 100", "record lost"])
def test_a_cached_file_unlike_its_recorded_sha256_is_solved_again(change, key_name, tmp_path):
    path = tmp_path / key_name
    GOOD.save(path)
    verify_digest(path)  # the record written with it
    tamper(path) if change == "damping x 100" else path.with_suffix(".sha256").unlink()
    done = cli(tmp_path)
    assert done.returncode == 0, done.stderr
    notes = said(done)
    why = "its content changed since it was cached" if change == "damping x 100" else "no sha256 recorded beside it"
    assert len(notes) == 1 and f"note: {path} is not usable ({why}" in notes[0] and "solving again" in notes[0], done.stderr
    np.testing.assert_array_equal(Coefficients.load(path).damping, GOOD.damping)
    verify_digest(path)  # cached again with its record


def test_a_tampered_cache_file_is_refused_in_one_line_without_a_solver(key_name, no_solver, tmp_path):
    path = tmp_path / key_name
    GOOD.save(path)
    tamper(path)
    done = cli(tmp_path, no_solver)
    assert done.returncode == 2 and done.stderr.count("\n") == 1 and "Traceback" not in done.stderr, done.stderr
    assert (
        f"{path} is not usable (its content changed since it was cached" in done.stderr and "solving again needs Capytaine" in done.stderr
    )


NO_SOLVE = ("import sys, sim.hydro.bem as bem\n"
            "bem.solve_parts = lambda *a, **k: sys.exit('the test failed: a BEM solve started')\n"
            "from sim.commands import main\nsys.exit(main(sys.argv[1:]))")  # fmt: skip


def test_xdg_cache_home_set_to_a_file_is_one_line_naming_it(tmp_path):
    home = tmp_path / "cache-home"
    home.write_text("a file, not a folder\n")
    env = {k: v for k, v in os.environ.items() if k not in ("FLOATSIM_BEM_CACHE", "CAPYTAINE_CACHE_DIR")}
    env.update(XDG_CACHE_HOME=str(home), PYTHONPATH=str(ROOT))
    done = subprocess.run([sys.executable, "-c", NO_SOLVE, *RUN], capture_output=True, text=True, timeout=120, env=env)
    assert done.returncode == 2 and done.stderr.count("\n") == 1 and "Traceback" not in done.stderr, done.stderr
    assert f"XDG_CACHE_HOME={home} is a file, not a folder" in done.stderr and done.stdout == ""


def test_an_unwritable_cache_costs_a_warning_not_the_run(tmp_path):
    (tmp_path / "file").write_text("")
    done = cli(tmp_path / "file" / "bem")  # a folder under a file: cannot be made, even by root
    assert done.returncode == 0, done.stderr
    warnings = said(done)
    assert len(warnings) == 1 and "warning: cannot cache the radiation coefficients" in warnings[0] and "Traceback" not in done.stderr
    assert "t = 0.1 s:" in done.stdout and "E_rad" in done.stdout  # the run went on with the solved coefficients


def test_every_preset_with_radiation_finds_its_shipped_solve(monkeypatch, tmp_path):
    """A fresh machine solves nothing for the presets: each one with radiation (still water, and in waves with the
    diffraction) finds its coefficients shipped. (The sphere's key once hashed a -0.0 on its water line: every new
    machine re-solved it, and a viewer switching the sphere to waves waited on the solve.)"""
    import sim.hydro.bem as bem
    from sim.scene.config import available_scenes, load_scene, with_overrides
    from sim.simulation import Simulation
    from sim.system.tree import build

    monkeypatch.setenv("FLOATSIM_BEM_CACHE", str(tmp_path))
    monkeypatch.setattr(bem, "solve_parts", lambda *a, **k: pytest.fail("a preset's coefficients were solved, not found shipped"))
    with_radiation = [name for name in available_scenes() if load_scene(name).fluid.radiation == "bem"]
    assert {"sphere", "point-absorber", "moored-buoy", "rm3"} <= set(with_radiation)
    for name in with_radiation:
        scene = load_scene(name)
        for kind in ("still", "regular"):
            waved = with_overrides(scene, waves__kind=kind, waves__height=0.01, waves__period=3.0)
            model = build(waved)[0] if scene.bodies else Simulation(waved, backend="numpy").model
            assert (model.radiation.diffraction is not None) == (kind == "regular")
    assert not list(tmp_path.glob("*.npz"))  # nothing solved, nothing cached
