"""Issue 26, moorings: lines on MoorDyn coupled to the body every step, checked against the elastic catenary
(a line at rest), the moored buoy's surge period from its added mass and the lines' linearised stiffness, the
compiled twin against the reference with the lines' pull held over each step, and the user's mistakes."""

from __future__ import annotations

import math
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from sim import ConfigError, Simulation, load_scene, with_overrides
from sim.lines.catenary import catenary, surge_stiffness
from sim.lines.moorings import Moorings, lines_of

ROOT = Path(__file__).resolve().parents[2]
RHO, G = 1000.0, 9.81


def run_cli(tmp_path, *args: str) -> tuple[subprocess.CompletedProcess, np.ndarray | None]:
    out = tmp_path / "run.csv"
    done = subprocess.run(
        [sys.executable, "-m", "sim", "run", "--out", str(out), *args], cwd=ROOT, capture_output=True, text=True, timeout=600
    )
    rows = np.genfromtxt(out, delimiter=",", names=True) if done.returncode == 0 else None
    return done, rows


@pytest.mark.parametrize("segments", [20, 40])
def test_a_line_at_rest_pulls_as_the_elastic_catenary(tmp_path, segments):
    """One line of the moored-buoy preset, as `run` writes its pull at t = 0 (MoorDyn's rest shape for the
    starting pose): the horizontal and vertical tension at the fairlead against the closed-form elastic
    catenary with seabed contact (sim/lines/catenary.py), within 1 %, closer with more segments."""
    done, rows = run_cli(
        tmp_path,
        "--scene",
        "moored-buoy",
        "--lines",
        "1",
        "--segments",
        str(segments),
        "--t-end",
        "0.01",
        "--every",
        "1",
        "--radiation",
        "none",
    )  # one line rests the body at another draft: its own BEM solve, and this is about the line
    assert done.returncode == 0, done.stderr
    assert "moorings: 1 line (MoorDyn), pull now" in done.stdout, done.stdout
    first = rows[0]
    spread = lines_of(load_scene("moored-buoy").moorings)
    X = spread.anchor_radius - (first["x"] + spread.fairlead_radius)  # heading 0: the anchor on +x, the body upright
    Z = spread.anchor_depth + first["z"] + spread.fairlead_height
    H, V = catenary(X, Z, spread.line_length, spread.weight_in_water(RHO, G), spread.line_stiffness)
    assert first["Fx_moor"] == pytest.approx(H, rel=0.01) and -first["Fz_moor"] == pytest.approx(V, rel=0.01)
    assert first["T_fair_max"] == pytest.approx(math.hypot(H, V), rel=0.01)
    assert abs(first["Fy_moor"]) < 1e-6 * H


def test_more_segments_come_closer_to_the_catenary():
    errors = []
    for segments in (5, 10, 20, 40):
        scene = with_overrides(
            load_scene("moored-buoy"), moorings__lines=1, moorings__segments=segments, fluid__radiation="none", waves__kind="still"
        )
        sim = Simulation(scene, backend="numpy")
        s = lines_of(scene.moorings)
        x = sim.state.x_world
        H, V = catenary(s.anchor_radius - x[0] - s.fairlead_radius, s.anchor_depth + x[2] + s.fairlead_height, s.line_length,
                        s.weight_in_water(RHO, G), s.line_stiffness)  # fmt: skip
        errors.append(abs(sim.frame().fairlead_tensions[0] / math.hypot(H, V) - 1))
        sim.moorings.close()
    print("tension error against the catenary, 5/10/20/40 segments:", [f"{e:.2%}" for e in errors])
    assert errors[-1] < 2e-3 and all(b < a for a, b in zip(errors, errors[1:])), errors


