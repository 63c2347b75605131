"""A passive radiation memory: the fit of K(i omega) = B(omega) + i omega (A(omega) - A_inf) behind hydro/radiation.py.

Cummins' memory K must be passive: the radiation damping B(omega) = Re K(i omega) is positive semi-definite at every
frequency (a body cannot take energy from still water). A fit that misses this can pump energy into a lightly damped
body without bound, so the fit here is made passive and checked:

1. Dofs. The dofs that radiate (as before: diagonal damping above 1e-3 of the largest translational one, rotations
   times length^2) fall into blocks of coupled dofs: two are coupled when the peak of their B or A - A_inf coupling
   is above 5 % of the geometric mean of their diagonal peaks (a cube's surge-pitch, rm3's spar and float heave).
   Smaller couplings (a symmetric body's numerical noise) are left out, so K is block diagonal; B and A are made
   symmetric (reciprocity) first.
2. Poles. In each block, scaled so each diagonal damping peaks at 1 (a congruence: it keeps B's eigenvalues' signs),
   every entry shares one set of stable poles, found by vector fitting (Gustavsen & Semlyen 1999, IEEE Trans. Power
   Delivery 14: 1052-1061; with a residual mass term s dA, the B and A residuals weighted against their own peaks and
   omega times the A residual against |K|'s), each kept within REACH times the grid's top frequency and at a damping
   ratio of at least ZETA_MIN (narrower features are the BEM's irregular frequencies, not radiation).
3. Residues. K(s) = sum_l R_l / (s - p_l) + s dA with real symmetric (pairs: complex conjugate) residue matrices,
   constrained so K(0) = 0 (B vanishes at rest), by weighted least squares on B and A together.
4. Passivity, enforced: the smallest change of the residues (in the least-squares metric of the data) that makes
   B_fit(omega) >= MARGIN x (its scale) at every frequency of a dense grid (log spaced from w_min / 1000 to
   1000 w_max, and across every pole's width), the limits omega -> 0 (B ~ omega^2 B_2) and omega -> infinity
   (B ~ B_-2 / omega^2) positive semi-definite too, and the residual mass dA >= 0 (what the dynamics above the grid
   add to A on it: a positive mass). This is a convex problem; it is solved by cutting planes (each violated
   eigenvector at a frequency is a linear constraint, Gustavsen 2008, IEEE Trans. Power Delivery 23: 2278-2285),
   each step a least-distance problem (Lawson & Hanson 1974, ch. 23) solved by non-negative least squares, planes
   that no longer hold the solution dropped. The result is checked on a grid four times denser, each dip of the
   smallest eigenvalue sampled 64 times finer; it must pass (else more planes).
5. Order: the lowest number of pole pairs whose passive fit meets the tolerance (B and A against their peaks, K
   against |K|'s); failing that, the order of least misfit with TAIL pole pairs added above the grid, which let the
   enforcement make the tail passive without bending the fit on the grid.

The memory's added mass at infinite frequency is the BEM's A_inf plus dA. Each entry (i, j) and pole becomes a block
of one or two states fed by one twist component and feeding one load component, as radiation.Radiation and the
compiled kernels take it; RadiationMemory.compact is the same K with one or two states per pole and input dof (the
several-body system's dense algebra).
"""

from __future__ import annotations

import ast
import hashlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from sim.errors import ConfigError
from sim.hydro import bem
from sim.hydro.bem import UNREADABLE, _replace, _thread

ZETA_MIN = 0.01
"""Smallest damping ratio of a pole."""
MARGIN = 1e-6
"""B_fit is kept at least this share of the block's largest damping (scaled by the band's shape below and above the grid)."""
TAIL = (1.5, 3.0)
"""Where a fit that misses the tolerance also tries two pole pairs (damping ratio 0.3), in multiples of the grid's top frequency."""
REACH = 3.0
"""Poles are kept within this multiple of the grid's top frequency (the damping past the grid's end, its tail)."""
ITERATIONS = 2000
"""Rounds of cutting planes on one grid before the enforcement gives up: a 9-dof block (three bodies' surge, heave and
pitch, the F3OF platform) needs about 600; 200 had been enough for blocks of up to 6."""
COUPLING = 0.05
"""Dofs whose B or A - A_inf coupling peaks above this share of their diagonals' geometric mean are fitted together."""


