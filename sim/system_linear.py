"""A linear system stepped exactly: linear hydrostatics and Froude-Krylov force (linear_hydro.py) on bodies that only
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
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.linalg import block_diag, expm

from .linear_hydro import LinearLoads

BATCH = 1000
"""Steps advanced in one bulk computation (its arrays: states x steps)."""
SINGULAR = 1e12
"""A component's steady response is not used past this condition number of A + i omega (an undamped resonance)."""


def exact_linear(system, s0):
    """The exact stepper of `system` from its starting state s0 (`ExactLinear`), or None where it does not apply."""
    if not all(isinstance(loads, LinearLoads) for loads in system.loads) or any(h is not None for h in system.held):
        return None
    if any(g.kind not in ("fixed", "prismatic") for g in system.groups) or not system.n_dofs:
        return None
    stepper = ExactLinear(system, s0)
    return stepper if stepper.ok else None


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
        self.A, self.c = A, c
        self.W = None if rad is None else J.T @ rad.H  # the radiated power is v . W x
        omega, Y = [], []
        for b, loads in enumerate(system.loads):  # each body's Froude-Krylov components, zero on the others
            for w, X in zip(loads.omega, loads.X):
                omega.append(w)
                Y.append(J.T @ _placed(X, b, len(system.loads)))
        if rad is not None and rad.diffraction is not None:
            for w, X in zip(rad.diffraction.omega, rad.diffraction.amplitude):
                omega.append(w)
                Y.append(J.T @ X)
        self.omega, index = np.unique(np.array(omega, float), return_inverse=True)  # components of one frequency add up
        forcing = np.zeros((len(self.omega), d), complex)
        np.add.at(forcing, index, np.array(Y).reshape(-1, d))
        Z, self.ok = np.zeros((n, len(self.omega)), complex), True
        for i, (w, y) in enumerate(zip(self.omega, forcing)):
            B = np.zeros(n, complex)
            B[d : 2 * d] = Minv @ y
            system_matrix = A + 1j * w * np.eye(n)
            if np.linalg.cond(system_matrix) > SINGULAR:
                self.ok = False
                return
            Z[:, i] = -np.linalg.solve(system_matrix, B)
        self.Zc, self.Zs = Z.real.copy(), Z.imag.copy()  # Re(Z e^(-i w t)) = Zc cos(w t) + Zs sin(w t)
        self._probe = np.zeros((2 * d, n))  # the rows of z the rates need: v, and W x
        self._probe[:d, d : 2 * d] = np.eye(d)
        if s:
            self._probe[d:, 2 * d : 2 * d + s] = self.W
        self._maps: dict = {}

    def _exp(self, h: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """e^(A h), and at the half step only the rows the rates need: probe e^(A h / 2) and probe Zc, probe Zs."""
        if h not in self._maps:
            P = self._probe
            self._maps = {h: (expm(self.A * h), P @ expm(self.A * (0.5 * h)), P @ self.Zc, P @ self.Zs)}
        return self._maps[h]

    def state_vector(self, st) -> np.ndarray:
        q = np.zeros(self.d)
        for k, i in self._joint:
            q[i] = st.theta[k]
        return np.concatenate([q, st.v, st.memory, [1.0]])

    def advance(self, st, h: float, n: int = 1):
        """The state n steps of h after st, exactly: the steady response at every step's end from one product, the
        transient carried by e^(A h); the rates at the ends and midpoints for Simpson's rule likewise in bulk."""
        out = st
        for start in range(0, n, BATCH):
            out = self._batch(out, h, min(BATCH, n - start))
        return out

    def _batch(self, st, h: float, n: int):
        full, half, Pc, Ps = self._exp(h)
        d, s = self.d, self.s
        times = st.t + h * np.arange(n + 1)
        wt, wm = np.multiply.outer(self.omega, times), np.multiply.outer(self.omega, times[:-1] + 0.5 * h)
        steady = self.Zc @ np.cos(wt) + self.Zs @ np.sin(wt)  # (states, n + 1)
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
