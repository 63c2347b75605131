"""Several bodies on joints (sim/system/tree.py): checked against one-body runs, closed forms and the energy balance."""

import dataclasses
import textwrap

import numpy as np
import pytest

from sim.bodies.body import Body
from sim.hydro.forces import Model
from sim.scene.config import load_scene
from sim.simulation import Simulation
from sim.system.frame import body_frames
from sim.system.tree import Member, System, build
from tests.dynamics.test_joints import damped_heave


def scene_file(tmp_path, text: str, name: str = "system.toml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return load_scene(str(path))


SLIDE = """
    [fluid]
    forces = "panels"
    damping = 50.0
    [waves]
    kind = "regular"
    height = 0.1
    period = 2.2
    [[bodies]]
    name = "cube"
    shape = "cube"
    density = 600.0
    position = [0.0, 0.0, 0.1]
    joint = "prismatic"
    axis = [0.0, 0.0, 1.0]
    pto_damping = 2000.0
    pto_stiffness = 500.0
    [step]
    dt = 0.01
"""


def test_one_body_on_a_slide_steps_as_the_joint_to_the_world(tmp_path):
    """The same scheme as joints.py: one body on a world slide, in waves with damping and a take-off, gives
    the world joint's trajectory and absorbed energy to round-off."""
    scene = scene_file(tmp_path, SLIDE)
    system, s = build(scene)
    e = scene.bodies[0]
    sim = Simulation(dataclasses.replace(scene, bodies=(), body=e.body, initial=e.initial, constraint=e.constraint), backend="numpy")
    for _ in range(200):
        s = system.step(s, 0.01)
    sim.step(200)
    assert abs(s.theta[0] - sim.joint.coordinate(sim.state)) < 1e-12
    assert abs(s.v[0] - sim.joint.rate(sim.body, sim.state)) < 1e-11
    assert s.absorbed[0] == pytest.approx(sim.pto_energy, rel=1e-10) and sim.pto_energy > 10.0


PAIR = """
    [fluid]
    forces = "panels"
    damping = 200.0
    [waves]
    kind = "regular"
    height = 0.2
    period = 2.5
    direction = 30.0
    [[bodies]]
    name = "hull"
    shape = "box"
    extents = [1.0, 0.6, 0.5]
    density = 500.0
    position = [0.0, 0.0, 0.0]
    omega = [0.3, -0.2, 0.5]
    velocity = [0.1, 0.0, 0.2]
    [[bodies]]
    name = "outrigger"
    parent = "hull"
    joint = "fixed"
    shape = "cube"
    size = 0.4
    density = 300.0
    position = [0.2, 0.9, 0.05]
    orientation = [0.9659258262890683, 0.0, 0.0, 0.25881904510252074]
"""


def test_the_waters_damping_acts_along_each_bodys_slide(tmp_path):
    """Two cubes on slides, the water's heave damping alone: each m z'' = -rho g A z - B33 z' in closed form (guards tree's J^T D J)."""
    B, starts = 800.0, (0.1, -0.06)
    text = f"""
        [fluid]
        forces = "panels"
        damping = 0.0
        heave_damping = {B}
        [waves]
        kind = "still"
        [step]
        dt = 0.01
        """
    for k, start in enumerate(starts):
        text += f"""
        [[bodies]]
        name = "cube{k}"
        shape = "cube"
        density = 500.0
        position = [{4.0 * k}, 0.0, 0.0]
        joint = "prismatic"
        axis = [0.0, 0.0, 1.0]
        start = {start}
        """
    system, s = build(scene_file(tmp_path, text))
    t, z = [], []
    for _ in range(300):
        s = system.step(s, 0.01)
        t.append(s.t)
        z.append(s.theta.copy())
    for k, start in enumerate(starts):
        expected = damped_heave(np.array(t), start, 500.0, 1000.0 * 9.81, B)
        error = np.abs(np.array(z)[:, k] - expected).max()
        assert error < 1e-3 * abs(start), (k, error)


def merged(members: list[Member], water, fluid) -> Member:
    """One body of the members' surfaces, mass and inertia (parallel axes), about their common centre of mass."""
    mass = sum(m.body.mass for m in members)
    com = sum(m.body.mass * m.offset for m in members) / mass
    tensor = np.zeros((3, 3))
    for m in members:
        c = m.offset - com
        tensor += m.rotation @ np.diag(m.body.inertia) @ m.rotation.T + m.body.mass * (c @ c * np.eye(3) - np.outer(c, c))
    moments, axes = np.linalg.eigh(tensor)
    if np.linalg.det(axes) < 0:
        axes[:, 2] *= -1

    def world(m, a):  # body-frame points of a member in the merged body's frame
        return (a @ m.rotation.T + (m.offset - com)) @ axes

    faces, count = [], 0
    for m in members:
        faces.append(m.body.mesh_faces + count)
        count += len(m.body.mesh_vertices)
    body = Body(np.vstack([world(m, m.body.r_body) for m in members]), np.vstack([m.body.n_body @ m.rotation.T @ axes for m in members]),
                np.concatenate([m.body.area for m in members]), mass, moments, sum(m.body.volume for m in members), 2.0,
                np.vstack([world(m, m.body.mesh_vertices) for m in members]), np.vstack(faces), np.array([1.0, 0, 0, 0]),
                np.vstack([world(m, m.body.cell_corners.reshape(-1, 3)).reshape(-1, 4, 3) for m in members]), "merged", True)  # fmt: skip
    return Member("merged", Model(body, water, fluid), com, axes)


@pytest.mark.slow
def test_a_welded_pair_moves_as_one_body_of_their_combined_mass_and_inertia(tmp_path):
    """Two bodies on a fixed joint, turning and drifting in oblique waves with damping, against one body made of
    both surfaces with the combined mass and inertia: the same trajectory to 1e-9 m over 10 s."""
    scene = scene_file(tmp_path, PAIR)
    system, s = build(scene)
    assert len(system.groups) == 1 and system.n_dofs == 6
    group = system.groups[0]
    one = merged(list(group.members), system.water, system.members[0].model.fluid)
    single = System([dataclasses.replace(group, members=(one,))], [(0, 0)], system.water, system.fluid)
    r = s
    for _ in range(1000):
        s, r = system.step(s, 0.01), single.step(r, 0.01)
    assert np.abs(s.x_free - r.x_free).max() < 1e-9
    assert np.abs(s.q_free - r.q_free).max() < 1e-9
    moved = body_frames(system, s)[1].x_world - np.array([0.2, 0.9, 0.05])
    turned = 2 * np.arccos(min(1.0, abs(s.q_free[0, 0])))
    assert np.linalg.norm(moved) > 0.1 and turned > 0.1  # it moved and turned: the check is not of a body at rest


CHAIN = """
    [fluid]
    forces = "panels"
    [[bodies]]
    name = "barge"
    shape = "box"
    extents = [2.0, 1.0, 0.5]
    density = 500.0
    position = [0.0, 0.0, 0.05]
    omega = [0.1, 0.3, 0.0]
    velocity = [0.2, 0.0, 0.1]
    [[bodies]]
    name = "flap"
    parent = "barge"
    joint = "revolute"
    axis = [0.0, 1.0, 0.0]
    pivot = [-0.6, 0.0, 0.0]
    pto_damping = 150.0
    pto_stiffness = 80.0
    shape = "box"
    extents = [1.2, 0.8, 0.2]
    density = 400.0
    position = [1.6, 0.0, 0.0]
    omega = [0.0, -0.5, 0.0]
    [[bodies]]
    name = "buoy"
    parent = "barge"
    joint = "prismatic"
    axis = [0.0, 0.0, 1.0]
    pto_damping = 400.0
    shape = "cube"
    size = 0.4
    density = 300.0
    position = [-1.3, 0.0, 0.1]
"""


def run_chain(scene, dt: float, t_end: float):
    system, s = build(scene)
    e0 = sum(system.energies(s).values())
    frames = []
    for _ in range(round(t_end / dt)):
        s = system.step(s, dt)
        frames.append(body_frames(system, s))
    return system, s, e0, frames


PLANAR_CHAIN = CHAIN.replace(
    "    omega = [0.1, 0.3, 0.0]\n", '    omega = [0.0, 0.3, 0.0]\n    joint = "planar"\n    axis = [0.0, 1.0, 0.0]\n'
)
"""The chain with the barge on a planar joint to the world (surge, heave and pitch, as WEC-Sim's RM3 spar), rocking in its plane."""


@pytest.mark.parametrize("chain", [CHAIN, PLANAR_CHAIN], ids=["free", "planar"])
def test_energy_closes_with_the_take_offs_to_second_order(tmp_path, chain):
    """A barge with a hinged flap and a sliding buoy, both with take-offs, rocking in still water without damping:
    kinetic + gravity + hydrostatic + spring energy plus what the take-offs absorbed stays constant, its error
    falls as dt^2."""
    scene = scene_file(tmp_path, chain)
    errors = []
    for dt in (0.02, 0.01):
        system, s, e0, _ = run_chain(scene, dt, 2.0)
        errors.append(abs(sum(system.energies(s).values()) + s.absorbed.sum() - e0))
        assert min(s.absorbed[g.coordinate] for g in system.joints) > 0.05  # both take-offs worked
    assert 3.0 < errors[0] / errors[1] < 5.5
    assert errors[1] < 2e-3 * e0


def test_joints_hold_to_round_off(tmp_path):
    """Through the bodies' own poses: the flap's hinge point stays on the barge's, its axis the barge's; the buoy
    stays on its slide (the line through its start, fixed in the barge) without turning against it."""
    scene = scene_file(tmp_path, CHAIN)
    _, _, _, frames = run_chain(scene, 0.02, 2.0)
    from sim.bodies.rotation import quat_to_matrix

    barge0, flap0, buoy0, pivot0 = (
        np.array([0.0, 0.0, 0.05]),
        np.array([1.6, 0.0, 0.0]),
        np.array([-1.3, 0.0, 0.1]),
        np.array([1.0, 0.0, 0.0]),
    )
    worst = 0.0
    for barge, flap, buoy in frames:
        Rb, Rf = quat_to_matrix(barge.q_world_body), quat_to_matrix(flap.q_world_body)  # both start unturned
        on_barge, on_flap = barge.x_world + Rb @ (pivot0 - barge0), flap.x_world + Rf @ (pivot0 - flap0)
        worst = max(worst, np.abs(on_barge - on_flap).max(), np.abs(Rb[:, 1] - Rf[:, 1]).max())
        slide = Rb.T @ (buoy.x_world - barge.x_world) - (buoy0 - barge0)  # along the barge's z only
        worst = max(worst, abs(slide[0]), abs(slide[1]), np.abs(Rb - quat_to_matrix(buoy.q_world_body)).max())
    assert worst < 1e-12
    assert abs(frames[-1][1].omega_world - frames[-1][0].omega_world).max() > 0.01  # the hinge did turn


def test_a_planar_joint_moves_as_a_free_body_kept_in_its_plane_by_symmetry(tmp_path):
    """The chain rocking in the x-z plane (every body symmetric about it, still water, started in-plane): with the
    barge free it stays in the plane by symmetry; on a planar joint it must move the same, every body to 1e-10 m,
    the hinge's and the slide's coordinates likewise; the planar joint's three coordinates are the barge's surge,
    heave and pitch."""
    free = scene_file(tmp_path, PLANAR_CHAIN.replace('    joint = "planar"\n    axis = [0.0, 1.0, 0.0]\n', ""), "free.toml")
    _, a, _, frames_free = run_chain(free, 0.01, 2.0)
    system, b, _, frames_planar = run_chain(scene_file(tmp_path, PLANAR_CHAIN), 0.01, 2.0)
    assert system.n_dofs == 5 and max(abs(f[0].x_world[1]) for f in frames_free) < 1e-12  # in the plane: symmetry holds
    for f, p in zip(frames_free, frames_planar):
        for body_free, body_planar in zip(f, p):
            assert np.abs(body_free.x_world - body_planar.x_world).max() < 1e-10
            assert np.abs(body_free.q_world_body - body_planar.q_world_body).max() < 1e-10
    np.testing.assert_allclose(a.theta, b.theta[3:], atol=1e-10)
    barge = frames_planar[-1][0]
    pitch = 2 * np.arctan2(barge.q_world_body[2], barge.q_world_body[0])
    np.testing.assert_allclose(b.theta[:3], [barge.x_world[0], barge.x_world[2] - 0.05, pitch], atol=1e-12)
    pitches = [abs(2 * np.arctan2(f[0].q_world_body[2], f[0].q_world_body[0])) for f in frames_planar]
    assert max(pitches) > 0.03 and max(abs(f[0].x_world[0]) for f in frames_planar) > 0.05  # it pitched (2.5 degrees) and surged


def sim_cli(*args: str, backend: str = "numpy"):
    import os
    import subprocess
    import sys

    return subprocess.run([sys.executable, "-m", "sim", *args], capture_output=True, text=True, timeout=120, check=False,
                          env={**os.environ, "FLOATSIM_BACKEND": backend})  # fmt: skip


SLIDING_PAIR = (
    SLIDE.replace('name = "cube"', 'name = "spar"')
    + """
    [[bodies]]
    name = "float"
    parent = "spar"
    joint = "prismatic"
    axis = [0.0, 0.0, 1.0]
    pto_damping = 300.0
    shape = "box"
    extents = [0.6, 0.6, 0.3]
    density = 400.0
    position = [0.0, 0.0, 0.8]
"""
)
"""A spar-like cube on a slide to the seabed and a float sliding on it, in waves: the rm3 preset's kernels (panels, damping, waves)."""


def test_run_writes_every_body_and_joint_to_csv(tmp_path):
    """`python -m sim run` on a [[bodies]] scene: a column per body's pose and twist and per joint, the joints
    holding in the rows (the float slides on the spar's vertical: same x, y), and the energy balance in the summary."""
    (tmp_path / "pair.toml").write_text(textwrap.dedent(SLIDING_PAIR))
    out = tmp_path / "pair.csv"
    done = sim_cli("run", "--scene", str(tmp_path / "pair.toml"), "--t-end", "3", "--every", "10", "--out", str(out))
    assert done.returncode == 0, done.stderr
    header = out.read_text().splitlines()[0].split(",")
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    assert header[:4] == ["t", "spar_x", "spar_y", "spar_z"] and "float_P_pto" in header and header[-2:] == ["E_total", "E_rad"]
    col = {name: data[:, i] for i, name in enumerate(header)}
    assert len(data) == 31 and np.isfinite(data).all()
    assert np.abs(col["float_x"] - col["spar_x"]).max() < 1e-12 and np.abs(col["float_y"]).max() < 1e-12
    rel = col["float_z"] - col["spar_z"] - 0.7
    np.testing.assert_allclose(rel, col["float_theta"], atol=1e-12)  # its coordinate is the slide against the spar
    np.testing.assert_allclose(col["float_P_pto"], 300.0 * col["float_rate"] ** 2, rtol=1e-9)
    assert col["float_E_pto"][-1] > 0 and "2 bodies" in done.stdout and "loads on the numpy reference" in done.stdout
    assert not col["E_rad"].any()  # no radiation here


def test_the_bodies_compiled_loads_match_the_reference_stage_by_stage(tmp_path):
    """Each body's loads from its compiled twin (kernels: linearised_loads) against forces.Model.linearised at the
    same pose, time and twist (the float crossing the wave surface), f and D to round-off; then the pair stepped
    on both for 2 s: the same trajectory to 1e-12."""
    from sim.compiling import warm_up

    system, s = build(scene_file(tmp_path, SLIDING_PAIR))
    for spec in system.specs:
        warm_up(spec)
    for _ in range(60):
        s = system.step(s, 0.01)
    pose = system.pose(s)
    reference = [loads(x, R, s.t, J @ s.v) for loads, x, R, J in zip(system.loads, pose.x, pose.R, pose.J)]
    system.use_kernels(True, expand=False)
    compiled = [loads(x, R, s.t, J @ s.v) for loads, x, R, J in zip(system.loads, pose.x, pose.R, pose.J)]
    for (f0, D0), (f1, D1) in zip(reference, compiled):
        scale = np.abs(f0).max()
        np.testing.assert_allclose(f1, f0, rtol=0, atol=1e-12 * scale)
        np.testing.assert_allclose(D1, D0, rtol=0, atol=1e-12 * np.abs(D0).max())
    assert 0 < np.abs(reference[1][1]).max()  # the float is wet: its damping matrix is there to compare
    a = b = s
    for _ in range(200):
        a = system.step(a, 0.01)
    system.use_kernels(False)
    for _ in range(200):
        b = system.step(b, 0.01)
    assert abs(a.theta[1] - s.theta[1]) > 1e-3  # it moved
    np.testing.assert_allclose(a.theta, b.theta, rtol=0, atol=1e-12)
    np.testing.assert_allclose(a.v, b.v, rtol=0, atol=1e-12)
    np.testing.assert_allclose(a.absorbed, b.absorbed, rtol=1e-12)


def test_run_compiles_the_bodies_loads_and_says_so(tmp_path):
    """The CLI on the numba backend with the kernels on disk: the bodies' loads compiled (the summary says so), and
    its rows the numpy reference's to the sea expansion's bound (1e-9 m)."""
    from sim.compiling import warm_up

    (tmp_path / "pair.toml").write_text(textwrap.dedent(SLIDING_PAIR))
    for spec in Simulation(load_scene(str(tmp_path / "pair.toml")), backend="numpy").specs:  # the loads' and the system step's
        warm_up(spec)  # into the disk cache the child reads
    rows = {}
    for backend in ("numba", "numpy"):
        out = tmp_path / f"{backend}.csv"
        done = sim_cli("run", "--scene", str(tmp_path / "pair.toml"), "--t-end", "2", "--every", "20", "--out", str(out), backend=backend)
        assert done.returncode == 0, done.stderr
        rows[backend] = np.loadtxt(out, delimiter=",", skiprows=1)
        assert ("loads compiled" in done.stdout) == (backend == "numba"), done.stdout
    np.testing.assert_allclose(rows["numba"], rows["numpy"], rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize(("entry", "message"), [
    ('name = "a"\nparent = "b"\njoint = "fixed"', "parent 'b' is not a body listed before it"),
    ('name = "a"\nparent = "world"\njoint = "free"\n[[bodies]]\nname = "a"', "body names must be distinct"),
    ('name = "a"\nparent = "world"\njoint = "free"\n[[bodies]]\nname = "b"\nparent = "a"', "a free body has no parent"),
    ('name = "a"\njoint = "hinge"', "joint must be one of"),
    ('name = "a"\nforces = "magic"', "forces must be one of"),
    ('name = "a"\ncolour = "red"', "unknown key 'colour'"),
    ('shape = "cube"', "give the body a name"),
    ('name = "a"\npoints_per_edge = 1000', "6,000,000 surface samples"),  # the one-body limits hold for each
    ('name = "a"\njoint = "prismatic"\naxis = [0.0, 0.0, 0.0]', "[[bodies]] a: [constraint] axis must not be zero"),
    ('name = "a"\njoint = "planar"\naxis = [0.0, 1.0, 0.0]\npto_damping = 5.0', "a: a planar joint has three coordinates"),
])  # fmt: skip
def test_bad_bodies_are_one_line_errors(tmp_path, entry, message):
    (tmp_path / "bad.toml").write_text("[[bodies]]\n" + entry + "\n")
    done = sim_cli("run", "--scene", str(tmp_path / "bad.toml"))
    assert done.returncode == 2 and message in done.stderr and len(done.stderr.strip().splitlines()) == 1, done.stderr


def test_one_body_flags_do_not_apply_to_several_bodies(tmp_path):
    (tmp_path / "pair.toml").write_text(textwrap.dedent(SLIDE))
    done = sim_cli("run", "--scene", str(tmp_path / "pair.toml"), "--density", "300")
    assert done.returncode == 2 and "this scene's bodies are its [[bodies]] (cube): name the body, e.g. cube.density" in done.stderr


MOORED = """
    [fluid]
    forces = "panels"
    damping = 100.0
    [waves]
    kind = "regular"
    height = 0.1
    period = 2.0
    [moorings]
    lines = 3
    anchor_radius = 25.0
    anchor_depth = 10.0
    fairlead_radius = 0.5
    fairlead_height = -0.3
    line_length = 28.0
    line_mass = 1.0
    line_diameter = 0.02
    line_stiffness = 1.0e5
    segments = 10
    [[bodies]]
    name = "pontoon"
    shape = "cube"
    density = 900.0
    position = [0.3, 0.0, -0.4]
    joint = "prismatic"
    axis = [1.0, 0.0, 0.0]
    pto_damping = 50.0
    [step]
    dt = 0.01
"""


def test_mooring_lines_on_one_of_several_bodies_pull_as_on_one_body(tmp_path):
    """A pontoon on a surge slide held by three MoorDyn lines, as a [[bodies]] entry and as a one-body scene with the
    same joint: the same lines' pull held over each step, so the same surge and take-off energy to round-off; the lines
    pull it back towards the middle (it starts 0.3 m off)."""
    pytest.importorskip("moordyn")
    from sim.simulation import Simulation

    scene = scene_file(tmp_path, MOORED)
    run = Simulation(scene, backend="numpy")
    e = scene.bodies[0]
    sim = Simulation(dataclasses.replace(scene, bodies=(), body=e.body, initial=e.initial, constraint=e.constraint), backend="numpy")
    try:
        run.step(300)
        sim.step(300)
        assert abs(run.state.theta[0] - sim.joint.coordinate(sim.state)) < 1e-10
        assert run.state.absorbed[0] == pytest.approx(sim.pto_energy, rel=1e-8)
        assert run.state.theta[0] < -0.05  # pulled back
        frame = run.frame()
        np.testing.assert_allclose(frame.mooring[:3], sim.frame().mooring_force, rtol=1e-8)
        assert len(frame.lines) == 3 and frame.lines[0].shape == (11, 3)
    finally:
        run.close()
        sim.moorings.close()


def test_run_writes_the_lines_pull_for_several_bodies(tmp_path):
    """The CLI on a moored [[bodies]] scene: the one-body scene's mooring columns, the pull along the slide's axis the
    one that moves it; a [moorings] body that is not one of the bodies is a one-line error."""
    pytest.importorskip("moordyn")
    (tmp_path / "moored.toml").write_text(textwrap.dedent(MOORED))
    out = tmp_path / "moored.csv"
    done = sim_cli("run", "--scene", str(tmp_path / "moored.toml"), "--t-end", "1", "--every", "10", "--out", str(out))
    assert done.returncode == 0, done.stderr
    header = out.read_text().splitlines()[0].split(",")
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    col = {name: data[:, i] for i, name in enumerate(header)}
    assert {"Fx_moor", "Fy_moor", "Fz_moor", "T_fair_max"} <= col.keys()
    assert (col["Fx_moor"][1:] < 0).all() and (col["T_fair_max"] > np.abs(col["Fx_moor"]) / 3).all()
    (tmp_path / "bad.toml").write_text(textwrap.dedent(MOORED).replace("[moorings]\n", '[moorings]\nbody = "buoy"\n'))
    done = sim_cli("run", "--scene", str(tmp_path / "bad.toml"))
    assert done.returncode == 2 and "[moorings] body = 'buoy' is not one of the [[bodies]]: pontoon" in done.stderr
