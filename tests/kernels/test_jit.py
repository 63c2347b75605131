"""How kernels compile (sim/kernels/jit.py): a kernel called by another is a part of its caller only, never compiled
alone; from Python it is a numba dispatcher; a wrong slice assignment raises numba's plain error."""

import numpy as np
import pytest

from sim.kernels.jit import Kernel, njit

OPTIONS = {"cache": False, "error_model": "numpy"}


def test_a_kernel_called_by_a_kernel_is_compiled_into_its_caller_only():
    """The caller's result is the Python function's; the callee has no compiled code of its own (no overload, so no
    machine code, wrapper or cache file) until Python calls it, when it compiles as a dispatcher and agrees."""

    @njit(**OPTIONS)
    def weight(x, k):
        return np.sum(x**2) * k + 1.0 / k  # (error_model numpy: 1/0 is inf, not an exception)

    @njit(**OPTIONS)
    def total(xs, k):
        s = 0.0
        for i in range(xs.shape[0]):
            s += weight(xs[i], k)
        return s

    assert isinstance(weight, Kernel) and isinstance(total, Kernel)
    xs = np.arange(12.0).reshape(4, 3)
    expected = sum(float(np.sum(x**2)) * 3 + 1 / 3 for x in xs)
    assert total(xs, 3) == pytest.approx(expected, rel=1e-15)
    assert len(total.overloads) == 1 and len(weight.overloads) == 0
    assert weight(xs[0], 0) == np.inf  # the caller's error model, from Python too
    assert len(weight.overloads) == 1
    assert total(xs, 2.5) == pytest.approx(sum(float(np.sum(x**2)) * 2.5 + 0.4 for x in xs), rel=1e-15)  # other types: compiled again


def test_a_slice_assigned_from_an_array_of_another_size_raises_numbas_plain_error():
    @njit(**OPTIONS)
    def put(a, b):
        a[0:3] = b
        return a

    np.testing.assert_array_equal(put(np.zeros(4), np.ones(3)), [1.0, 1.0, 1.0, 0.0])
    with pytest.raises(ValueError, match="cannot assign slice from input of different size"):
        put(np.zeros(4), np.ones(2))
