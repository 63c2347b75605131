"""Issue 60, WAMIT's second-order force files `.12d` and `.12s` read and kept for issue 61: known QTFs written as WAMIT
writes them (one triangle, nondimensional, its time factor) come back whole; the OC4 semi's `.12d` (RAFT's) reads to a
mean drift that is real and pushes with the waves; a cut file is one line."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from sim.errors import ConfigError
from sim.io.wamit_qtf import read_qtf

ROOT = Path(__file__).resolve().parents[2]
SEMI = ROOT / "assets" / "coefficients" / "wamit" / "marin_semi.12d"
RHO, G = 1025.0, 9.81


def _write(path: Path, periods, headings, T, ulen: float) -> None:
    """`T` ((n, n, m, m, 6k), floatsim's time factor, dimensional) as WAMIT's rows: the pairs i <= j only (every heading
    pair), nondimensional by rho g L^k, conjugated to e^(i omega t)."""
    lines = [" WAMIT Numeric Output -- a test's file"]
    n, m, modes = T.shape[0], T.shape[2], T.shape[4]
    for i in range(n):
        for j in range(i, n):
            for a in range(m):
                for b in range(m):
                    for k in range(modes):
                        value = np.conj(T[i, j, a, b, k]) / (RHO * G * ulen ** (2 if k % 6 >= 3 else 1))
                        lines.append(f"{periods[i]:.6E} {periods[j]:.6E} {headings[a]:.6E} {headings[b]:.6E} {k + 1} "
                                     f"{abs(value):.6E} {math.degrees(np.angle(value)):.6E} {value.real:.9E} {value.imag:.9E}")  # fmt: skip
    path.write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize("kind", ["difference", "sum"])
def test_a_qtf_file_comes_back_as_the_transfer_functions_it_was_written_from(tmp_path, kind):
    """Two bodies, two headings, ULEN 2: every entry of both triangles, the other triangle by symmetry (the difference
    QTF Hermitian, the sum QTF symmetric, headings swapped with the frequencies), moments scaled by L^2."""
    rng = np.random.default_rng(12)
    periods, headings = np.array([20.0, 10.0, 5.0]), np.array([0.0, 30.0])  # (periods: ascending frequency)
    n, m = 3, 2
    T = (rng.normal(size=(n, n, m, m, 12)) + 1j * rng.normal(size=(n, n, m, m, 12))) * 1e4
    for i in range(n):  # the whole QTF as physics has it: the other triangle follows from the file's
        for j in range(i):
            T[i, j] = np.swapaxes(np.conj(T[j, i]) if kind == "difference" else T[j, i], 0, 1)
        for a in range(m):
            T[i, i, a, a] = T[i, i, a, a].real if kind == "difference" else T[i, i, a, a]
    path = tmp_path / f"two.{'12d' if kind == 'difference' else '12s'}"
    _write(path, periods, headings, T, ulen=2.0)
    q = read_qtf(path, RHO, G, ulen=2.0)
    assert q.kind == kind and np.allclose(q.omega, 2 * math.pi / periods) and np.allclose(q.headings, np.radians(headings))
    assert q.filled.all()
    assert np.allclose(q.T, T, rtol=1e-7, atol=1e-6)
    if kind == "difference":
        assert np.allclose(q.mean_drift(), np.stack([T[i, i][[0, 1], [0, 1]] for i in range(n)]).real)


def test_the_oc4_semis_difference_qtf_gives_a_real_mean_drift_that_pushes_with_the_waves():
    """RAFT's `marin_semi.12d` (28 of its periods kept): every period pair, the diagonal (the mean drift) real to the
    file's digits, the surge drift positive (down-wave) in every wave shorter than 10 s and at its largest tens of kN
    per square metre of amplitude (the semi's three 12 m columns and its 6.5 m one at the water line)."""
    q = read_qtf(SEMI, RHO, G)
    n = len(q.omega)
    assert n == 28 and q.filled.all() and q.kind == "difference"
    assert q.omega[0] == pytest.approx(2 * math.pi / 25.133, rel=1e-4) and q.omega[-1] == pytest.approx(2 * math.pi / 2.1299, rel=1e-4)
    diagonal = q.T[np.arange(n), np.arange(n), 0, 0]
    assert np.abs(diagonal.imag).max() < 1e-5 * np.abs(diagonal.real).max()
    surge = q.mean_drift()[:, 0, 0]
    short = q.omega > 2 * math.pi / 10.0
    assert (surge[short] > 0).all()
    assert 5e4 < surge.max() < 0.5 * RHO * G * (3 * 12.0 + 6.5)  # below a wall as wide as every column reflecting all
    assert np.allclose(q.T[..., 0, 0, 0], np.conj(q.T[..., 0, 0, 0]).T)


def test_a_cut_qtf_file_is_one_line(tmp_path):
    lines = SEMI.read_text().splitlines()
    cut = tmp_path / "cut.12d"
    cut.write_text("\n".join(lines[:-60]) + "\n")  # the last pairs' rows gone
    with pytest.raises(ConfigError, match=r"pairs of its 28 periods \(a cut file\?\)"):
        read_qtf(cut, RHO, G)
    with pytest.raises(ConfigError, match="a QTF file is WAMIT's .12d"):
        read_qtf(tmp_path / "other.8", RHO, G)


def test_a_qtf_file_cut_inside_a_pair_is_one_line(tmp_path):
    """The last pair of periods with one of its six modes gone: the pairs are all there, their rows are not."""
    lines = SEMI.read_text().splitlines()
    cut = tmp_path / "cut.12d"
    cut.write_text("\n".join(lines[:-1]) + "\n")
    with pytest.raises(ConfigError, match="some pairs of periods have 5 rows, others 6"):
        read_qtf(cut, RHO, G)
