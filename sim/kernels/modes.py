"""The 6x6 algebra of the linear twist flow, in mass-normalised coordinates: it reads no spec (spec.py), so one
compiled copy serves every specialisation of the kernels (SHARED in __init__.py)."""

from __future__ import annotations

import math

import numpy as np

from .jit import JIT, njit


@njit(**JIT)
def matmul6(A, B):
    out = np.zeros((6, 6))
    for i in range(6):
        for j in range(6):
            acc = 0.0
            for k in range(6):
                acc += A[i, k] * B[k, j]
            out[i, j] = acc
    return out


@njit(**JIT)
def mat6v(K, y):
    out = np.zeros(6)
    for i in range(6):
        for j in range(6):
            out[i] += K[i, j] * y[j]
    return out


@njit(**JIT)
def damping_modes(D, R, mass, inertia):
    """K = W D W with W = diag(M, R I R^T)^(-1/2): D in mass-normalised coordinates, whose
    eigenvalues are the damping rates."""
    W = np.zeros((6, 6))
    for i in range(3):
        W[i, i] = 1.0 / math.sqrt(mass)
        for j in range(3):  # R diag(I^-1/2) R^T
            W[3 + i, 3 + j] = (
                R[i, 0] * R[j, 0] / math.sqrt(inertia[0])
                + R[i, 1] * R[j, 1] / math.sqrt(inertia[1])
                + R[i, 2] * R[j, 2] / math.sqrt(inertia[2])
            )
    return matmul6(matmul6(W, D), W)


@njit(**JIT)
def exact_modes(K, h):
    """Eigenmodes of K when h K is stiff; when h trace(K) <= 1/2 the Taylor series of exp(-hK)
    converges to round-off in ~15 products and is cheaper than an eigensolver: flagged by lam[0] = -1."""
    if h * (K[0, 0] + K[1, 1] + K[2, 2] + K[3, 3] + K[4, 4] + K[5, 5]) <= 0.5:
        lam = np.zeros(6)
        lam[0] = -1.0
        return lam, np.eye(6)
    lam, V = np.linalg.eigh(K)
    # a zero mode (a few wet samples: D has rank 3) can come out at -1e-11: clamped, or lam[0] < 0 would read as
    # the mild flag above and sum a divergent series (a 1 kg cube at d = 1e7 reached 1e106 m/s in one step). V in C order
    # as np.eye's: one array type for the carry's V, so the linear flow taking it compiles once, not once per layout
    return np.maximum(lam, 0.0), np.ascontiguousarray(V)
