"""Shared test setup: floating-point errors fail loudly (underflow to zero is fine); kernels compiled first."""

import numpy as np
import pytest


@pytest.fixture(scope="session", autouse=True)
def _compiled_kernels():
    """Compile (fresh clone) or load the numba kernels once, before any test times anything."""
    from sim.simulation import default_backend

    if default_backend() == "numba":
        from sim.kernels import warm_up

        warm_up()


@pytest.fixture(autouse=True)
def _fp_errors_raise():
    old = np.seterr(all="raise", under="ignore")
    yield
    np.seterr(**old)
