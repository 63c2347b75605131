"""Part 8 of the accuracy report: radiation that cannot create energy (the radiation memory's passivity, issue 38).

For every shipped BEM solve (sim.hydro.bem.SHIPPED), its memory as the scenes fit it (sim.hydro.radiation.fit_memory): the
smallest eigenvalue of the fitted damping B_fit(omega) (the Hermitian part of K_fit(i omega), Re K for a reciprocal
fit) on a dense grid from 0 to 10x the solve's top frequency, against the solve's peak damping; the fit's misfits of
B and A against each entry's own peak; its states. In time: rm3 without its take-off's damper, the float kicked
upwards at 0.5 m/s in still water, linear hydro stepped exactly (sim.system.linear.exact_linear): the mechanical
energy, E_total + E_pto + E_rad, and the largest real part of the linear system's eigenvalues.

The helpers are also `python -m studies.passivity`'s and tests/hydro/test_passivity.py's. They use only what the fit
before issue 38's passive one had too (fit_memory, response, exact_linear), so the study can be run against an
older checkout.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

KICK = 0.5
"""The float's upward kick in still_rm3, m/s."""
ROUND_OFF = 1e-12
"""The passivity check's bound: min eig B_fit >= -ROUND_OFF x the peak damping."""
OLD_FIT = {"commit": "658f3a1^", "eig": 0.0046, "energy": 2.6e16, "horizon": 3000.0}
"""What the fit before issue 38's passive one did (rm3 without a damper, linear hydro, the kick of this part):
`python -m studies.passivity` run against the parent of commit 658f3a1 (the old fit's code is not in this tree)."""


@dataclass(frozen=True)
class PassivitySettings:
    horizon: float = 3000.0
    """rm3's run, s (0: no rm3 run)."""
    every: float = 1.0
    """Its sampling, s (the exact stepper takes 0.1 s steps between samples)."""
    points: int = 20000
    """Frequencies of each of the two grids (linear and logarithmic) the damping's eigenvalues are taken on."""

    def jobs(self) -> int:
        return len(list(_shipped())) + (1 if self.horizon > 0 else 0)


FULL_PASSIVITY = PassivitySettings()
QUICK_PASSIVITY = PassivitySettings(horizon=300.0, every=2.0, points=5000)


@dataclass
class SolveFit:
    name: str
    """The shipped file's stem (its key)."""
    bodies: int
    frequencies: int
    omega_top: float
    peak: float
    """The largest |B| of the solve, any entry and frequency."""
    states: int
    misfit_B: float
    misfit_A: float
    omega_low: float
    """The solve's lowest frequency."""
    dofs: int
    """How many dofs radiate (the fit's block; the others' B_fit is zero)."""
    omega: np.ndarray
    low: np.ndarray
    """The smallest eigenvalue of B_fit over the radiating dofs at each omega (N s/m and the like)."""

    @property
    def lowest(self) -> float:
        """min over omega of the smallest eigenvalue, against the peak damping."""
        return float(self.low.min() / self.peak)

    @property
    def where(self) -> float:
        return float(self.omega[self.low.argmin()])


@dataclass
class KickedRm3:
    t: np.ndarray
    energy: np.ndarray
    """E_total - its start, J (mechanical: kinetic, gravity, hydrostatic, springs)."""
    balance: np.ndarray
    """E_total + E_pto + E_rad - the start, J."""
    kick: float
    """The kinetic energy of the kick, J."""
    eig_max: float
    """The largest real part of an eigenvalue of the linear system, 1/s."""
    E_rad: float

    @property
    def rise(self) -> float:
        """The most the mechanical energy ever stood above its start after it, J (negative: never above)."""
        return float(self.energy[1:].max())

    @property
    def gap(self) -> float:
        return float(np.abs(self.balance).max())


@dataclass
class Passivity:
    settings: PassivitySettings
    solves: list[SolveFit] = field(default_factory=list)
    rm3: KickedRm3 | None = None


# ---- shared with studies/passivity.py and tests/hydro/test_passivity.py ----------------------------------


def damping_floor(memory, omega_top: float, points: int = 20000, dofs=None) -> tuple[np.ndarray, np.ndarray]:
    """(omega, the smallest eigenvalue of the Hermitian part of K_fit(i omega) there) on 2 x `points` frequencies from 0
    to 10 omega_top, linear and logarithmic (Re K for a reciprocal fit: B_fit(omega)); `dofs`: of that block only (the
    radiating ones: the others' rows and columns are zero, so the whole matrix's is min(0, the block's))."""
    w = np.unique(np.concatenate([np.linspace(1e-4, 10 * omega_top, points), np.geomspace(1e-4 * omega_top, 10 * omega_top, points)]))
    K = memory.response(w)
    if dofs is not None:
        K = K[:, dofs][:, :, dofs]
    return w, np.linalg.eigvalsh(0.5 * (K + np.conj(K.transpose(0, 2, 1))))[:, 0]


def lowest_damping(memory, omega_top: float, points: int = 20000) -> tuple[float, float]:
    """(min over omega of the smallest eigenvalue of B_fit(omega), where) on damping_floor's grid."""
    w, low = damping_floor(memory, omega_top, points)
    return float(low.min()), float(w[low.argmin()])


def radiating(memory) -> list[int]:
    """The dofs the fit has entries in."""
    return sorted({e.row for e in memory.entries})


