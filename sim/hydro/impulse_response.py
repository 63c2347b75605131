"""The radiation's impulse response and the frequency coefficients, each from the other (Ogilvie 1964):

    K(t) = (2/pi) int_0^inf B(w) cos(w t) dw,    B(w) = int_0^inf K(t) cos(w t) dt,
    A(w) = A(inf) - (1/w) int_0^inf K(t) sin(w t) dt,

as WEC-Sim's BEMIO writes K (radiationIRF.m) and as files that hold only one side need the other (sim/io/bemio_h5.py:
A and B from K; sim/io/nemoh.py: A(inf) from A and B). The integrals are the trapezoid rule on the samples given,
as weights contracted with the cosines and sines: no (frequencies x modes x modes x times) array.
"""

from __future__ import annotations

import math

import numpy as np


def trapezoid_weights(x: np.ndarray) -> np.ndarray:
    """(n,) w with sum_i w_i f(x_i) the trapezoid rule of f over the samples x (two at least)."""
    step = np.diff(np.asarray(x, float))
    return np.concatenate([[step[0] / 2], (step[:-1] + step[1:]) / 2, [step[-1] / 2]])


def impulse_response(omega: np.ndarray, B: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(r, c, nt) K at times `t` from the damping B ((n, r, c)) at frequencies `omega`."""
    return (2 / math.pi) * np.einsum("nrc,nt->rct", B * trapezoid_weights(omega)[:, None, None], np.cos(np.outer(omega, t)))


def frequency_response(K: np.ndarray, t: np.ndarray, omega: np.ndarray, A_inf: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(n, r, c) A and B at `omega` from the impulse response K ((r, c, nt)) at times `t` and A(inf)."""
    weighted = K * trapezoid_weights(t)
    B = np.einsum("rct,nt->nrc", weighted, np.cos(np.outer(omega, t)))
    A = A_inf[None] - np.einsum("rct,nt->nrc", weighted, np.sin(np.outer(omega, t))) / omega[:, None, None]
    return A, B
