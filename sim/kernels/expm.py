"""Compiled twin of scipy.linalg.expm for the system's kicks (system/tree.py: System.kick): Pade approximants of degree
3, 5, 7, 9 or 13 with scaling and squaring (Higham 2005, "The scaling and squaring method for the matrix exponential
revisited"), and the small dense algebra it needs, written out as loops: at 10 x 10 a BLAS or LAPACK call costs
more than its arithmetic."""

from __future__ import annotations

import math

import numpy as np

from .jit import JIT, njit

THETA = (1.495585217958292e-2, 2.539398330063230e-1, 9.504178996162932e-1, 2.097847961257068e0, 5.371920351148152e0)
"""The largest 1-norm for which the Pade approximant of degree 3, 5, 7, 9, 13 is exact to double precision (Higham 2005, table 2.3)."""
B3 = np.array([120.0, 60.0, 12.0, 1.0])
B5 = np.array([30240.0, 15120.0, 3360.0, 420.0, 30.0, 1.0])
B7 = np.array([17297280.0, 8648640.0, 1995840.0, 277200.0, 25200.0, 1512.0, 56.0, 1.0])
B9 = np.array([17643225600.0, 8821612800.0, 2075673600.0, 302702400.0, 30270240.0, 2162160.0, 110880.0, 3960.0, 90.0, 1.0])
B13 = np.array([64764752532480000.0, 32382376266240000.0, 7771770303897600.0, 1187353796428800.0, 129060195264000.0,
                10559470521600.0, 670442572800.0, 33522128640.0, 1323241920.0, 40840800.0, 960960.0, 16380.0, 182.0, 1.0])  # fmt: skip


@njit(**JIT)
def matmul_into(A, B, out):
    """out = A B for small dense matrices (out neither A nor B)."""
    n, m, p = A.shape[0], A.shape[1], B.shape[1]
    out[:] = 0.0
    for i in range(n):
        for k in range(m):
            a = A[i, k]
            if a != 0.0:
                for j in range(p):
                    out[i, j] += a * B[k, j]


@njit(**JIT)
def matmul(A, B):
    """A B for small dense matrices."""
    out = np.empty((A.shape[0], B.shape[1]))
    matmul_into(A, B, out)
    return out


@njit(**JIT)
def solve_into(LU, X):
    """X <- A^-1 X ((n, n) and (n, p)), LU holding A and overwritten: Gaussian elimination with partial pivoting (LAPACK's
    getrf/getrs, unblocked)."""
    n, p = LU.shape[0], X.shape[1]
    for c in range(n):
        r, best = c, abs(LU[c, c])
        for i in range(c + 1, n):
            if abs(LU[i, c]) > best:
                r, best = i, abs(LU[i, c])
        if r != c:
            for j in range(n):
                LU[c, j], LU[r, j] = LU[r, j], LU[c, j]
            for j in range(p):
                X[c, j], X[r, j] = X[r, j], X[c, j]
        pivot = LU[c, c]
        for i in range(c + 1, n):
            f = LU[i, c] / pivot
            if f != 0.0:
                for j in range(c + 1, n):
                    LU[i, j] -= f * LU[c, j]
                for j in range(p):
                    X[i, j] -= f * X[c, j]
    for c in range(n - 1, -1, -1):
        for j in range(p):
            acc = X[c, j]
            for k in range(c + 1, n):
                acc -= LU[c, k] * X[k, j]
            X[c, j] = acc / LU[c, c]


@njit(**JIT)
def solve(A, B):
    """X with A X = B ((n, n) and (n, p))."""
    X = B.copy()
    solve_into(A.copy(), X)
    return X


@njit(**JIT)
def expm(A):
    """e^A of a small square matrix (expm_into)."""
    n = A.shape[0]
    out = np.empty((n, n))
    expm_into(A, out, np.empty((7, n, n)))
    return out


@njit(**JIT)
def expm_into(A, out, W):
    """out = e^A of a small square matrix, W (7, n, n) work: the lowest Pade degree exact at A's 1-norm, else degree 13 on
    A / 2^s, squared s times."""
    n = A.shape[0]
    norm = 0.0
    for j in range(n):
        col = 0.0
        for i in range(n):
            col += abs(A[i, j])
        norm = max(norm, col)
    A2, A4, A6, A8, u, V, T = W[0], W[1], W[2], W[3], W[4], W[5], W[6]
    matmul_into(A, A, A2)
    if norm <= THETA[3]:
        count = 1 if norm <= THETA[0] else 2 if norm <= THETA[1] else 3 if norm <= THETA[2] else 4
        b = B3 if count == 1 else B5 if count == 2 else B7 if count == 3 else B9
        u[:] = 0.0
        V[:] = 0.0
        for i in range(n):
            u[i, i], V[i, i] = b[1], b[0]
        for k in range(count):  # U = A sum b_odd A^(2k), V = sum b_even A^(2k)
            P = A2 if k == 0 else A4 if k == 1 else A6 if k == 2 else A8
            if k > 0:
                matmul_into(A2 if k == 1 else A4 if k == 2 else A6, A2, P)
            for i in range(n):
                for j in range(n):
                    u[i, j] += b[2 * k + 3] * P[i, j]
                    V[i, j] += b[2 * k + 2] * P[i, j]
        matmul_into(A, u, T)
        _pade_solve(T, V, out)
        return
    s = max(0, int(math.ceil(math.log2(norm / THETA[4]))))
    scale = 0.5**s
    for i in range(n):
        for j in range(n):
            A8[i, j] = A[i, j] * scale  # As
            A2[i, j] *= scale * scale
    matmul_into(A2, A2, A4)
    matmul_into(A4, A2, A6)
    b = B13
    for i in range(n):  # inner terms into T (U's) and V (V's)
        for j in range(n):
            T[i, j] = b[13] * A6[i, j] + b[11] * A4[i, j] + b[9] * A2[i, j]
            V[i, j] = b[12] * A6[i, j] + b[10] * A4[i, j] + b[8] * A2[i, j]
    matmul_into(A6, T, u)
    for i in range(n):
        for j in range(n):
            u[i, j] += b[7] * A6[i, j] + b[5] * A4[i, j] + b[3] * A2[i, j]
    matmul_into(A6, V, T)
    for i in range(n):
        for j in range(n):
            V[i, j] = T[i, j] + b[6] * A6[i, j] + b[4] * A4[i, j] + b[2] * A2[i, j]
        u[i, i] += b[1]
        V[i, i] += b[0]
    matmul_into(A8, u, T)
    _pade_solve(T, V, out)
    for _ in range(s):
        matmul_into(out, out, T)
        out[:] = T


@njit(**JIT)
def _pade_solve(U, V, out):
    """out = (V - U)^-1 (U + V); U and V overwritten."""
    n = U.shape[0]
    for i in range(n):
        for j in range(n):
            out[i, j] = U[i, j] + V[i, j]
            V[i, j] = V[i, j] - U[i, j]
    solve_into(V, out)
