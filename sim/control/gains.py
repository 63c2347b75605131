"""A take-off's best gains in regular waves, from the frequency domain: what its joint sees (its *port*).

About the rest pose, with time factor e^(-i omega t), the generalised motion xi of a body or a system obeys

    [-omega^2 (M + J^T A J) - i omega J^T (B + D) J + K] xi = J^T X + e F_pto,

J the bodies' twists per unit generalised rate, A, B, X the BEM's added mass, radiation damping and excitation
(Froude-Krylov and diffraction, linearly interpolated in frequency and heading as the runs' diffraction is), D the
terms' linear damping, K the stiffness of the model's own pose loads, e the joint's column. Seen from the take-off,
everything else is one impedance Z (force per unit rate of its coordinate) and one force F (per unit wave amplitude):

    Z = 1 / (-i omega G),   G = e^T [..]^-1 e,      F = Z V_open,   V_open = -i omega e^T [..]^-1 J^T X.

A take-off F_pto = -k theta - c theta_dot absorbs P = c |F a|^2 / (2 |Z + c + i k / omega|^2) in waves of amplitude a:
- complex-conjugate (reactive) control, c + i k / omega = conj(Z): c = Re Z, k = -omega Im Z, and
  P_max = |F a|^2 / (8 Re Z) (Falnes 2002, Ocean Waves and Oscillating Systems, sec. 6.3; for one body |X|^2 / 8B);
- the best damper alone: c = |Z| (the same, with k = 0);
- latching: the natural period T_n (Im Z = 0) gives the latch time (T - T_n) / 2 (Babarit & Clement 2006).
The take-off's own spring and damper are left out of Z: the port is the device without its take-off.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from sim.errors import ConfigError
from sim.hydro.diffraction import transfer_at
from sim.hydro.forces import Model
from sim.hydro.linear_hydro import LinearLoads
from sim.system.frequency import damping_at_rest, stiffness
from sim.water.seas import StillWater


@dataclass(frozen=True)
class Port:
    omega: float
    """rad/s."""
    impedance: complex
    """Z: force per unit rate of the joint's coordinate, N s/m (N m s/rad)."""
    force: complex
    """F: the waves' force at the port per unit wave amplitude (its Thevenin equivalent), N/m."""
    natural_period: float | None
    """T_n where Im Z crosses zero on the solve's grid (linearly interpolated), s; None if it does not."""

    def power(self, stiffness: float, damping: float, amplitude: float) -> float:
        """The mean power a spring and damper on the joint absorb in waves of `amplitude`, W."""
        load = self.impedance + damping + 1j * stiffness / self.omega
        return 0.5 * damping * abs(self.force * amplitude) ** 2 / abs(load) ** 2

    @property
    def reactive(self) -> tuple[float, float]:
        """(k, c) of complex-conjugate control."""
        return -self.omega * self.impedance.imag, self.impedance.real

    @property
    def passive(self) -> float:
        """The damper alone that absorbs most: |Z|."""
        return abs(self.impedance)

    def optimum(self, amplitude: float) -> float:
        """|F a|^2 / (8 Re Z), W."""
        return abs(self.force * amplitude) ** 2 / (8.0 * self.impedance.real)

    def latch_time(self) -> float | None:
        """(T - T_n) / 2 for the wave's period T (None without T_n, or below it: then declutching suits)."""
        T = 2 * math.pi / self.omega
        return None if self.natural_period is None or T <= self.natural_period else 0.5 * (T - self.natural_period)


def _interpolated(c, omega: float) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) at omega, linearly between the solve's frequencies."""
    w = np.asarray(c.omega, float)
    if not w[0] <= omega <= w[-1]:
        raise ConfigError(f"the wave's frequency {omega:.4g} rad/s is outside the BEM solve's {w[0]:.4g}-{w[-1]:.4g} rad/s")
    k = int(np.clip(np.searchsorted(w, omega) - 1, 0, len(w) - 2))
    s = (omega - w[k]) / (w[k + 1] - w[k])
    return (1 - s) * c.added_mass[k] + s * c.added_mass[k + 1], (1 - s) * c.damping[k] + s * c.damping[k + 1]


def _impedance(c, omega: float, J: np.ndarray, M: np.ndarray, D: np.ndarray, K: np.ndarray) -> np.ndarray:
    A, B = _interpolated(c, omega)
    return -(omega**2) * (M + J.T @ A @ J) - 1j * omega * (J.T @ B @ J + D) + K


