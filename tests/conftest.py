"""Shared test setup: floating-point errors fail loudly (underflow to zero is fine)."""

import numpy as np
import pytest


@pytest.fixture(autouse=True)
def _fp_errors_raise():
    old = np.seterr(all="raise", under="ignore")
    yield
    np.seterr(**old)
