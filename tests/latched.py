"""The periodic motion of a memoryless oscillator under a switching take-off, semi-analytically (tests' reference).

m x'' + b x' + C x = F cos(omega t) with b the take-off's damper, switched at each stop (x' = 0) of the motion:
latching holds x for t_L from each stop, then frees it (b = c) until the next (Babarit & Clement 2006, Applied Ocean
Research 28: 77-91); declutching frees it (b = 0) for t_D from each stop, then damps it (b = c). In the periodic state
the motion is antisymmetric over half a period, so a half period starts at a stop (x0, 0) at some phase and ends at the
next, (-x0, 0), T / 2 later. Each segment's solution is the forced response plus the free one (a matrix exponential),
so the end state is linear in x0 and in (cos omega t_s, sin omega t_s): the half-period condition is a 2 x 3 linear
system whose null vector, normalised on the circle, gives the orbit. Its mean absorbed power is (2 / T) times the
integral of c x'^2 over the damped segments.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import expm, null_space


def _forced(m, b, C, F, omega) -> np.ndarray:
    """P (2, 2): the forced response (x, v) = P (cos omega t, sin omega t)."""
    X = F / complex(C - m * omega**2, omega * b)  # x = Re X e^(i omega t)
    return np.array([[X.real, -X.imag], [-omega * X.imag, -omega * X.real]])


def _turn(angle: float) -> np.ndarray:
    return np.array([[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]])


def periodic_power(m, C, F, omega, segments) -> tuple[float, float]:
    """(mean absorbed power, W; the stop's amplitude x0, m) of the periodic orbit whose half period is `segments`: a list
    of (b, duration), b = None for held (latched). The durations add up to T / 2."""
    T = 2 * math.pi / omega
    assert abs(sum(d for _, d in segments) - T / 2) < 1e-9 * T
    # the state as Sx x0 + Su u, u = (cos omega t_s, sin omega t_s)
    Sx, Su, elapsed = np.array([1.0, 0.0]), np.zeros((2, 2)), 0.0
    pieces = []
    for b, d in segments:
        pieces.append((b, d, elapsed, Sx.copy(), Su.copy()))
        if b is None:  # held: x stays, v = 0
            Sx, Su = np.array([Sx[0], 0.0]), np.vstack([Su[0], np.zeros(2)])
        else:
            A = np.array([[0.0, 1.0], [-C / m, -b / m]])
            Phi, P = expm(A * d), _forced(m, b, C, F, omega)
            Sx, Su = Phi @ Sx, P @ _turn(omega * (elapsed + d)) + Phi @ (Su - P @ _turn(omega * elapsed))
        elapsed += d
    system = np.column_stack([Sx + np.array([1.0, 0.0]), Su])  # end = (-x0, 0)
    w = null_space(system)[:, 0]
    w = w / np.linalg.norm(w[1:])
    x0, u = w[0], w[1:]
    energy = 0.0
    for b, d, start, Sx0, Su0 in pieces:
        if b is None or b == 0.0:
            continue
        A = np.array([[0.0, 1.0], [-C / m, -b / m]])
        P = _forced(m, b, C, F, omega)
        y0 = Sx0 * x0 + Su0 @ u
        s = np.linspace(0.0, d, 2001)
        v = np.array([(P @ _turn(omega * (start + si)) @ u + expm(A * si) @ (y0 - P @ _turn(omega * start) @ u))[1] for si in s])
        energy += b * float(np.trapezoid(v * v, s))
    return 2.0 * energy / T, abs(x0)