def misfits(memory, c) -> tuple[float, float]:
    """The largest B and A misfits on the grid over the fitted entries that matter (peak over 5 % of the diagonals'
    geometric mean), each against the entry's own peak (the symmetric part of the solve's), the model's A being its
    A_inf plus Im K_fit / omega: the same measure for any fit."""
    dofs = radiating(memory)
    K = memory.response(c.omega)
    B, A = 0.5 * (c.damping + c.damping.transpose(0, 2, 1)), 0.5 * (c.added_mass + c.added_mass.transpose(0, 2, 1))
    A_fit = memory.added_mass_inf + K.imag / c.omega[:, None, None]
    peak = np.abs(B).max(axis=0)
    worst = [0.0, 0.0]
    for i in dofs:
        for j in dofs:
            if peak[i, j] > 0.05 * np.sqrt(peak[i, i] * peak[j, j]):
                worst[0] = max(worst[0], np.abs(K[:, i, j].real - B[:, i, j]).max() / peak[i, j])
                worst[1] = max(worst[1], np.abs(A_fit[:, i, j] - A[:, i, j]).max() / np.abs(A[:, i, j]).max())
    return float(worst[0]), float(worst[1])


MISFITS = {"85f92b9aecb0610382e7": ("two point absorbers 3 m apart, assets/scenes/farms/pair_3m.toml", 0.5 * 3**0.5)}
"""Shipped solves whose fit misses its tolerance, by key: (what they are, the body radius their scene fits with). A
farm's cross terms oscillate with frequency (docs/farms.md); its fit stays passive and stable, and a run says it misses."""


def scene_length(c, name: str = "") -> float:
    """The body size the scenes fit with: 1 m for one body (make_radiation's), the largest body radius for several (rm3's
    two bodies, the F3OF platform's three)."""
    if name in MISFITS:
        return MISFITS[name][1]
    bodies = c.damping.shape[1] // 6
    if bodies == 1:
        return 1.0
    from sim.bodies.body import make_body
    from sim.scene.config import SCENES_DIR, load_scene

    scene = load_scene({2: "rm3", 3: str(SCENES_DIR / "f3of" / "dt1.toml")}[bodies])
    return max(make_body(e.body, scene.base_dir, True).radius for e in scene.bodies)


def still_rm3(hydro: str, stiffness: float = 0.0):
    """rm3 in still water, its take-off without a damper (a spring of `stiffness`, N/m, or nothing), the float kicked
    upwards at KICK m/s."""
    from sim.scene.config import load_scene, with_overrides

    scene = with_overrides(load_scene("rm3"), waves__kind="still", fluid__hydro=hydro)
    f = scene.bodies[1]
    f = dataclasses.replace(f, constraint=dataclasses.replace(f.constraint, pto_damping=0.0, pto_stiffness=stiffness),
                            initial=dataclasses.replace(f.initial, velocity=(0.0, 0.0, KICK)))  # fmt: skip
    return dataclasses.replace(scene, bodies=(scene.bodies[0], f))


# ---- the report's runs ------------------------------------------------------------------------------


def _shipped() -> list[Path]:
    from sim.hydro.bem import SHIPPED

    return sorted(SHIPPED.glob("*.npz"))


def solve_fit(path: Path, points: int) -> SolveFit:
    """One shipped solve's fit: its damping's floor over the dense grid, its misfits, its states."""
    from sim.hydro.bem import Coefficients
    from sim.hydro.radiation import fit_memory

    c = Coefficients.load(path)
    memory = fit_memory(c, length=scene_length(c, path.stem))
    w, low = damping_floor(memory, float(c.omega.max()), points, radiating(memory))
    B, A = misfits(memory, c)
    return SolveFit(path.stem, c.damping.shape[1] // 6, len(c.omega), float(c.omega.max()), float(np.abs(c.damping).max()), memory.states,
                    B, A, float(c.omega.min()), len(radiating(memory)), w, low)  # fmt: skip


def kicked_rm3(horizon: float, every: float) -> KickedRm3:
    """rm3 without a damper (still_rm3), linear hydro stepped exactly for `horizon` s, sampled every `every` s."""
    from sim.system.linear import exact_linear
    from sim.system.tree import build

    system, s = build(still_rm3("linear"))
    stepper = exact_linear(system, s)
    n = stepper.A.shape[0] - 1  # the last state is the constant 1
    eig = float(np.linalg.eigvals(stepper.A[:n, :n]).real.max())
    start, kick = sum(system.energies(s).values()), system.energies(s)["E_kin"]
    steps = max(1, round(every / 0.1))
    t, energy, balance = [0.0], [0.0], [0.0]
    for _ in range(round(horizon / (0.1 * steps))):
        s = stepper.advance(s, 0.1, steps)
        e = sum(system.energies(s).values()) - start
        t.append(s.t)
        energy.append(e)
        balance.append(e + s.absorbed.sum() + s.E_rad)
    return KickedRm3(np.array(t), np.array(energy), np.array(balance), float(kick), eig, float(s.E_rad))


def compute_passivity(cfg: PassivitySettings, tick) -> Passivity:
    out = Passivity(cfg)
    for path in _shipped():
        out.solves.append(solve_fit(path, cfg.points))
        tick()
    if cfg.horizon > 0:
        out.rm3 = kicked_rm3(cfg.horizon, cfg.every)
        tick()
    return out
