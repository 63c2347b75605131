"""A linear system stepped exactly: linear hydrostatics and Froude-Krylov force (hydro/linear_hydro.py) on bodies that only
slide (fixed and prismatic joints down to the world: constant Jacobians, nothing turns), no mooring lines.

Then everything is linear and time-invariant but the waves' forcing. With q the joints' coordinates, v their rates
(the system's velocities), x the radiation memory's states and J the bodies' stacked twist Jacobian (constant):

    M v' = J^T (f0 - C J q - D J v - H x) - K q - c v + J^T Re sum_i Y_i e^(-i omega_i t),   q' = v,   x' = F x + G J v,

M the mass with the added mass at infinite frequency, f0, C, D the bodies' linear loads at rest (stacked, block
diagonal), K and c the take-offs' springs and dampers, (F, G, H) the memory's fit, Y_i the Froude-Krylov and
diffraction forces of component i. So z = (q, v, x, 1) obeys z' = A z + Re sum_i B_i e^(-i omega_i t), whose
solution over a step is exact: z(t + h) = z_p(t + h) + e^(A h) (z(t) - z_p(t)), with z_p = Re sum_i Z_i e^(-i omega_i t),
(A + i omega_i) Z_i = -B_i, the steady response to each component (the frequency domain's). No time-step error:
dt only sets how often the state is written. The take-offs' absorbed energy and the radiated energy are the
integrals of c v^2 and v . J^T H x over each step by Simpson's rule (fourth order). Cost: two products of the
state with fixed matrices a step, whatever the sea (a 64-component sea on rm3: see `python -m sim bench`).

The sea's ramp r(t) = (1 - cos(pi t / T_r)) / 2 over its first T_r seconds is itself a sum of sinusoids: r(t) e^(-i omega t)
= e^(-i omega t) / 2 - e^(-i (omega - pi / T_r) t) / 4 - e^(-i (omega + pi / T_r) t) / 4, so up to T_r the particular
solution is the same construction over those three frequencies per component (its steps cost up to three times
the steady ones'), and after it the steady one; a step across T_r is split there. The ramp is stepped exactly too.

The wave loads are phased at each body's centre of mass where it is (hydro/linear_hydro.py, hydro/diffraction.py): fixed here
only while no body can move horizontally. A slide with a horizontal component in waves is not stepped exactly
(`exact_linear` gives None: Stormer-Verlet, which phases the loads where the bodies are).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from sim.hydro.linear_hydro import LinearLoads

BATCH = 1000
"""Steps advanced in one bulk computation (its arrays: states x steps)."""
SINGULAR = 1e12
"""A component's steady response is not used past this condition number of A + i omega (an undamped resonance)."""


def exact_linear(system, s0):
    """The exact stepper of `system` from its starting state s0 (`ExactLinear`), or None where it does not apply."""
    if not all(isinstance(loads, LinearLoads) for loads in system.loads) or any(h is not None for h in system.held):
        return None
    if system.radiation is not None and system.radiation.wave_drift is not None:  # a force quadratic in the sea, not a linear one
        return None
    if any(g.kind not in ("fixed", "prismatic") for g in system.groups) or not system.n_dofs:
        return None
    if not system.water.flat and moves_horizontally(system, s0):
        return None
    stepper = ExactLinear(system, s0)
    return stepper if stepper.ok else None


def moves_horizontally(system, s0) -> bool:
    """Whether some body's centre of mass can move horizontally (a slide with a horizontal component): the waves' phase
    at it then changes with the motion, which the fixed-phase particular solution cannot follow."""
    return bool(np.abs(system.pose(s0).stacked.reshape(-1, 6, system.n_dofs)[:, :2]).max(initial=0.0) > 1e-12)


