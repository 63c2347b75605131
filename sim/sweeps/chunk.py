"""One chunk of a sweep (sim/grid.py): its cases advanced together in one ensemble to the end or,
with `settle`, each until it is at rest; then a row of results per case, as plain columns.

A case that ends wholly under water and heavier than the water it displaces has status 'sank' and no draft or
period (NaN): it is falling, not floating. At rest means: at two checks one simulated second apart, |u| and |omega| x radius below 1e-3 sqrt(g L)
and the net force and torque below 1e-3 of the weight (and weight x radius). A case's numbers depend
on itself alone (each body steps on its own in the compiled ensemble), so chunks can run anywhere.
"""

from __future__ import annotations

import math

import numpy as np

from sim.bodies.rotation import quat_to_matrix
from sim.ensemble import Ensemble
from sim.errors import SimulationDiverged
from sim.simulation import Simulation

from .grid import Sweep, case_scene

SAMPLE = 0.1
"""Seconds between the samples of z a case's period is measured from."""
CHECK = 1.0
"""Seconds between rest checks."""
REST = 1e-3
SUMMARY = ("status", "t", "time_to_rest", "x", "y", "z", "qw", "qx", "qy", "qz", "speed", "spin", "E_total", "E_pto", "tilt_deg", "draft",
           "period")  # fmt: skip
HISTORY = ("case", "t", "x", "y", "z", "qw", "qx", "qy", "qz")


def at_rest(sim) -> bool:
    f, body = sim.frame(), sim.body
    g = sim.params.g or 9.81
    scale = math.sqrt(g * 2 * body.radius)
    weight = body.mass * g
    return bool(np.linalg.norm(f.u_world) < REST * scale and np.linalg.norm(f.omega_world) * body.radius < REST * scale
                and np.linalg.norm(f.force_world) < REST * weight and np.linalg.norm(f.torque_world) < REST * weight * body.radius)  # fmt: skip


def sinks(sim) -> bool:
    """The body weighs more than the water it displaces wholly under (it cannot float: no draft, no period of heave)."""
    return sim.body.mass > sim.params.rho * sim.body.volume


def nearest_face_tilt(body, q: np.ndarray) -> float:
    """Angle from vertical of the body's face normal nearest to it (0: a face lies flat on top), degrees."""
    up = (body.face_normals @ quat_to_matrix(q).T)[:, 2]
    return math.degrees(math.acos(min(1.0, float(up.max()))))


def period(t: np.ndarray, z: np.ndarray) -> float:
    """Mean time between upward crossings of z's final value (nan with fewer than two)."""
    y = z - z[-1]
    i = np.flatnonzero((y[:-1] < 0) & (y[1:] >= 0))
    if len(i) < 2:
        return math.nan
    crossings = t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i])
    return float(np.mean(np.diff(crossings)))