def test_the_catenary_holds_a_heavy_chain_at_every_offset_and_meets_the_slack_line():
    """rm3-moored's chain (92 kg/m in water, EA 500 MN, 260 m from 70 m down) over 41 m of fairlead travel: each (H, V)
    puts the fairlead where it is to 1e-10 of the line's length, H grows with the span; and where the line just lifts
    off the seabed the taut solution meets the slack one, a line hanging straight down stretched by its own weight."""
    from sim.lines.catenary import _ends

    scene = load_scene("rm3-moored")
    chain = lines_of(scene.moorings)
    w, L, EA, Z = chain.weight_in_water(RHO, G), chain.line_length, chain.line_stiffness, 70.0 - 18.6743
    hanging = EA * (math.sqrt(1 + 2 * w * Z / EA) - 1)  # Z = V / w + V^2 / (2 EA w)
    X_slack = L - hanging / w  # 208.7 m: taut beyond
    H_before = 0.0
    for X in np.linspace(X_slack + 1e-3, 250.0, 501):
        H, V = catenary(X, Z, L, w, EA)
        np.testing.assert_allclose(_ends(H, V, L, w, EA), (X, Z), atol=1e-9 * L)
        assert H > H_before
        H_before = H
    assert catenary(X_slack - 1e-3, Z, L, w, EA) == (0.0, pytest.approx(hanging, rel=1e-12))
    H, V = catenary(X_slack + 1e-6, Z, L, w, EA)
    assert 0.0 < H < 1e-3 * hanging and V == pytest.approx(hanging, rel=1e-6)


def _surge_period(mass: float, coefficients, k: float) -> float:
    """2 pi sqrt((M + A_11(omega_n)) / k), A_11 read in the solve's grid at the natural frequency itself (a fixed point)."""
    T = 2 * math.pi * math.sqrt(mass / k)
    for _ in range(30):
        w = 2 * math.pi / T
        assert coefficients.omega[0] < w < coefficients.omega[-1]  # inside the solve's grid: read, not clamped
        T = 2 * math.pi * math.sqrt((mass + float(np.interp(w, coefficients.omega, coefficients.added_mass[:, 0, 0]))) / k)
    return T


def _swing_stiffness(scene, rest: np.ndarray, amplitude: float, omega: float, dt: float, periods: int = 5) -> float:
    """The lines' own surge stiffness at a swing: MoorDyn's lines, their fairleads moved by amplitude sin(omega t) about
    the rest (upright, translation only), the pull's in-phase part per metre over the periods after the first two."""
    lines = Moorings.of_scene(scene, rest, np.eye(3), np.zeros(3), np.zeros(3))
    n = int(round(periods * 2 * math.pi / omega / dt))
    t = (np.arange(n) + 0.5) * dt  # the pull is held over each step: its value at the step's middle
    with lines:
        pull = np.array([lines.advance(rest + [amplitude * math.sin(omega * i * dt), 0.0, 0.0], np.eye(3),
                                       np.array([amplitude * omega * math.cos(omega * i * dt), 0.0, 0.0]), np.zeros(3), dt)[0]
                         for i in range(n)])  # fmt: skip
    kept = t > 2 * 2 * math.pi / omega
    return -2 * float(np.mean((pull[kept] - pull[kept].mean()) * np.sin(omega * t[kept]))) / amplitude


