"""Shared test setup: floating-point errors fail loudly (underflow to zero is fine); kernels compiled first;
the browser (Debian chromium through Playwright) for the tests that need one."""

import os

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


def _require(ok: bool, reason: str) -> None:
    if not ok:
        if os.environ.get("CI"):
            pytest.fail(f"{reason} (CI is set: the browser test must run)")
        pytest.skip(reason)


@pytest.fixture
def browser_page():
    from app.browser import launch, missing

    why = missing()
    _require(why is None, why or "")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = launch(p)
        try:
            page = browser.new_page(viewport={"width": 800, "height": 600})
            page.set_default_timeout(60_000)
            yield page
        finally:
            browser.close()