@dataclass(frozen=True, eq=False)
class EntryFit:
    """One pole's share of K_ij(s): r / (s - p) (+ its conjugate for a complex pole), as a block of one or two states."""

    row: int
    col: int
    F: np.ndarray
    """(n, n) system matrix, n = 1 (real pole) or 2 (complex pair), eigenvalues in the left half plane."""
    G: np.ndarray
    """(n,) input vector (the velocity nu_j enters here)."""
    H: np.ndarray
    """(n,) output vector (mu_i = H x)."""
    error: float
    """The entry's misfit (its block's: B against B's peak, A against A's, the larger), the same for each of its poles."""
    pole: complex = 0j
    residue: complex = 0j

    def response(self, omega) -> np.ndarray:
        """This block's K(i omega); omega may be complex (the fit continued off the real axis)."""
        s = 1j * np.asarray(omega, complex)
        out = self.residue / (s - self.pole)
        return out + np.conj(self.residue) / (s - np.conj(self.pole)) if self.pole.imag != 0 else out


@dataclass(frozen=True, eq=False)
class BlockFit:
    """The fit of one block of coupled dofs."""

    dofs: tuple
    poles: np.ndarray
    """Complex, one of each conjugate pair (Im >= 0)."""
    error_B: np.ndarray
    """(m, m) max |B_fit - B| over the grid against the entry's peak |B_ij| (against sqrt(peak B_ii B_jj) for couplings
    under COUPLING of it)."""
    error_A: np.ndarray
    """(m, m) max |A_fit - A| against the entry's peak |A_ij| (likewise)."""
    planes: int = 0
    """Cutting planes the passivity enforcement needed."""
    residues: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 0), complex))
    """(m, m, elements) each pole's residue matrix (pairs expanded: p then p*), SI units."""


