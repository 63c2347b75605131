"""The shape of the code that the physics relies on: one declaration per parameter reaches every
place that needs it, water is asked rather than assumed, the scene describes what runs, and the
physics package imports no viewer, plotting or command-line library."""

import ast
import dataclasses
import importlib.util
import subprocess
import sys
from pathlib import Path

import grimp
import numpy as np
import pytest

from sim import PARAMS, TERMS, FluidConfig, Model, Simulation, StillWater, load_scene
from sim.bodies.body import make_box
from sim.commands.run import RunArgs
from sim.kernels.layout import coefficients, slot

ROOT = Path(__file__).resolve().parent.parent
SIM = ROOT / "sim"


def test_the_layers_hold_as_written():
    """pyproject.toml's import-linter contracts: each layer of sim and app imports only those below it, and the physics
    no viewer, parser or plotting library (CI runs lint-imports too; here a broken layer fails the test line)."""
    lint = Path(sys.executable).parent / "lint-imports"  # import-linter's command, installed beside this python
    out = subprocess.run([str(lint), "--no-cache"], cwd=ROOT, capture_output=True, text=True, check=False)
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-2000:]
    assert "0 broken" in out.stdout


def test_no_module_imports_one_that_imports_it_back():
    """No import cycle among the modules of sim, app and studies, however long, counting imports inside functions
    (a type named only for annotations, under TYPE_CHECKING, is no import at run time)."""
    graph = grimp.build_graph("sim", "app", "studies", include_external_packages=False, exclude_type_checking_imports=True, cache_dir=None)
    cycles = [c for c in _strongly_connected(graph) if len(c) > 1]
    assert not cycles, cycles


def _strongly_connected(graph) -> list[list[str]]:
    """Tarjan's strongly connected components of the import graph (each cycle of modules is one)."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(m: str) -> None:
        index[m] = low[m] = len(index)
        stack.append(m)
        on.add(m)
        for n in graph.find_modules_directly_imported_by(m):
            if n not in index:
                visit(n)
                low[m] = min(low[m], low[n])
            elif n in on:
                low[m] = min(low[m], index[n])
        if low[m] == index[m]:
            component = []
            while True:
                n = stack.pop()
                on.discard(n)
                component.append(n)
                if n == m:
                    break
            out.append(component)

    for m in sorted(graph.modules):
        if m not in index:
            visit(m)
    return out


def test_an_import_inside_a_function_is_for_an_optional_extra_or_a_stated_start_up_cost():
    """Imports of the project's own modules sit at the top of a module, where the layers show them: inside a function
    only numba's kernels (0.6 s to import), and in the viewer viser's and PyAV's modules, each with its reason beside it."""
    allowed = ("sim.kernels", "app.main", "app.recording.video", "app.recording.replay")
    for path in [*SIM.rglob("*.py"), *(ROOT / "app").rglob("*.py")]:
        if "kernels" in path.parts:
            continue  # the kernels' own modules are imported afresh per specialisation (kernels/__init__.py)
        lines = path.read_text().splitlines()
        for fn in ast.walk(ast.parse("\n".join(lines))):
            if not isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            for node in ast.walk(fn):
                if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module.split(".")[0] in ("sim", "app"):
                    target = node.module + ("." + node.names[0].name if node.module == "sim" else "")
                    assert target.startswith(allowed), f"{path}:{node.lineno} imports {target} inside a function"
                    assert "#" in lines[node.end_lineno - 1] or "#" in lines[node.lineno - 1], (
                        f"{path}:{node.lineno}: say why it is imported here"
                    )
                assert not isinstance(node, ast.Import) or not node.names[0].name.startswith(("sim", "app")), f"{path}:{node.lineno}"


def test_the_layers_page_is_made_from_the_code():
    """docs/developer.md's map is what `python docs/layers.py` makes of the code now."""
    spec = importlib.util.spec_from_file_location("layers", ROOT / "docs" / "layers.py")
    layers = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(layers)
    text = layers.PAGE.read_text()
    assert layers.page_with(text, layers.picture()) == text, "the layers in docs/developer.md are stale: run python docs/layers.py"
    assert text.count("| `sim.") >= 15 and "`sim.hydro` | What water does to a body" in text


