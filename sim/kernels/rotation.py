"""Compiled twin of bodies/rotation.py (and of the small vector helpers the kernels need), written out as
scalar code: numba's @ calls BLAS, which costs more than the arithmetic at 3x3."""

from __future__ import annotations

import math

import numpy as np

from .jit import JIT, njit


@njit(**JIT)
def quat_multiply(a, b):
    return np.array([
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ])  # fmt: skip


@njit(**JIT)
def quat_to_matrix(q):
    n = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    w, x, y, z = q[0] / n, q[1] / n, q[2] / n, q[3] / n
    R = np.empty((3, 3))
    R[0, 0], R[0, 1], R[0, 2] = 1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)
    R[1, 0], R[1, 1], R[1, 2] = 2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)
    R[2, 0], R[2, 1], R[2, 2] = 2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)
    return R


@njit(**JIT)
def rotation_quat(v):
    theta2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
    if theta2 < 1e-8:
        half_sinc = 0.5 - theta2 / 48.0 + theta2 * theta2 / 3840.0
        cos_half = 1.0 - theta2 / 8.0 + theta2 * theta2 / 384.0
    else:
        theta = math.sqrt(theta2)
        half_sinc = math.sin(0.5 * theta) / theta
        cos_half = math.cos(0.5 * theta)
    return np.array([cos_half, half_sinc * v[0], half_sinc * v[1], half_sinc * v[2]])


@njit(**JIT)
def normalized(q):
    return q / math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])


@njit(**JIT)
def cross(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


@njit(**JIT)
def mv(R, v):
    """R v for a 3x3 R."""
    return np.array([R[0, 0] * v[0] + R[0, 1] * v[1] + R[0, 2] * v[2],
                     R[1, 0] * v[0] + R[1, 1] * v[1] + R[1, 2] * v[2],
                     R[2, 0] * v[0] + R[2, 1] * v[1] + R[2, 2] * v[2]])  # fmt: skip


@njit(**JIT)
def mtv(R, v):
    """R^T v for a 3x3 R."""
    return np.array([R[0, 0] * v[0] + R[1, 0] * v[1] + R[2, 0] * v[2],
                     R[0, 1] * v[0] + R[1, 1] * v[1] + R[2, 1] * v[2],
                     R[0, 2] * v[0] + R[1, 2] * v[1] + R[2, 2] * v[2]])  # fmt: skip


@njit(**JIT)
def rotate_tensor(R, Q):
    """R Q R^T for 3x3 matrices."""
    out = np.zeros((3, 3))
    for i in range(3):
        for j in range(3):
            acc = 0.0
            for k in range(3):
                for m in range(3):
                    acc += R[i, k] * Q[k, m] * R[j, m]
            out[i, j] = acc
    return out