@pytest.mark.slow  # over 4 s (the marker's rule)
def test_the_moored_buoy_surges_at_the_period_of_its_added_mass_and_mooring_stiffness():
    """Released 0.5 m off its rest in calm water (the preset's sea at Hs 0: the same compiled kernels), the buoy swings
    at 2 pi sqrt((M + A_11(omega_n)) / k_11) within 0.5 %, A_11 from the solve the run uses (at the moored draft, its
    grid reaching below omega_n) and k_11 the lines' own: MoorDyn's lines swung alone at the buoy's amplitude and
    frequency (measured: 28.20 s at 0.31 m against 28.17 s, +0.10 %). The elastic catenary's static stiffness predicts
    27.98 s (+0.78 %): it leaves out the lines' inertia and drag and MoorDyn's 20 segments (their stiffness is 1.3 %
    lower at this swing, and -5 % to +8 % at a few centimetres, where the touchdown moves less than a segment). Held
    there to 1 %."""
    scene = with_overrides(load_scene("moored-buoy"), waves__hs=0.0, initial__position=(0.5, 0.0, -0.44))  # about its moored draft
    sim = Simulation(scene)
    t, x, z = [], [], []
    while sim.state.t < 120.0:
        sim.step(5)
        t.append(sim.state.t)
        x.append(sim.state.x_world[0])
        z.append(sim.state.x_world[2])
    t, x = np.array(t), np.array(x)
    down = [t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i]) for i in range(len(x) - 1) if x[i] > 0 >= x[i + 1]]
    assert len(down) >= 4, "the buoy did not swing back and forth"
    measured = float(np.mean(np.diff(down[1:])))  # the first swing's lines still settle
    swing = float(np.abs(x[t > down[1]]).max() + np.abs(x[t > down[-1]]).max()) / 2  # the amplitude over those swings
    rest = np.array([0.0, 0.0, float(np.mean(z[len(z) // 2 :]))])
    k = _swing_stiffness(scene, rest, swing, 2 * math.pi / measured, scene.step.dt)
    k_static = surge_stiffness(lines_of(scene.moorings), rest, RHO, G)
    c = sim.model.radiation.coefficients
    predicted, quasi_static = _surge_period(sim.body.mass, c, k), _surge_period(sim.body.mass, c, k_static)
    print(
        f"surge period: measured {measured:.3f} s at {swing:.3f} m; the lines' stiffness there {k:.2f} N/m: {predicted:.3f} s "
        f"({measured / predicted - 1:+.2%}); the catenary's {k_static:.2f} N/m: {quasi_static:.3f} s ({measured / quasi_static - 1:+.2%})"
    )
    assert measured == pytest.approx(predicted, rel=0.005), (measured, predicted)
    assert measured == pytest.approx(quasi_static, rel=0.01), (measured, quasi_static)


def test_compiled_and_reference_agree_with_the_lines_pulling():
    """The same moored run (lines, waves, radiation, diffraction) on the kernels and on numpy: the pull is held
    over each step in both, so their trajectories meet to round-off."""
    scene = with_overrides(load_scene("moored-buoy"), initial__position=(0.3, 0.1, -0.35))
    runs = []
    for backend in ("numba", "numpy"):
        sim = Simulation(scene, backend=backend)
        sim.step(200)
        f = sim.frame()
        runs.append(np.concatenate([sim.state.x_world, sim.state.q_world_body, sim.state.u_world, f.fairlead_tensions]))
        assert np.abs(f.mooring_force).max() > 10.0  # the lines pull
    np.testing.assert_allclose(runs[0], runs[1], rtol=1e-9, atol=1e-9)


def test_the_frame_carries_the_lines_and_the_pull_is_in_the_force():
    sim = Simulation(load_scene("moored-buoy"), backend="numpy")
    f = sim.frame()
    spread = lines_of(sim.scene.moorings)
    assert len(f.lines) == 3 and all(line.shape == (spread.segments + 1, 3) for line in f.lines)
    for line, heading in zip(f.lines, spread.headings()):
        anchor = spread.anchor_radius * np.array([math.cos(heading), math.sin(heading)])
        np.testing.assert_allclose(line[0], [*anchor, -spread.anchor_depth], atol=1e-9)  # anchor end first, on the seabed
        assert line[:, 2].min() >= -spread.anchor_depth - 0.01  # the seabed holds it (its contact is a stiff spring)
    unmoored = Simulation(with_overrides(load_scene("moored-buoy"), moorings__lines=0), backend="numpy").frame()
    np.testing.assert_allclose(f.force_world - unmoored.force_world, f.mooring_force, atol=1e-9)


def test_a_moordyn_file_gives_the_same_lines_as_the_spread(tmp_path):
    """[moorings] line_file: the spread's own MoorDyn input, written out, gives the same pull (the lines alone: no BEM
    solve for a grid of their own)."""
    scene = with_overrides(load_scene("moored-buoy"), fluid__radiation="none")
    spread = lines_of(scene.moorings)
    path = tmp_path / "lines.txt"
    path.write_text(spread.input_file(np.array(scene.initial.position), np.eye(3), RHO, G, scene.step.dt))
    a = Simulation(scene, backend="numpy").frame()
    b = Simulation(with_overrides(scene, moorings__lines=0, moorings__line_file=str(path)), backend="numpy").frame()
    np.testing.assert_allclose(a.mooring_force, b.mooring_force, rtol=1e-9, atol=1e-6)


@pytest.mark.parametrize(
    "args, message",
    [
        (("--line-file", "nowhere.txt"), "mooring file not found: nowhere.txt"),
        (("--line-length", "5"), "the mooring lines cannot reach"),
        (("--segments", "0"), "segments must be >= 1"),
    ],
)
def test_mistakes_are_one_line_and_exit_2(tmp_path, args, message):
    done, _ = run_cli(tmp_path, "--scene", "moored-buoy", "--t-end", "0.1", *args)
    assert done.returncode == 2 and message in done.stderr and "Traceback" not in done.stderr, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1


def test_without_moordyn_the_error_says_how_to_get_it(tmp_path):
    code = "import sys; sys.modules['moordyn'] = None; from sim.commands import floatsim; sys.exit(floatsim(['run', '--scene', 'moored-buoy']))"
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 2 and "pip install -e '.[moorings]'" in done.stderr and "Traceback" not in done.stderr, done.stderr


def test_a_config_error_for_lines_that_cannot_reach():
    with pytest.raises(ConfigError, match="cannot reach"):
        Simulation(with_overrides(load_scene("moored-buoy"), moorings__line_length=5.0), backend="numpy")


def test_a_recording_draws_the_lines_where_the_run_had_them():
    """The replay page (the viewer's scene in a recording) carries the mooring lines: the last update of its
    /moorings node is the last frame's lines, segment by segment."""
    import base64

    import msgspec
    import zstandard

    from app.recording.replay import replay_html
    from app.recording.take import Take, shot_of

    sim = Simulation(load_scene("moored-buoy"))
    take = Take()
    take.add(shot_of(sim))
    while sim.state.t < 1.0:
        sim.step(7)
        take.add(shot_of(sim))
    raw = base64.b64decode(re.search(r'window.__VISER_EMBED_DATA__="([^"]+)"', replay_html(take)).group(1))
    inner = zstandard.ZstdDecompressor().decompress(raw[8:], max_output_size=int.from_bytes(raw[:8], "little"))
    n = int.from_bytes(inner[:8], "little")
    doc = msgspec.msgpack.decode(inner[8 : 8 + n])
    sizes, starts, at = doc["binaryBufferLengths"], [], 8 + n
    for size in sizes:  # the arrays follow the messages, each at an offset that is a multiple of 8 (viser's framing)
        at += -at % 8
        starts.append(at)
        at += size
    assert at == len(inner)
    updates = [
        m[1]["updates"]["points"]
        for m in doc["messages"]
        if m[1].get("name") == "/world/moorings" and m[1]["type"] == "SceneNodeUpdateMessage" and "points" in m[1]["updates"]
    ]  # (the lines' colours follow their tension in updates of their own)
    assert len(updates) >= 10  # streamed as the run goes (15 a second at most)
    i = updates[-1]["__binary_index"]
    last = np.frombuffer(inner[starts[i] : starts[i] + sizes[i]], dtype=np.float32).reshape(-1, 2, 3)
    shown = [np.concatenate([np.stack([p[:-1], p[1:]], axis=1) for p in take[k].frame.lines]) for k in range(len(take))]
    gaps = [np.abs(last - lines).max() for lines in shown]
    assert min(gaps) < 1e-5 and np.argmin(gaps) >= len(take) - 3, gaps  # one of the last shots (the drawing is throttled)
    assert max(gaps) > 1e-3  # the lines moved during the run


def test_anchors_and_fairleads_given_point_by_point_are_the_spread_they_describe(tmp_path):
    """[moorings] anchors and fairleads (a scene file's lists) in place of the spread's parameters: the same
    three lines pull the same; a count that does not match, or an anchor under the seabed, is one line and exit 2."""
    from sim.lines.moorings import LineSet

    base = load_scene("moored-buoy")
    lines = lines_of(base.moorings)
    ends = lines.ends(np.zeros(3), np.eye(3))
    anchors = [[float(v) for v in a] for a, _ in ends]
    fairleads = [[float(v) for v in f] for _, f in ends]
    text = (ROOT / "assets/scenes/moored-buoy.toml").read_text().replace("lines = 3\n", f"anchors = {anchors}\nfairleads = {fairleads}\n")
    text = text.replace('radiation = "bem"', 'radiation = "none"')  # the lines alone: no BEM solve of a grid of their own
    base = with_overrides(base, fluid__radiation="none")
    scene_file = tmp_path / "points.toml"
    scene_file.write_text(text)
    given = load_scene(str(scene_file))
    assert given.moorings.lines == 0 and isinstance(lines_of(given.moorings), LineSet)
    a = Simulation(base, backend="numpy").frame()
    b = Simulation(given, backend="numpy").frame()
    np.testing.assert_allclose(b.mooring_force, a.mooring_force, rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(b.fairlead_tensions, a.fairlead_tensions, rtol=1e-9)
    scene_file.write_text(text.replace(f"fairleads = {fairleads}", f"fairleads = {fairleads[:2]}"))
    done, _ = run_cli(tmp_path, "--scene", str(scene_file), "--t-end", "0.1")
    assert done.returncode == 2 and "3 anchors and 2 fairleads" in done.stderr, done.stderr
    deep = [[*anchors[0][:2], -12.0], *anchors[1:]]
    scene_file.write_text(text.replace(f"anchors = {anchors}", f"anchors = {deep}"))
    done, _ = run_cli(tmp_path, "--scene", str(scene_file), "--t-end", "0.1")
    assert done.returncode == 2 and "below the seabed" in done.stderr and "Traceback" not in done.stderr, done.stderr


@pytest.mark.parametrize(
    "given, step",
    [({"line_stiffness": 1e13}, "2.04e-07 s"), ({"line_mass": 1e-9}, "6.44e-08 s"), ({"segments": 500, "lines": 8}, "8.13e-05 s")],
)
def test_lines_whose_moordyn_start_up_would_take_too_long_are_refused_before_it(tmp_path, given, step):
    """Issue 37: values inside the accepted ranges used to sit in MoorDyn's start-up for hours (1.8e9 steps of 1.1e-7 s).
    Now one line, exit 2, at once: the step they need, the time it would take, what to change; the value it
    suggests passes the same rule (and the preset as shipped does)."""
    import re
    import time

    from sim.lines.moorings import check_start

    flags = [a for k, v in given.items() for a in (f"--{k.replace('_', '-')}", f"{v:g}")]
    started = time.monotonic()
    done, _ = run_cli(tmp_path, "--scene", "moored-buoy", "--t-end", "0.1", *flags)
    assert done.returncode == 2 and "Traceback" not in done.stderr and len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert (
        f"MoorDyn steps of {step}" in done.stderr and "start-up could take up to" in done.stderr and "over the 120 s allowed" in done.stderr
    )
    assert time.monotonic() - started < 30.0  # refused before MoorDyn, not after
    key, value = re.search(r"(line_stiffness|line_mass) (?:to |\()([0-9.e+-]+) (?:N|kg/m)", done.stderr).groups()
    scene = load_scene("moored-buoy")
    overrides = {f"moorings__{k}": v for k, v in given.items()}
    with pytest.raises(ConfigError, match=f"MoorDyn steps of {step}"):
        with_overrides(scene, **overrides)
    check_start(lines_of(with_overrides(scene, **{**overrides, f"moorings__{key}": float(value)}).moorings), RHO)  # passes
    check_start(lines_of(scene.moorings), RHO)


def test_ctrl_c_stops_moordyns_start_up_at_once(tmp_path):
    """MoorDyn's start-up is one C call that Python cannot interrupt: it runs in a forked child, which Ctrl-C ends.
    Stiffer lines (EA 1e8: steps of 3.5e-5 s, a start-up of several seconds, under the 120 s budget) stopped
    in the middle of it: out within 2 s, exit 130, one line, and the child gone with it."""
    import signal
    import time

    proc = subprocess.Popen([sys.executable, "-m", "sim", "run", "--scene", "moored-buoy", "--line-stiffness", "1e8", "--t-end", "1"],
                            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip
    children = Path(f"/proc/{proc.pid}/task/{proc.pid}/children")
    deadline = time.monotonic() + 120
    while proc.poll() is None and not children.read_text().split() and time.monotonic() < deadline:
        time.sleep(0.02)  # until the start-up's child exists
    assert proc.poll() is None, proc.communicate()
    child = children.read_text().split()[0]
    time.sleep(0.5)
    proc.send_signal(signal.SIGINT)
    sent = time.monotonic()
    _, err = proc.communicate(timeout=60)
    stopped_in = time.monotonic() - sent
    print(f"stopped {stopped_in:.2f} s after Ctrl-C")
    assert proc.returncode == 130 and stopped_in < 2.0, (proc.returncode, stopped_in, err)
    assert "Traceback" not in err and err.count("\n") == 1 and "interrupted (Ctrl-C)" in err, err
    assert not Path(f"/proc/{child}").exists()


def test_a_moordyn_file_is_held_to_the_same_rules(tmp_path):
    """[moorings] line_file: its dtM and TmaxIC against the start-up budget, its Fixed points (anchors) in the water."""
    scene = load_scene("moored-buoy")
    text = lines_of(scene.moorings).input_file(np.array(scene.initial.position), np.eye(3), RHO, G)
    path = tmp_path / "lines.txt"
    path.write_text(re.sub(r"(?m)^\S+ dtM$", "1e-7 dtM", text))
    done, _ = run_cli(tmp_path, "--scene", "moored-buoy", "--lines", "0", "--line-file", str(path), "--t-end", "0.1", "--radiation", "none")
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1 and "dtM = 1e-07 s over 60 segments" in done.stderr, (
        done.stderr
    )
    anchor = text.splitlines()[text.splitlines().index("(#) (-) (m) (m) (m) (kg) (m^3) (m^2) (-)") + 1]
    path.write_text(text.replace(anchor, anchor.replace(" -10 0 0 0 0", " 2 0 0 0 0")))
    done, _ = run_cli(tmp_path, "--scene", "moored-buoy", "--lines", "0", "--line-file", str(path), "--t-end", "0.1", "--radiation", "none")
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1 and "2 m above the water" in done.stderr, done.stderr


def test_anchors_above_the_water_are_refused(tmp_path):
    """MoorDyn takes a line as submerged all along, so an anchor above z = 0 would hang in water that is not there:
    one line, exit 2; on the surface it is still in the water."""
    base = load_scene("moored-buoy")
    ends = lines_of(base.moorings).ends(np.zeros(3), np.eye(3))
    fairleads = [[float(v) for v in f] for _, f in ends]
    scene_file = tmp_path / "airborne.toml"
    for z in (0.5, 0.0):
        anchors = [[float(v) for v in a] for a, _ in ends]
        anchors[1][2] = z
        text = (ROOT / "assets/scenes/moored-buoy.toml").read_text()
        scene_file.write_text(text.replace("lines = 3\n", f"anchors = {anchors}\nfairleads = {fairleads}\n"))
        if z > 0:
            done, _ = run_cli(tmp_path, "--scene", str(scene_file), "--t-end", "0.1")
            assert done.returncode == 2 and "Traceback" not in done.stderr and len(done.stderr.strip().splitlines()) == 1, done.stderr
            assert "[moorings] anchor 2 is at z = 0.5 m, above the water" in done.stderr
        else:
            assert load_scene(str(scene_file)).moorings.anchors[1][2] == 0.0


def test_the_start_up_in_a_child_leaves_moordyn_as_the_start_up_here_would(monkeypatch):
    """The forked start-up hands its state back through MoorDyn's Serialize: the same pull and the same next 50
    steps, to the bit, as MoorDyn's Init in this process (where there is no fork)."""
    import os

    from sim.lines.moorings import Moorings

    scene = load_scene("moored-buoy")
    x0 = np.array(scene.initial.position)
    text = lines_of(scene.moorings).input_file(x0, np.eye(3), RHO, G)
    runs = []
    for fork in (True, False):
        if not fork:
            monkeypatch.delattr(os, "fork")
        with Moorings(text, x0, np.eye(3), np.zeros(3), np.zeros(3)) as lines:
            pulls = [lines.load.copy()]
            for k in range(50):
                pulls.append(lines.advance(x0 + [0.002 * k, 0.0, 0.001 * k], np.eye(3), np.array([0.2, 0.0, 0.1]), np.zeros(3), 0.01))
            runs.append(np.array(pulls))
    assert np.abs(runs[0][0]).max() > 100.0 and np.ptp(runs[0][:, 0]) > 1.0  # the lines pull, and the pull changes
    np.testing.assert_array_equal(runs[0], runs[1])


def test_a_moordyn_file_whose_step_is_too_long_for_its_lines_stops_in_one_line(tmp_path):
    """A light line (10 g/m, EA 3 MN, one line of 10 segments) stepped at 1.02e-4 s, the old rule's step (it counted the
    water around the line as moving along it, where MoorDyn's CaAx = 0): MoorDyn found NaN in its nodes and the run
    ended in a RuntimeError's traceback. Such a file now stops as a divergence in one line, exit 3; floatsim's own
    rule (7.4e-5 s: 0.46 of an axial wave's crossing of a segment, the line's own mass) runs the same line."""
    import dataclasses

    scene = load_scene("moored-buoy")
    light = dataclasses.replace(lines_of(scene.moorings), lines=1, segments=10, line_mass=0.01, line_stiffness=3e6)
    text = light.input_file(np.array(scene.initial.position), np.eye(3), RHO, G)
    path = tmp_path / "light.txt"
    path.write_text(re.sub(r"(?m)^\S+ dtM$", "1.02e-4 dtM", text))
    still = ("--radiation", "none", "--waves", "still", "--t-end", "0.5")
    done, _ = run_cli(tmp_path, "--scene", "moored-buoy", "--lines", "0", "--line-file", str(path), *still)
    assert done.returncode == 3 and "Traceback" not in done.stderr, done.stderr
    said = [line for line in done.stderr.splitlines() if "note:" not in line]
    assert len(said) == 1 and "the mooring lines (MoorDyn) diverged at t = " in said[0], done.stderr
    assert light.sub_step(RHO) == pytest.approx(7.44e-5, rel=1e-3)
    flags = ("--lines", "1", "--segments", "10", "--line-mass", "0.01", "--line-stiffness", "3e6")
    done, rows = run_cli(tmp_path, "--scene", "moored-buoy", *flags, *still)
    assert done.returncode == 0 and np.isfinite(rows["T_fair_max"]).all() and rows["T_fair_max"].max() > 1.0, done.stderr


def test_a_moordyn_file_holds_the_body_as_stiffly_as_the_spread_it_writes(tmp_path):
    """The rest pose's horizontal stiffness from a MoorDyn file (the lines settled with the body held off its start,
    their fairleads moved with it) is the spread's elastic catenaries' within MoorDyn's discretisation (12 % here), so a
    BEM solve's grid reaches down past the same surge frequency (to the quarter octave) whichever way the lines are given."""
    import math

    from sim.hydro.equilibrium import pull_stiffness
    from sim.hydro.radiation import lowest_frequency

    scene = with_overrides(load_scene("moored-buoy"), fluid__radiation="none")
    path = tmp_path / "lines.txt"
    path.write_text(lines_of(scene.moorings).input_file(np.array(scene.initial.position), np.eye(3), RHO, G, scene.step.dt))
    given = with_overrides(scene, moorings__lines=0, moorings__line_file=str(path))
    at = np.array([*scene.initial.position[:2], -0.44])
    spread, file = (pull_stiffness(s, at, np.eye(3)) for s in (scene, given))
    assert spread[0, 0] > 10.0 and abs(file[0, 0] / spread[0, 0] - 1) < 0.12 and abs(file[1, 1] / spread[1, 1] - 1) < 0.12
    mass = 900.0  # the buoy's (1 m cube, 900 kg/m^3)
    lows = [lowest_frequency(s, mass, at, np.eye(3)) for s in (scene, given)]
    assert None not in lows and abs(math.log2(lows[1] / lows[0])) <= 0.25, lows


def _as_coupled_body(text: str, place, angles_deg) -> str:
    """A MoorDyn file's Coupled points hung instead on a MoorDyn body of type Coupled at `place`, turned by `angles_deg`
    (roll, pitch, yaw): each point given relative to the body, as WEC-Sim's and OpenFAST's files give fairleads."""
    from sim.lines.moordyn_input import _rotation

    place = np.asarray(place, float)
    R = _rotation(*np.radians(angles_deg))

    def relative(m):
        p = R.T @ (np.array([float(m[2]), float(m[3]), float(m[4])]) - place)
        return f"{m[1]} Body1 {float(p[0])!r} {float(p[1])!r} {float(p[2])!r} "

    text = re.sub(r"^(\d+) Coupled (\S+) (\S+) (\S+) ", relative, text, flags=re.M)
    body = "1 Coupled " + " ".join(repr(float(v)) for v in (*place, *angles_deg)) + " 0 0 0 0 0 0"
    return text.replace("---------------------- POINTS", "---------------------- BODIES ----------------------\nID Attachment X0 Y0 Z0 r0 p0 y0 "
                        f"Mass CG I Volume CdA Ca\n(#) (-) (m) (m) (m) (deg) (deg) (deg) (kg) (m) (kg-m^2) (m^3) (m^2) (-)\n{body}\n"
                        "---------------------- POINTS", 1)  # fmt: skip


@pytest.mark.slow
def test_fairleads_on_a_coupled_moordyn_body_move_with_the_body(tmp_path):
    """rm3-wecsim-moorings with its fairleads hung on a MoorDyn body of type Coupled (turned 5 deg in roll and 30 in
    yaw, the points given in its frame) runs as the same fairleads given as Coupled points: the same rows to 1e-9
    (the body's points are placed once, at the start, to round-off). A Coupled body with a mass of its own is refused
    in one line."""
    moorings = ROOT / "assets" / "moorings"
    points_form = (moorings / "rm3_wecsim.txt").read_text()
    (tmp_path / "body.txt").write_text(_as_coupled_body(points_form, (0.0, 0.0, -21.5), (5.0, 0.0, 30.0)))
    scene = (ROOT / "assets" / "scenes" / "rm3-wecsim-moorings.toml").read_text().replace('"../', f'"{ROOT / "assets"}/')
    rows = {}
    for form, lines in (("points", moorings / "rm3_wecsim.txt"), ("body", tmp_path / "body.txt")):
        path = tmp_path / f"{form}.toml"
        path.write_text(scene.replace(f'line_file = "{moorings}/rm3_wecsim.txt"', f'line_file = "{lines}"'))
        out = tmp_path / f"{form}.csv"
        done = subprocess.run([sys.executable, "-m", "sim", "run", "--scene", str(path), "--t-end", "1", "--every", "10", "--out", str(out)],
                              capture_output=True, text=True, timeout=300)  # fmt: skip
        assert done.returncode == 0, done.stderr[-2000:]
        rows[form] = np.genfromtxt(out, delimiter=",", names=True)
    assert rows["points"]["T_fair_max"].max() > 5e4  # the chains pull
    for name in rows["points"].dtype.names:
        np.testing.assert_allclose(rows["body"][name], rows["points"][name], rtol=1e-9, atol=1e-9 * (1 + abs(rows["points"][name]).max()))
    heavy = _as_coupled_body(points_form, (0.0, 0.0, -21.5), (0.0, 0.0, 0.0)).replace(
        "1 Coupled 0.0 0.0 -21.5 0.0 0.0 0.0 0 ", "1 Coupled 0.0 0.0 -21.5 0.0 0.0 0.0 5000 "
    )
    (tmp_path / "body.txt").write_text(heavy)
    done = subprocess.run([sys.executable, "-m", "sim", "run", "--scene", str(tmp_path / "body.toml"), "--t-end", "0.1"], capture_output=True,
                          text=True, timeout=300)  # fmt: skip
    assert done.returncode == 2 and "Coupled with its own mass" in done.stderr and len(done.stderr.strip().splitlines()) == 1, done.stderr


def test_a_line_file_that_is_not_moordyn_input_is_refused_before_any_solve(tmp_path):
    """moored-buoy with its lines from a file that is not MoorDyn input: without its spread the buoy rests elsewhere, its
    shipped BEM solve no longer matches and a Capytaine solve would start (2 min 55 s here before the file was refused);
    the file is read first and refused in one line, in seconds."""
    text = (ROOT / "assets" / "scenes" / "moored-buoy.toml").read_text()
    start, end = text.index("\n[moorings]\n"), text.index("\n[initial]\n")
    (tmp_path / "notes.txt").write_text("my notes\nnot a mooring file\n")
    (tmp_path / "buoy.toml").write_text(text[:start] + '\n[moorings]\nline_file = "notes.txt"\n' + text[end:])
    started = time.monotonic()
    done = subprocess.run([sys.executable, "-m", "sim", "run", "--scene", str(tmp_path / "buoy.toml"), "--t-end", "1"], cwd=ROOT,
                          capture_output=True, text=True, timeout=120)  # fmt: skip
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert "notes.txt: not a MoorDyn input file" in done.stderr and time.monotonic() - started < 60.0