def test_physics_package_imports_no_viewer_plotting_or_cli_library():
    code = "import sys, sim, sim.kernels, sim.ensemble; print(sorted(m for m in ('tyro', 'matplotlib', 'viser', 'app', 'studies') if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
    for path in SIM.rglob("*.py"):
        if "commands" in path.parts:
            continue  # the command line is the one subpackage that uses tyro
        for node in ast.walk(ast.parse(path.read_text())):
            names = (
                [a.name for a in node.names]
                if isinstance(node, ast.Import)
                else [node.module or ""]
                if isinstance(node, ast.ImportFrom)
                else []
            )
            for name in names:
                assert name.split(".")[0] not in ("tyro", "matplotlib", "viser", "app", "studies"), (path, name)


@pytest.mark.parametrize("term", TERMS, ids=lambda t: t.name)
def test_each_term_parameter_is_a_scene_key_a_flag_a_control_and_a_kernel_slot(term):
    from app.live.loop import CONTROLLED

    fields = {f.name for f in dataclasses.fields(FluidConfig)}
    flags = {f.name for f in dataclasses.fields(RunArgs)}
    for p in term.params:
        assert PARAMS[f"fluid.{p.key}"] is p and p.key in fields and p.key in flags
        assert (p.key in CONTROLLED) == (p.gui is not None)
        fluid = FluidConfig(**{p.key: 0.25})
        assert coefficients(fluid)[slot(p.key)] == 0.25
        assert not any(t.name == term.name for t in Model(make_box((1, 1, 1), 2, 1.0), StillWater(), FluidConfig(**{p.key: 0.0})).terms)


class RaisedWater(StillWater):
    """Calm water whose surface stands at z = 0.3 m instead of 0."""

    flat = False  # not the kernels' plane z = 0

    def elevation(self, xy, t):
        return np.full(np.shape(xy)[:-1], 0.3)

    def pressure(self, points, t):
        return -self.rho * self.g * (points[..., 2] - 0.3)


@pytest.mark.parametrize("forces", ["points", "panels"])
def test_wet_surface_and_pressure_come_from_the_water(forces):
    """The ice cube floats 0.9 m deep below whatever surface the water has: raised by 0.3 m, its rest
    height rises by 0.3 m; nothing assumes the plane z = 0."""
    body = make_box((1.0, 1.0, 1.0), 6, 900.0, "cube")
    fluid = FluidConfig(forces=forces)
    model = Model(body, RaisedWater(), fluid)
    wet = model.wetted(np.array([0.0, 0.0, -0.1]), np.eye(3))
    force, torque = model.pose_loads(wet)
    np.testing.assert_allclose(force, 0.0, atol=1e-9 * body.mass * 9.81)
    np.testing.assert_allclose(torque, 0.0, atol=1e-9)
    assert wet.submerged_area == pytest.approx(1.0 + 4 * (0.9 if forces == "panels" else 5 / 6))  # samples: 5 of 6 rows per side
    still = Model(body, StillWater(), fluid).pose_loads(Model(body, StillWater(), fluid).wetted(np.array([0.0, 0.0, -0.1]), np.eye(3)))
    assert still[0][2] == pytest.approx(1000 * 9.81 * 0.6 - 900 * 9.81)  # in still water that pose is not a rest


def test_scene_stays_current_and_describes_what_runs():
    """After changes between steps, a fresh Simulation built from `scene` continues identically."""
    sim = Simulation(load_scene("damped"), backend="numpy")
    sim.step(50)
    sim.set_density(700.0)
    sim.set_params(damping=250.0, drag_coefficient=0.4)
    sim.set_dt(0.004)
    sim.set_integrator("rk4")
    sim.update(body__points_per_edge=7)
    s = sim.scene
    assert (s.body.density, s.fluid.damping, s.fluid.drag_coefficient, s.step.dt, s.step.integrator, s.body.points_per_edge) == (
        700.0, 250.0, 0.4, 0.004, "rk4", 7)  # fmt: skip
    assert sim.body.mass == pytest.approx(700.0) and sim.body.n_samples == 6 * 49 and sim.model.term_names[-1] == "drag"
    twin = Simulation(sim.scene, backend="numpy")
    twin.reset(sim.state)
    sim.step(30)
    twin.step(30)
    np.testing.assert_array_equal(sim.state.as_vector(), twin.state.as_vector())