@dataclass(frozen=True, eq=False)
class RadiationMemory:
    """Every fitted block stacked: x' = F x + G nu, memory force (d,) = -H x (d = 6 per body)."""

    F: np.ndarray
    G: np.ndarray
    """(states, d)"""
    H: np.ndarray
    """(d, states)"""
    entries: tuple[EntryFit, ...]
    added_mass_inf: np.ndarray
    """(d, d) the model's added mass at infinite frequency: the BEM's A_inf plus `residual_mass`."""
    residual_mass: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    """(d, d) dA >= 0: the added mass the dynamics above the BEM grid give on it."""
    blocks: tuple[BlockFit, ...] = ()

    @property
    def states(self) -> int:
        return self.F.shape[0]

    def response(self, omega) -> np.ndarray:
        """(n, d, d) K(i omega) of the whole fitted memory (omega may be complex)."""
        omega = np.atleast_1d(np.asarray(omega, complex))
        d = self.G.shape[1]
        out = np.zeros((len(omega), d, d), complex)
        for e in self.entries:
            out[:, e.row, e.col] += e.response(omega)
        return out

    def damping(self, omega) -> np.ndarray:
        """(n, d, d) B_fit(omega) = Re K(i omega), real omega."""
        return self.response(np.asarray(omega, float)).real

    def compact(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(F, G, H) of the same K(s) with the fewest states these poles allow here: per pole and input dof one state
        (real pole) or two (pair), feeding every load of its block (H dense), for the several-body system's dense algebra.
        The per-entry form (F, G, H, entries) is the compiled kernels' (one load per state)."""
        d = self.G.shape[1]
        Fs, Gs, Hs = [], [], []
        for b in self.blocks:
            k = 0
            for p in b.poles:
                R = b.residues[:, :, k]
                k += 1 if p.imag == 0 else 2
                for a, j in enumerate(b.dofs):
                    g, h = np.zeros((1 if p.imag == 0 else 2, d)), np.zeros((d, 1 if p.imag == 0 else 2))
                    g[0, j] = 1.0
                    if p.imag == 0:
                        Fs.append(np.array([[p.real]]))
                        h[list(b.dofs), 0] = R[:, a].real
                    else:
                        Fs.append(np.array([[p.real, -p.imag], [p.imag, p.real]]))
                        h[list(b.dofs), 0], h[list(b.dofs), 1] = 2 * R[:, a].real, -2 * R[:, a].imag
                    Gs.append(g)
                    Hs.append(h)
        if not Fs:
            return np.zeros((0, 0)), np.zeros((0, d)), np.zeros((d, 0))
        from scipy.linalg import block_diag

        return block_diag(*Fs), np.vstack(Gs), np.hstack(Hs)

    @property
    def error(self) -> tuple[float, float]:
        """(B, A): the largest misfits over every block."""
        return (
            max((float(b.error_B.max()) for b in self.blocks), default=0.0),
            max((float(b.error_A.max()) for b in self.blocks), default=0.0),
        )


def transfer(c) -> np.ndarray:
    """(n, 6k, 6k) K(i omega) = B(omega) + i omega (A(omega) - A_inf) from BEM coefficients."""
    return c.damping + 1j * c.omega[:, None, None] * (c.added_mass - c.added_mass_inf)


def _symmetric(X: np.ndarray) -> np.ndarray:
    return 0.5 * (X + np.swapaxes(X, -1, -2))


def radiating(c, length: float) -> np.ndarray:
    """The dofs whose damping matters: peak |B_ii| above 1e-3 of the largest translational one (rotations: times
    length^2, the body's size, so a sphere's numerical-noise roll damping is left out)."""
    diag = np.diag(np.abs(c.damping).max(axis=0))
    scale = diag.reshape(-1, 6)[:, :3].max()
    return np.flatnonzero(diag > 1e-3 * scale * np.tile([1.0, 1.0, 1.0, length**2, length**2, length**2], len(diag) // 6))


def coupled_blocks(B: np.ndarray, A: np.ndarray, dofs) -> list[list[int]]:
    """The dofs grouped by coupling (COUPLING of the diagonals' geometric mean, in B or A - A_inf), connected components."""
    links = []
    for X in (B, A):
        peak = np.abs(X).max(axis=0)
        links.append(peak > COUPLING * np.sqrt(np.outer(peak.diagonal(), peak.diagonal())))
    link = links[0] | links[1]
    left, out = [int(i) for i in dofs], []
    while left:
        group = [left.pop(0)]
        for i in group:  # grows while scanned
            group += [j for j in left if link[i, j]]
            left = [j for j in left if j not in group]
        out.append(sorted(group))
    return out


# ---- rational basis ----------------------------------------------------------------------------------------------


def _elements(poles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(lam, T): every pole (pairs expanded) and the map from real coefficients to their complex residues: a real pole
    takes one coefficient, a pair p, p* two (x + i y on p, x - i y on p*)."""
    lam, cols = [], []
    for p in poles:
        if p.imag == 0:
            lam.append(p)
            cols.append({len(lam) - 1: 1.0})
        else:
            lam += [p, np.conj(p)]
            cols += [{len(lam) - 2: 1.0, len(lam) - 1: 1.0}, {len(lam) - 2: 1j, len(lam) - 1: -1j}]
    T = np.zeros((len(lam), len(cols)), complex)
    for j, col in enumerate(cols):
        for k, v in col.items():
            T[k, j] = v
    return np.array(lam, complex), T


def _basis(poles: np.ndarray, s: np.ndarray) -> np.ndarray:
    """(len(s), n) real-rational basis functions at s: 1/(s - p) for a real pole; for a pair 1/(s-p) + 1/(s-p*), i/(s-p) - i/(s-p*)."""
    lam, T = _elements(poles)
    return (1.0 / (s[:, None] - lam[None, :])) @ T


def _stable(z: np.ndarray, top: float) -> np.ndarray:
    """The poles made usable: in the left half plane, within `top` in magnitude, damping ratio >= ZETA_MIN; one of each pair."""
    z = np.where(z.real > 0, -np.conj(z), z)
    z = np.where(np.abs(z) > top, z * top / np.abs(z), z)
    out = []
    for p in z:
        if abs(p.imag) <= 1e-9 * abs(p):
            out.append(complex(min(p.real, -1e-9 * top), 0.0))
        elif p.imag > 0:
            out.append(complex(min(p.real, -ZETA_MIN * abs(p)), p.imag))
    return np.array(out, complex)


def _relocate(w: np.ndarray, data: np.ndarray, wre: np.ndarray, wim: np.ndarray, pairs: int, iterations: int = 15) -> np.ndarray:
    """Vector fitting's poles for every column of `data` (n, E) at once, with a residual mass term s e per column;
    real and imaginary rows weighted by wre, wim (n, E)."""
    s = 1j * w
    beta = np.geomspace(w.min(), w.max(), pairs)
    poles = -beta / 100 + 1j * beta
    for _ in range(iterations):
        Phi = _basis(poles, s)
        n = Phi.shape[1]
        rows = []
        for e in range(data.shape[1]):  # per column: eliminate its own residues (QR), keep sigma's rows
            f = data[:, e]
            M = np.hstack([Phi, s[:, None], -f[:, None] * Phi, f[:, None]])
            R = np.linalg.qr(np.vstack([M.real * wre[:, e, None], M.imag * wim[:, e, None]]), mode="r")
            rows.append(R[n + 1 :, n + 1 :])
        big = np.vstack(rows)
        sigma = np.linalg.lstsq(big[:, :-1], big[:, -1], rcond=None)[0]
        lam, T = _elements(poles)
        zeros = np.linalg.eigvals(np.diag(lam) - np.outer(np.ones(len(lam)), T @ sigma))  # the zeros of 1 + sigma(s)
        poles = _stable(zeros, REACH * w.max())
    return poles


# ---- one block --------------------------------------------------------------------------------------------------


@dataclass
class _Block:
    """A block's scaled data and its least-squares problem for fixed poles."""

    w: np.ndarray
    Bs: np.ndarray
    """(n, m, m) S B S, S = diag(1 / sqrt(peak B_ii))."""
    As: np.ndarray
    """(n, m, m) S (A - A_inf) S."""
    wA: np.ndarray
    """(m, m) weight of an A residual (scaled) so it reads against sqrt(peak |A_ii| peak |A_jj|)."""

    @property
    def m(self) -> int:
        return self.Bs.shape[1]

    def upper(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(i, j, mu): the entries i <= j, each off-diagonal one weighted sqrt(2) (it stands for two)."""
        i, j = np.triu_indices(self.m)
        return i, j, np.where(i == j, 1.0, np.sqrt(2.0))

    def poles(self, pairs: int) -> np.ndarray:
        i, j, mu = self.upper()
        data = (self.Bs + 1j * self.w[:, None, None] * self.As)[:, i, j]
        return _relocate(self.w, data, np.ones_like(data.real) * mu, self.weight_A() * mu / self.w[:, None], pairs)

    def weight_A(self) -> np.ndarray:
        """(n, E) each entry's weight of its A residual at each frequency: against A's peak, and omega times it against
        the peak of |K| (the diagonals'), whichever is the more demanding."""
        i, j, _ = self.upper()
        peak = np.abs(self.Bs + 1j * self.w[:, None, None] * self.As).max(axis=0).diagonal()
        return np.maximum(self.wA[i, j][None, :], self.w[:, None] / np.sqrt(peak[i] * peak[j])[None, :])

    def design(self, poles: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(Z, P, Q): the null space Z of K(0) in the basis's coefficients, and on the grid the B rows P and A rows Q of the
        basis Z (then the residual mass, last column)."""
        Z = np.linalg.svd(_basis(poles, np.zeros(1, complex)).real)[2][1:].T
        Phi = _basis(poles, 1j * self.w) @ Z
        n = len(self.w)
        return Z, np.hstack([Phi.real, np.zeros((n, 1))]), np.hstack([Phi.imag / self.w[:, None], np.ones((n, 1))])

    def least_squares(self, P: np.ndarray, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(c, R): each entry's unconstrained coefficients (E, k) and the triangular factor of its weighted design
        (E, k, k): the misfit of c' is |R (c' - c)|^2 plus a constant."""
        i, j, mu = self.upper()
        weight = self.weight_A()
        c, Rs = [], []
        for e in range(len(i)):
            M = np.vstack([P * mu[e], Q * weight[:, e, None] * mu[e]])
            y = np.concatenate([self.Bs[:, i[e], j[e]] * mu[e], self.As[:, i[e], j[e]] * weight[:, e] * mu[e]])
            q, r = np.linalg.qr(M)
            c.append(np.linalg.solve(r, q.T @ y))
            Rs.append(r)
        return np.array(c), np.array(Rs)

    def misfit(self, P: np.ndarray, Q: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(m, m) max B and A residuals over the grid, scaled (against sqrt(peak B_ii B_jj), sqrt(peak |A_ii| |A_jj|)), and
        max |K_fit - K| against the peak |K_ij| (against sqrt(peak |K_ii| |K_jj|) where that is under COUPLING of it)."""
        i, j, _ = self.upper()
        eB, eA, eK = np.zeros((self.m, self.m)), np.zeros((self.m, self.m)), np.zeros((self.m, self.m))
        rB, rA = P @ c.T - self.Bs[:, i, j], Q @ c.T - self.As[:, i, j]
        eB[i, j] = eB[j, i] = np.abs(rB).max(axis=0)
        eA[i, j] = eA[j, i] = (np.abs(rA) * self.wA[i, j]).max(axis=0)
        peak = np.abs(self.Bs + 1j * self.w[:, None, None] * self.As).max(axis=0)
        own = peak[i, j] / np.sqrt(peak[i, i] * peak[j, j])
        eK[i, j] = eK[j, i] = np.abs(rB + 1j * self.w[:, None] * rA).max(axis=0) / (
            peak[i, j] * np.where(own > COUPLING, 1.0, COUPLING / own)
        )
        return eB, eA, eK


def _least_distance(G: np.ndarray, h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(z, active): min |z| subject to G z >= h (Lawson & Hanson, ch. 23: by non-negative least squares), and which
    constraints hold it there (a positive multiplier)."""
    from scipy.optimize import nnls

    n = G.shape[1]
    E = np.vstack([G.T, h[None, :]])
    f = np.zeros(n + 1)
    f[-1] = 1.0
    u = nnls(E, f, maxiter=50 * E.shape[1])[0]
    r = E @ u - f
    if abs(r[-1]) < 1e-14:
        raise ValueError("the passivity constraints cannot be met")
    return -r[:n] / r[-1], u > 0


def _grid(w: np.ndarray, poles: np.ndarray, n: int) -> np.ndarray:
    """Frequencies to check: n log spaced from w_min / 1000 to 1000 w_max, and n / 100 across +-20 half-widths of each pole."""
    parts = [np.geomspace(w.min() / 1000, w.max() * 1000, n)]
    parts += [p.imag + np.linspace(-20, 20, n // 100) * abs(p.real) for p in poles if p.imag > 0]
    g = np.unique(np.concatenate(parts))
    return g[g > 0]


def _limits(poles: np.ndarray, Z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(low, high): each basis function's B ~ low w^2 as w -> 0 and B ~ high / w^2 as w -> infinity (residual mass: 0)."""
    lam, T = _elements(poles)
    low = np.real((1.0 / lam**3) @ T) @ Z  # 1/(s - p) = -1/p - s/p^2 - s^2/p^3 ...: Re at s = i w: w^2 Re(1/p^3)
    high = np.real(-lam @ T) @ Z  # 1/(s - p) = 1/s + p/s^2 + ...: Re at s = i w: -Re(p) / w^2
    return np.append(low, 0.0), np.append(high, 0.0)


def _enforce(block: _Block, poles: np.ndarray, Z: np.ndarray, c0: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, int]:
    """The coefficients nearest c0 (in the data's least-squares metric R) with B_fit >= its margin on the dense grid, both
    limits positive semi-definite and the residual mass positive semi-definite: (c, planes). Each dip of the grid is then
    sampled 64 times finer, so one between samples is found too."""

    m, (i, j, _) = block.m, block.upper()
    E, k = c0.shape
    w, top = block.w, np.linalg.eigvalsh(block.Bs).max()
    Rinv = np.linalg.inv(R)
    low, high = _limits(poles, Z)
    mass = np.zeros(k)
    mass[-1] = 1.0
    twice = np.where(i == j, 1.0, 2.0)
    # (coefficients, floor, slack): the limits' floors continue the grid's (MARGIN top (w / w_min)^2, MARGIN top (w_max / w)^2);
    # the residual mass >= 0, round-off below zero being zero
    limits = (
        (low, MARGIN * top / w.min() ** 2, 0.0),
        (high, MARGIN * top * w.max() ** 2, 0.0),
        (mass, 0.0, 1e-12 * np.abs(block.As).max()),
    )
    rows, bounds, planes = [], [], 0

    def plane(psi, v, bound):  # v^T (sum_k C_k psi_k) v >= bound, in the entries' coefficients
        rows.append((np.outer(v[i] * v[j] * twice, psi)).ravel())
        bounds.append(bound)

    def floor_at(g):
        return MARGIN * top * np.minimum(1.0, np.minimum((g / w.min()) ** 2, (w.max() / g) ** 2))

    c = c0
    extra = np.zeros(0)
    for n in (4000, 16000, 16000, 16000, 16000, 16000):  # enforce on a grid, then on one four times denser with every dip sampled finer
        g = np.unique(np.concatenate([_grid(w, poles, n), extra]))
        Psi = np.hstack([_basis(poles, 1j * g).real @ Z, np.zeros((len(g), 1))])
        floor = floor_at(g)
        for _ in range(ITERATIONS):
            C = np.zeros((k, m, m))
            C[:, i, j] = C[:, j, i] = c.T
            lam, V = np.linalg.eigh(np.einsum("gk,kab->gab", Psi, C))
            added = len(bounds)
            for q in range(m):  # each run of frequencies where an eigenvalue is under half the floor: planes around its worst
                bad = np.flatnonzero(lam[:, q] < 0.5 * floor)
                for run in np.split(bad, np.flatnonzero(np.diff(bad) > 1) + 1) if len(bad) else []:
                    worst = run[np.argmin(lam[run, q] / floor[run])]
                    for f in (0.99, 1.0, 1.01):
                        at = min(int(np.searchsorted(g, g[worst] * f)), len(g) - 1)
                        plane(Psi[at], V[worst, :, q], 2.0 * floor[at])
            for a, floor_a, slack in limits:
                la, Va = np.linalg.eigh(np.einsum("k,kab->ab", a, C))
                for q in np.flatnonzero(la < 0.5 * floor_a - slack):
                    plane(a, Va[:, q], 2.0 * floor_a)
            if len(bounds) == added:
                break
            planes += len(bounds) - added
            A, b = np.array(rows), np.array(bounds)
            z, active = _least_distance(np.einsum("pek,ekl->pel", A.reshape(len(A), E, k), Rinv).reshape(len(A), -1), b - A @ c0.ravel())
            c = c0 + np.einsum("ekl,el->ek", Rinv, z.reshape(E, k))
            rows, bounds = [r for r, keep in zip(rows, active) if keep], [x for x, keep in zip(bounds, active) if keep]  # (an idle plane
            # that is needed again comes back from the grid)
        else:
            raise ValueError("the radiation memory could not be made passive")
        if n == 4000:
            continue
        # between samples: around each local minimum of the sampled smallest eigenvalue (over its floor), 64 more
        ratio = lam[:, 0] / floor
        dips = np.flatnonzero((ratio[1:-1] <= ratio[:-2]) & (ratio[1:-1] <= ratio[2:]) & (ratio[1:-1] < 10.0)) + 1
        fine = (g[dips - 1][:, None] + (g[dips + 1] - g[dips - 1])[:, None] * np.linspace(0.0, 1.0, 66)[None, 1:-1]).ravel()
        C = np.zeros((k, m, m))
        C[:, i, j] = C[:, j, i] = c.T
        Pf = np.hstack([_basis(poles, 1j * fine).real @ Z, np.zeros((len(fine), 1))])
        below = fine[np.linalg.eigvalsh(np.einsum("gk,kab->gab", Pf, C))[:, 0] < 0.5 * floor_at(fine)]
        if not len(below):
            break
        extra = np.append(extra, below)
    else:
        raise ValueError("the radiation memory could not be made passive")
    return c, planes


def _fit_block(block: _Block, tol: float, max_order: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """(poles, residues (m, m, elements) and dA, both scaled, cutting planes) of the lowest order whose passive fit
    meets tol; failing that, the order of least (unconstrained) misfit with TAIL poles above the grid added (room for the
    enforcement to make the tail passive without bending the fit on the grid), made passive (without them if that fails)."""
    tried, passive = [], None
    for pairs in range(1, max_order + 1):
        poles = block.poles(pairs)
        Z, P, Q = block.design(poles)
        c, R = block.least_squares(P, Q)
        err = max(m.max() for m in block.misfit(P, Q, c))
        if not tried or err < 0.9 * tried[0][0]:  # a higher order must earn its states
            tried.insert(0, (err, poles))
        if err <= tol:  # made passive, does it still? (if it cannot be, a higher order may)
            try:
                passive = _passive(block, tried[0][1])
            except ValueError:
                continue
            if passive[0] <= tol:
                return passive[1:]
    top = block.w.max()
    tail = np.array([complex(-0.3 * f * top, np.sqrt(1 - 0.3**2) * f * top) for f in TAIL])
    for poles in (np.concatenate([tried[0][1], tail]), tried[0][1]):
        try:
            candidate = _passive(block, poles)
        except ValueError:  # (the other may do)
            continue
        return candidate[1:] if passive is None or candidate[0] < passive[0] else passive[1:]
    if passive is None:
        raise ValueError("the radiation memory could not be made passive")
    return passive[1:]


def _passive(block: _Block, poles) -> tuple:
    """(misfit, poles, residues, dA, planes) of the fit on these poles made passive."""
    Z, P, Q = block.design(poles)
    c0, R = block.least_squares(P, Q)
    c, planes = _enforce(block, poles, Z, c0, R)
    i, j, _ = block.upper()
    _, T = _elements(poles)
    coef = np.zeros((block.m, block.m, c.shape[1]))
    coef[i, j] = coef[j, i] = c
    residues = np.einsum("lr,abr->abl", T, np.einsum("rk,abk->abr", Z, coef[:, :, :-1]))
    return max(m.max() for m in block.misfit(P, Q, c)), poles, residues, coef[:, :, -1], planes


def _mirror(block: _Block, fitted: list) -> tuple | None:
    """A block already fitted whose data are this one's up to the signs of its dofs (D X D, D = diag(+-1), to 1e-6 of
    the peaks: surge-pitch and sway-roll of an axisymmetric body): (its fit, D); else None."""
    m = block.m
    for other, fit in fitted:
        if other.m != m or other.Bs.shape != block.Bs.shape:
            continue
        for signs in range(2 ** (m - 1)):
            D = np.array([1.0] + [-1.0 if signs >> k & 1 else 1.0 for k in range(m - 1)])
            DD = np.outer(D, D)
            if all(
                np.abs(X * DD - Y).max() <= 1e-6 * max(np.abs(Y).max(), 1e-300) for X, Y in ((other.Bs, block.Bs), (other.As, block.As))
            ):
                return fit, DD
    return None


def _misfit(block: _Block, poles: np.ndarray, residues: np.ndarray, mass: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(m, m) max B and A residuals over the grid, scaled (against sqrt(peak B_ii B_jj), sqrt(peak |A_ii| |A_jj|))."""
    lam, _ = _elements(poles)
    s = 1j * block.w
    K = np.einsum("abl,nl->nab", residues, 1.0 / (s[:, None] - lam[None, :])) + s[:, None, None] * mass
    return np.abs(K.real - block.Bs).max(axis=0), (np.abs(K.imag / block.w[:, None, None] - block.As) * block.wA).max(axis=0)


# ---- the whole memory ---------------------------------------------------------------------------------------------

_FITS: dict = {}
"""Fits already made or read in this process, by their key (`fit_key`)."""
STORED = Path(__file__).resolve().parents[2] / "assets" / "coefficients" / "memory"
"""The shipped solves' fits (`python -m sim.commands.memory_fits` writes them): a fit of rm3's 12 dofs takes 7-30 s."""


def _fitting_code() -> bytes:
    """This module's code as the fits depend on it: its syntax tree without imports and docstrings (a moved import, a
    comment or a reworded docstring keeps every fit; a changed line of code makes them anew)."""
    tree = ast.parse(Path(__file__).read_text())
    tree.body = [n for n in tree.body if not isinstance(n, (ast.Import, ast.ImportFrom))]
    for node in ast.walk(tree):
        body = getattr(node, "body", None)
        if isinstance(body, list):  # every bare string is documentation: a docstring, or an attribute's
            node.body = [n for n in body if not (isinstance(n, ast.Expr) and isinstance(n.value, ast.Constant))] or [ast.Pass()]
    return ast.dump(tree).encode()


_FITTING_CODE = _fitting_code()


def forget_fits() -> None:
    """Forget the fits made or read in this process (the next ask reads or makes each again)."""
    _FITS.clear()


def fit_key(c, tol: float, max_order: int, length: float) -> str:
    """The fit's identity: the coefficients' bytes, the arguments and this module's code (so a changed fit is made
    anew, never read stale from a file)."""
    h = hashlib.sha256(_FITTING_CODE)
    for a in (c.omega, c.damping, c.added_mass, c.added_mass_inf):
        h.update(np.ascontiguousarray(a, dtype=float).tobytes())
    h.update(repr((float(tol), int(max_order), round(float(length), 12))).encode())
    return h.hexdigest()[:20]


def fit_memory(c, tol: float = 0.02, max_order: int = 10, length: float = 1.0) -> RadiationMemory:
    """The passive memory of the coefficients `c` (the module's docstring): each block of coupled radiating dofs with
    the lowest number of pole pairs (up to max_order) meeting `tol` in B and A (each against its peak), made passive.
    Read from the shipped fits or the user's cache when they hold it, else made (and cached)."""
    key = fit_key(c, tol, max_order, length)
    if key not in _FITS:
        cached = bem.user_cache() / "memory" / f"{key}.npz"
        memory = next((m for m in (_read(STORED / f"{key}.npz"), _read(cached)) if m is not None), None)
        if memory is None:
            refuse_fit_here()
            memory = _fit(c, tol, max_order, length)
            _keep(memory, cached)
        _FITS[key] = memory
    return _FITS[key]


def refuse_fit_here() -> None:
    """Inside bem.no_solves (a live viewer's simulation thread), a fit neither shipped nor cached is refused as a solve
    is (a ConfigError saying why): fitting takes seconds to a minute (rm3-moored's spar resampled: 16 s)."""

    why = getattr(_thread, "no_solve", None)
    if why:
        raise ConfigError(f"it needs a new fit of the radiation memory, {why}")


def _read(path: Path) -> RadiationMemory | None:
    """A stored fit, or None when absent or unreadable (then it is made again)."""

    if not path.exists():
        return None
    try:
        with np.load(path) as f:
            blocks = tuple(_block(f, k) for k in range(int(f["blocks"])))
            return _assemble(blocks, f["added_mass_inf"], f["residual_mass"])
    except UNREADABLE:
        return None


def _block(f, k: int) -> BlockFit:
    """Block k of a stored fit."""
    dofs = tuple(int(i) for i in f[f"dofs{k}"])
    return BlockFit(dofs, f[f"poles{k}"], f[f"error_B{k}"], f[f"error_A{k}"], int(f[f"planes{k}"]), f[f"residues{k}"])


def _keep(memory: RadiationMemory, path: Path) -> None:
    """Store a fresh fit (atomically); a cache that cannot be written only means the next run fits again."""

    arrays = {"blocks": len(memory.blocks), "residual_mass": memory.residual_mass,
              "added_mass_inf": memory.added_mass_inf - memory.residual_mass}  # fmt: skip
    for k, b in enumerate(memory.blocks):
        arrays |= {f"dofs{k}": np.array(b.dofs), f"poles{k}": b.poles, f"error_B{k}": b.error_B, f"error_A{k}": b.error_A,
                   f"planes{k}": b.planes, f"residues{k}": b.residues}  # fmt: skip
    try:
        _replace(path, ".npz", lambda f: np.savez(f, **arrays))
    except OSError:
        pass


def _fit(c, tol: float, max_order: int, length: float) -> RadiationMemory:
    B, A, A_inf = _symmetric(c.damping), _symmetric(c.added_mass), _symmetric(c.added_mass_inf)
    d, w = B.shape[1], c.omega
    blocks, dA, fitted = [], np.zeros((d, d)), []
    for dofs in coupled_blocks(B, A - A_inf, radiating(c, length)):
        ix = np.ix_(dofs, dofs)
        Bb, Ab = B[:, dofs][:, :, dofs], A[:, dofs][:, :, dofs]
        pB, pA = np.abs(Bb).max(axis=0).diagonal(), np.abs(Ab).max(axis=0).diagonal()
        S = 1.0 / np.sqrt(pB)
        SS = np.outer(S, S)
        block = _Block(w, Bb * SS, (Ab - A_inf[ix]) * SS, np.sqrt(np.outer(pB, pB) / np.outer(pA, pA)))
        mirror = _mirror(block, fitted)
        if mirror is None:
            fit = _fit_block(block, tol, max_order)
        else:  # the same fit, its dofs' signs turned
            (poles, residues, mass, planes), DD = mirror
            fit = (poles, residues * DD[:, :, None], mass * DD, planes)
        fitted.append((block, fit))
        poles, residues, mass, planes = fit
        eB, eA = _misfit(block, poles, residues, mass)
        dA[ix] = mass / SS
        # against each entry's own peak where it matters, else against the diagonals' (the scaled residuals are the latter)
        own_B, own_A = np.abs(Bb).max(axis=0) / np.sqrt(np.outer(pB, pB)), np.abs(Ab).max(axis=0) / np.sqrt(np.outer(pA, pA))
        error_B = eB / np.where(own_B > COUPLING, own_B, 1.0)
        error_A = eA / np.where(own_A > COUPLING, own_A, 1.0)
        blocks.append(BlockFit(tuple(dofs), poles, error_B, error_A, planes, residues / SS[:, :, None]))
    return _assemble(tuple(blocks), A_inf, dA)


def _assemble(blocks: tuple[BlockFit, ...], A_inf: np.ndarray, dA: np.ndarray) -> RadiationMemory:
    """The state-space memory of fitted blocks: per entry (i, j) and pole a block of one or two states."""
    d = len(A_inf)
    entries = []
    for b in blocks:
        for a, i in enumerate(b.dofs):
            for k2, j in enumerate(b.dofs):
                error = float(max(b.error_B[a, k2], b.error_A[a, k2]))
                k = 0
                for p in b.poles:
                    r = b.residues[a, k2, k]
                    k += 1 if p.imag == 0 else 2
                    if r == 0:
                        continue
                    if p.imag == 0:  # r / (s - p)
                        entries.append(EntryFit(i, j, np.array([[p.real]]), np.ones(1), np.array([r.real]), error, p, r.real + 0j))
                    else:  # r / (s - p) + conj: zeta' = p zeta + nu, mu = 2 Re(r zeta), zeta = x1 + i x2
                        F = np.array([[p.real, -p.imag], [p.imag, p.real]])
                        entries.append(EntryFit(i, j, F, np.array([1.0, 0.0]), np.array([2 * r.real, -2 * r.imag]), error, p, r))
    n = sum(len(e.G) for e in entries)
    F, G, H = np.zeros((n, n)), np.zeros((n, d)), np.zeros((d, n))
    k = 0
    for e in entries:
        m = len(e.G)
        F[k : k + m, k : k + m] = e.F
        G[k : k + m, e.col] = e.G
        H[e.row, k : k + m] = e.H
        k += m
    return RadiationMemory(F, G, H, tuple(entries), A_inf + dA, dA, tuple(blocks))
