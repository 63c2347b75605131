"""Unit quaternions (w, x, y, z order) and the exact rotation exp(h [w]x), smooth at w = 0."""

from __future__ import annotations

import numpy as np


def quat_multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product a * b of two quaternions (w, x, y, z)."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return np.array(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ]
    )


def quat_to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrix of a unit quaternion (w, x, y, z); normalises q first."""
    w, x, y, z = q / np.sqrt(q @ q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def matrix_to_quat(R: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z) with w >= 0 of a rotation matrix (Shepperd's method)."""
    tr = np.trace(R)
    diag = np.diag(R)
    k = int(np.argmax([tr, *diag]))
    if k == 0:
        s = 2.0 * np.sqrt(1.0 + tr)
        q = np.array([s / 4, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s])
    else:
        i = k - 1
        j, m = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * np.sqrt(1.0 + R[i, i] - R[j, j] - R[m, m])
        q = np.empty(4)
        q[0] = (R[m, j] - R[j, m]) / s
        q[1 + i] = s / 4
        q[1 + j] = (R[j, i] + R[i, j]) / s
        q[1 + m] = (R[m, i] + R[i, m]) / s
    q /= np.sqrt(q @ q)
    return q if q[0] >= 0 else -q


def rotation_quat(rotvec: np.ndarray) -> np.ndarray:
    """Quaternion of the rotation by angle |v| about v, i.e. exp([v]x); exact and smooth at v = 0.

    sin(theta/2)/theta is taken from its Taylor series for small theta, so no
    artificial spin is ever needed (the source report needed one to avoid 0/0).
    """
    theta2 = float(rotvec @ rotvec)
    if theta2 < 1e-8:  # series error < theta^6/3e5 < 1e-29: below round-off
        half_sinc = 0.5 - theta2 / 48.0 + theta2 * theta2 / 3840.0
        cos_half = 1.0 - theta2 / 8.0 + theta2 * theta2 / 384.0
    else:
        theta = np.sqrt(theta2)
        half_sinc = np.sin(0.5 * theta) / theta
        cos_half = np.cos(0.5 * theta)
    return np.array([cos_half, *(half_sinc * rotvec)])


def rotate_world(q: np.ndarray, rotvec_world: np.ndarray) -> np.ndarray:
    """Apply the world-frame rotation exp([v]x) to orientation q (left multiplication)."""
    return quat_multiply(rotation_quat(rotvec_world), q)


def rotate_body(q: np.ndarray, rotvec_body: np.ndarray) -> np.ndarray:
    """Apply a body-frame rotation exp([v]x) to orientation q (right multiplication)."""
    return quat_multiply(q, rotation_quat(rotvec_body))


def normalized(q: np.ndarray) -> np.ndarray:
    return q / np.sqrt(q @ q)


def skew(v: np.ndarray) -> np.ndarray:
    """Cross-product matrix [v]x, so that skew(v) @ a == cross(v, a)."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