class ExactLinear:
    def __init__(self, system, s0):
        self.system = system
        pose = system.pose(s0)
        J = pose.stacked
        d = system.n_dofs
        rad = system.radiation
        s = 0 if rad is None else rad.states
        self.d, self.s = d, s
        n = 2 * d + s + 1  # (q, v, x, 1)
        M = system.inertia(pose)
        f0 = np.concatenate([loads.f0 for loads in system.loads])
        from scipy.linalg import block_diag  # scipy.linalg takes 0.3 s to import: paid by the linear systems

        C = block_diag(*(loads.C for loads in system.loads))
        D = block_diag(*(np.zeros((6, 6)) if loads.D0 is None else loads.D0 for loads in system.loads))
        K, c = np.zeros((d, d)), np.zeros(d)
        self._joint = [(g.coordinate, g.dofs.start) for g in system.joints]
        for g in system.joints:
            K[g.dofs.start, g.dofs.start] += g.stiffness
            c[g.dofs.start] += g.damping
        Minv = np.linalg.inv(M)
        A = np.zeros((n, n))
        A[:d, d : 2 * d] = np.eye(d)
        A[d : 2 * d, :d] = -Minv @ (J.T @ C @ J + K)
        A[d : 2 * d, d : 2 * d] = -Minv @ (J.T @ D @ J + np.diag(c))
        A[d : 2 * d, -1] = Minv @ (J.T @ f0)
        if s:
            A[d : 2 * d, 2 * d : 2 * d + s] = -Minv @ J.T @ rad.H
            A[2 * d : 2 * d + s, d : 2 * d] = rad.G @ J
            A[2 * d : 2 * d + s, 2 * d : 2 * d + s] = rad.F
        self.A, self.c, self.Minv = A, c, Minv
        self.W = None if rad is None else J.T @ rad.H  # the radiated power is v . W x
        omega, Y = [], []
        for b, loads in enumerate(system.loads):  # each body's Froude-Krylov components, zero on the others
            for w, X in zip(loads.omega, loads.X):
                omega.append(w)
                Y.append(J.T @ _placed(X, b, len(system.loads)))
        if rad is not None and rad.diffraction is not None:  # at the bodies' centres (no slide moves them horizontally)
            for w, X in zip(rad.diffraction.omega, rad.diffraction.amplitudes(pose.x)):
                omega.append(w)
                Y.append(J.T @ X)
        self._probe = np.zeros((2 * d, n))  # the rows of z the rates need: v, and W x
        self._probe[:d, d : 2 * d] = np.eye(d)
        if s:
            self._probe[d:, 2 * d : 2 * d + s] = self.W
        self._maps: dict = {}
        self.ramp = float(system.water.ramp) if omega else 0.0
        """The sea's ramp, s: up to it the forcing is r(t) times the steady one (0: none)."""
        self.steady = self._particular(np.array(omega, float), np.array(Y, complex).reshape(-1, d))
        self.ok = self.steady is not None
        if self.ok and self.ramp > 0:  # r e^(-i w t) = e^(-i w t) / 2 - e^(-i (w -+ pi / T_r) t) / 4
            side = np.pi / self.ramp
            w3 = np.concatenate([omega, np.subtract(omega, side), np.add(omega, side)])
            Y3 = np.concatenate([0.5 * np.array(Y), -0.25 * np.array(Y), -0.25 * np.array(Y)]).reshape(-1, d)
            self.ramped = self._particular(w3, Y3)
            self.ok = self.ramped is not None

    def _particular(self, omega: np.ndarray, Y: np.ndarray):
        """(omega, Zc, Zs, probe Zc, probe Zs) of the forcing Re sum_i Y_i e^(-i omega_i t): its steady response
        Re(Z e^(-i w t)) = Zc cos(w t) + Zs sin(w t), components of one frequency added up; None past SINGULAR."""
        d, n = self.d, self.A.shape[0]
        freq, index = np.unique(omega, return_inverse=True)
        forcing = np.zeros((len(freq), d), complex)
        np.add.at(forcing, index, Y)
        Z = np.zeros((n, len(freq)), complex)
        for i, (w, y) in enumerate(zip(freq, forcing)):
            B = np.zeros(n, complex)
            B[d : 2 * d] = self.Minv @ y
            system_matrix = self.A + 1j * w * np.eye(n)
            if np.linalg.cond(system_matrix) > SINGULAR:
                return None
            Z[:, i] = -np.linalg.solve(system_matrix, B)
        Zc, Zs = Z.real.copy(), Z.imag.copy()
        return freq, Zc, Zs, self._probe @ Zc, self._probe @ Zs

    def _exp(self, h: float) -> tuple[np.ndarray, np.ndarray]:
        """e^(A h), and at the half step only the rows the rates need: probe e^(A h / 2) (a few step lengths kept: a step
        across the ramp's end is split there)."""
        if h not in self._maps:
            if len(self._maps) > 4:
                self._maps.clear()
            from scipy.linalg import expm

            self._maps[h] = (expm(self.A * h), self._probe @ expm(self.A * (0.5 * h)))
        return self._maps[h]

    def state_vector(self, st) -> np.ndarray:
        q = np.zeros(self.d)
        for k, i in self._joint:
            q[i] = st.theta[k]
        return np.concatenate([q, st.v, st.memory, [1.0]])

    def advance(self, st, h: float, n: int = 1):
        """The state n steps of h after st, exactly: the steady response at every step's end from one product, the
        transient carried by e^(A h); the rates at the ends and midpoints for Simpson's rule likewise in bulk. Steps up
        to the ramp's end take the ramped particular solution; one across it is split there."""
        out, left = st, n
        while left:
            if self.ramp - out.t <= 1e-9 * h:  # past the ramp's end (to round-off)
                k, part = left, self.steady
            else:
                k, part = min(left, math.floor((self.ramp - out.t) / h + 1e-9)), self.ramped
            if k == 0:  # the step across the ramp's end: to it, then on
                t_end = out.t + h
                out = self._batch(self._batch(out, self.ramp - out.t, 1, self.ramped), t_end - self.ramp, 1, self.steady)
                out, left = replace(out, t=t_end), left - 1
                continue
            for start in range(0, k, BATCH):
                out = self._batch(out, h, min(BATCH, k - start), part)
            left -= k
        return out

    def _batch(self, st, h: float, n: int, particular):
        full, half = self._exp(h)
        omega, Zc, Zs, Pc, Ps = particular
        d, s = self.d, self.s
        times = st.t + h * np.arange(n + 1)
        wt, wm = np.multiply.outer(omega, times), np.multiply.outer(omega, times[:-1] + 0.5 * h)
        steady = Zc @ np.cos(wt) + Zs @ np.sin(wt)  # (states, n + 1)
        transient = np.empty_like(steady)
        transient[:, 0] = self.state_vector(st) - steady[:, 0]
        for k in range(n):
            transient[:, k + 1] = full @ transient[:, k]
        ends = self._probe @ (steady + transient)  # (2d, n + 1): v and W x at each step's end
        middles = Pc @ np.cos(wm) + Ps @ np.sin(wm) + half @ transient[:, :-1]
        (a_end, r_end), (a_mid, r_mid) = self._rates(ends), self._rates(middles)
        simpson = lambda end, mid: h / 6 * (end[..., :-1] + 4 * mid + end[..., 1:]).sum(axis=-1)  # noqa: E731
        z = steady[:, -1] + transient[:, -1]
        absorbed, theta = st.absorbed.copy(), st.theta.copy()
        gained = simpson(a_end, a_mid)
        for k, i in self._joint:
            absorbed[k] += gained[i]
            theta[k] = z[i]
        return replace(st, t=float(times[-1]), theta=theta, v=z[d : 2 * d].copy(), memory=z[2 * d : 2 * d + s].copy(), absorbed=absorbed,
                       E_rad=st.E_rad + float(simpson(r_end, r_mid)))  # fmt: skip

    def _rates(self, probed: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(each take-off's absorbed power, the radiated power) from the probed rows (v, W x) of one or more states."""
        v = probed[: self.d]
        return self.c[:, None] * v * v, (v * probed[self.d :]).sum(axis=0) if self.W is not None else np.zeros(probed.shape[1])


def _placed(X: np.ndarray, b: int, bodies: int) -> np.ndarray:
    """(6 bodies,) complex: body b's (6,) load in its place, zero elsewhere."""
    out = np.zeros(6 * bodies, complex)
    out[6 * b : 6 * b + 6] = X
    return out
