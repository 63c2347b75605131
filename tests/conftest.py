"""Shared test setup: floating-point errors fail loudly (underflow to zero is fine); kernels compiled first;
the browser (Debian chromium through Playwright) for the tests that need one."""

import os

import numpy as np
import pytest


@pytest.fixture(scope="session", autouse=True)
def _compiled_kernels():
    """Compile (fresh clone) or load the presets' numba kernels once, before any test times anything: in two
    child processes at once (this machine's two cores), once for all pytest-xdist workers (a file lock).
    Other specialisations compile where a test first needs them."""
    from sim.simulation import default_backend

    if default_backend() != "numba":
        return
    import fcntl
    import subprocess
    import sys

    from sim.compiling import preset_specs, spec_argument
    from sim.kernels import KERNEL_CACHE, cached, warm_up

    specs = preset_specs()
    os.makedirs(KERNEL_CACHE, exist_ok=True)
    with open(os.path.join(KERNEL_CACHE, ".tests.lock"), "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
        todo = [spec_argument(spec) for spec in specs if not cached(spec)]
        children = [
            subprocess.Popen([sys.executable, "-m", "sim.compiling", str(os.getpid()), *todo[i::2]]) for i in range(2) if todo[i::2]
        ]
        for child in children:
            assert child.wait() == 0, "the presets' kernels did not compile"
    for spec in specs:
        warm_up(spec)  # from the disk cache


@pytest.hookimpl(tryfirst=True)  # before pytest-xdist reads the groups
def pytest_collection_modifyitems(items):
    """One real browser at a time (`--dist loadgroup` in the pytest options): two chromiums drawing with
    software WebGL on two cores starve each other's pages and the servers they talk to."""
    for item in items:
        if "browser_page" in getattr(item, "fixturenames", ()):
            item.add_marker(pytest.mark.xdist_group("browser"))


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