def run_chunk(sweep: Sweep, indices: list[int], stop=None) -> tuple[dict, dict | None]:
    """Results (one row per case) and, if asked, histories of the cases `indices`, as column dicts.
    `stop` (interrupt.StopOnCtrlC) is checked every block: once asked, Interrupted is raised."""
    base = sweep.base()
    if base.bodies:
        return run_system_chunk(sweep, indices, stop), None
    cases = {i: sweep.case(i) for i in indices}
    scenes = [case_scene(base, cases[i]) for i in indices]
    ensemble = Ensemble(scenes)
    dt = ensemble.dt
    n_steps = round(base.step.t_end / dt)
    sample = max(1, round(SAMPLE / dt))
    check = max(1, round(CHECK / dt))
    block = math.gcd(sample, check)  # every sample, rest check and history row falls on a block's end
    if sweep.history_every:
        block = math.gcd(block, sweep.history_every)
    n = len(indices)
    samples_t, samples_z = [0.0], [[s.body_state.x_world[2] for s in ensemble.sims]]
    rest_time = [math.nan] * n
    candidate = [math.nan] * n  # time of the first of two checks at rest
    history = {k: [] for k in HISTORY} if sweep.history_every else None

    def keep_history(done: int) -> None:
        for j, s in enumerate(ensemble.sims):
            if ensemble.stopped[j] and done > 0:
                continue
            st = s.body_state
            for k, v in zip(HISTORY, (indices[j], st.t, *st.x_world, *st.q_world_body)):
                history[k].append(v)

    if history is not None:
        keep_history(0)
    done = 0
    while done < n_steps and not all(ensemble.stopped[j] or ensemble.diverged[j] for j in range(n)):
        k = min(block - done % block, n_steps - done)
        ensemble.step(k, check_energy=(done + k) % check == 0 or done + k == n_steps)  # the blow-up check once a second
        done += k
        if stop is not None:
            stop.check()
        if done % sample == 0 or done == n_steps:
            samples_t.append(done * dt)
            samples_z.append([s.body_state.x_world[2] for s in ensemble.sims])
        if history is not None and done % sweep.history_every == 0:
            keep_history(done)
        if sweep.settle and done % check == 0:
            for j, s in enumerate(ensemble.sims):
                if ensemble.stopped[j] or ensemble.diverged[j]:
                    continue
                if at_rest(s):
                    if math.isnan(candidate[j]):
                        candidate[j] = s.body_state.t
                    else:
                        rest_time[j] = candidate[j]
                        ensemble.stopped[j] = True
                else:
                    candidate[j] = math.nan
    t_samples, z_samples = np.array(samples_t), np.array(samples_z)
    rows: dict = {"case": list(indices)}
    for name, _ in sweep.params:
        rows[name] = [cases[i][name] for i in indices]
    for key in SUMMARY:
        rows[key] = []
    for j, s in enumerate(ensemble.sims):
        f = s.frame()
        upto = t_samples <= f.t + 1e-9
        vertices = s.body.mesh_vertices @ quat_to_matrix(f.q_world_body).T + f.x_world
        sank = sinks(s) and float(vertices[:, 2].max()) < f.eta  # heavier than the water it displaces, and all of it under
        status = "diverged" if ensemble.diverged[j] else ("rest" if ensemble.stopped[j] else "sank" if sank else "end")
        values = (status, f.t, rest_time[j], *f.x_world, *f.q_world_body, float(np.linalg.norm(f.u_world)), float(np.linalg.norm(f.omega_world)),
                  f.E_total, f.E_pto, nearest_face_tilt(s.body, f.q_world_body), math.nan if sank else -float(vertices[:, 2].min()),
                  math.nan if sank else period(t_samples[upto], z_samples[upto, j]))  # fmt: skip
        for key, v in zip(SUMMARY, values):
            rows[key].append(v)
    return rows, history


def run_system_chunk(sweep: Sweep, indices: list[int], stop=None) -> dict:
    """A scene of several bodies, case after case: each run to t_end; per joint, the take-off's mean power and the
    coordinate's amplitude (half its range) over the run's second half (the start's transient left out), and the
    energy every take-off absorbed (`E_pto`). A case that diverges gets status 'diverged' and NaNs."""

    base = sweep.base()
    rows: dict = {"case": list(indices)}
    for name, _ in sweep.params:
        rows[name] = [sweep.case(i)[name] for i in indices]
    for key in ("status", "t", "E_pto"):
        rows[key] = []
    for i in indices:
        run = Simulation(case_scene(base, sweep.case(i)))
        joints = run.system.joints
        n_steps = round(run.scene.step.t_end / run.dt)
        sample = max(1, round(SAMPLE / run.dt))
        status, coordinates, halfway = "end", [], None
        try:
            done = 0
            while done < n_steps:
                run.step(min(sample, n_steps - done))
                done = min(done + sample, n_steps)
                if stop is not None:
                    stop.check()
                if halfway is None and 2 * done >= n_steps:
                    halfway = (run.state.t, run.state.absorbed.copy())
                if halfway is not None:
                    coordinates.append(run.state.theta.copy())
        except SimulationDiverged:
            status = "diverged"
        finally:
            run.close()
        s = run.state
        rows["status"].append(status)
        rows["t"].append(s.t)
        rows["E_pto"].append(float(s.absorbed.sum()))
        spread = np.ptp(np.array(coordinates), axis=0) if len(coordinates) > 1 and status == "end" else None
        for g in joints:
            power = (
                (s.absorbed[g.coordinate] - halfway[1][g.coordinate]) / (s.t - halfway[0])
                if spread is not None and s.t > halfway[0]
                else math.nan
            )
            rows.setdefault(f"{g.name}_power", []).append(float(power))
            rows.setdefault(f"{g.name}_amplitude", []).append(float(0.5 * spread[g.coordinate]) if spread is not None else math.nan)
    return rows