def port(c, omega: float, beta: float, J: np.ndarray, M: np.ndarray, D: np.ndarray, K: np.ndarray, e: np.ndarray) -> Port:
    """The port of the generalised coordinate `e` ((d,)) at omega for waves heading beta: J (6k, d); M, D, K (d, d) the
    generalised mass, the terms' linear damping and the stiffness (the take-off's own left out)."""

    X = (transfer_at(c, c.froude_krylov, omega, beta) + transfer_at(c, c.diffraction, omega, beta))[0]
    Zd = _impedance(c, omega, J, M, D, K)
    G = complex(e @ np.linalg.solve(Zd, e))
    Z = 1.0 / (-1j * omega * G)
    V_open = complex(-1j * omega * (e @ np.linalg.solve(Zd, J.T @ X)))
    reactance = []
    for w in c.omega:
        Zw = _impedance(c, float(w), J, M, D, K)
        reactance.append((1.0 / (-1j * w * complex(e @ np.linalg.solve(Zw, e)))).imag)
    reactance = np.array(reactance)
    natural = None
    for i in np.nonzero(np.sign(reactance[:-1]) != np.sign(reactance[1:]))[0]:
        if reactance[i] > 0 > reactance[i + 1]:  # spring-like below, mass-like above: resonance
            w0 = c.omega[i] - reactance[i] * (c.omega[i + 1] - c.omega[i]) / (reactance[i + 1] - reactance[i])
            natural = 2 * math.pi / float(w0)
    return Port(float(omega), Z, Z * V_open, natural)


def body_port(sim) -> Port:
    """The port of a one-body Simulation's joint in its scene's regular waves."""

    omega, beta, c = _sea(sim.scene, sim.model.radiation)
    joint, body = sim.joint, sim.body
    if joint is None or not joint.dofs:
        raise ConfigError("take-off gains need the body on a prismatic or revolute joint ([constraint] joint)")
    x0, R0 = joint.pose(0.0)
    still = LinearLoads(Model(body, StillWater(sim.scene.fluid.rho, sim.scene.fluid.g), sim.scene.fluid), x0, R0)
    J = joint.jacobian(x0).reshape(6, 1)
    M = np.zeros((6, 6))
    M[:3, :3], M[3:, 3:] = body.mass * np.eye(3), (R0 * body.inertia) @ R0.T
    D = np.zeros((6, 6)) if still.D0 is None else still.D0
    return port(c, omega, beta, J, J.T @ M @ J, J.T @ D @ J, J.T @ still.C @ J, np.ones(1))


def system_port(asm, body: str) -> Port:
    """The port of the joint of `body` (a run of several bodies') in its scene's regular waves, every other joint's take-off kept."""

    omega, beta, c = _sea(asm.scene, asm.system.radiation)
    system = asm.system
    names = [g.name for g in system.joints]
    if body not in names:
        raise ConfigError(f"no take-off on {body!r}: the joints with one are on {', '.join(names) or 'no body'}")
    g = system.joints[names.index(body)]
    bare = [replace(h, stiffness=0.0, damping=0.0) if h is g else h for h in system.groups]
    kept = system.groups, system.joints
    system.groups, system.joints = bare, [h for h in bare if h.kind in ("prismatic", "revolute")]
    try:
        s0 = replace(asm.start, theta=np.zeros_like(asm.start.theta), v=np.zeros_like(asm.start.v))
        pose = system.pose(s0)
        J = np.vstack(pose.J)
        D, K, M = damping_at_rest(system, pose), stiffness(system, s0), system.mass_matrix(pose)
    finally:
        system.groups, system.joints = kept
    e = np.zeros(system.n_dofs)
    e[g.dofs.start] = 1.0
    return port(c, omega, beta, J, M, D, K, e)


def _sea(scene, radiation) -> tuple[float, float, object]:
    """(omega, heading, the BEM coefficients) of a scene in regular waves with radiation from the BEM."""
    if scene.waves.kind != "regular":
        raise ConfigError(f'take-off gains are for regular waves ([waves] kind = "regular"), not {scene.waves.kind!r}')
    if radiation is None or radiation.coefficients is None or radiation.coefficients.diffraction is None:
        raise ConfigError('take-off gains need the BEM\'s coefficients: [fluid] radiation = "bem" in waves')
    return 2 * math.pi / float(scene.waves.period), math.radians(float(scene.waves.direction)), radiation.coefficients
