"""Shared test setup: floating-point errors fail loudly (underflow to zero is fine); kernels compiled first;
the browser (Debian chromium through Playwright) for the tests that need one."""

import os

import numpy as np
import pytest


@pytest.hookimpl(tryfirst=True)  # before pytest-xdist starts its workers: their output is not shown
def pytest_sessionstart(session):
    """Compile (fresh clone) the numba kernels of the covering set (tests/covering.py: the presets' and a few more)
    once, before any test times anything, in two child processes at once (this machine's two cores), saying so on the
    terminal line by line: a cold run is minutes of compiling, and a silent one looks hung. Compiled here rather than
    in the tests that first need them: two xdist workers would each compile the same one."""
    if hasattr(session.config, "workerinput"):
        return  # an xdist worker: the controller did it
    _compile_covering(session.config.pluginmanager.get_plugin("terminalreporter"))


CHILDREN = 2
"""Processes compiling the covering set side by side (this project's machines have two cores)."""


def _compile_covering(terminal=None) -> None:
    from sim.compiling import default_backend

    if default_backend() != "numba":
        return
    import fcntl
    import selectors
    import subprocess
    import sys
    import time

    from sim.compile_estimate import compile_seconds, shares_of, slowness, spec_cpu
    from sim.compiling import cached, parse_spec, spec_argument
    from sim.kernels import KERNEL_CACHE
    from tests.covering import compiled_first

    say = terminal.write_line if terminal is not None else print
    specs = compiled_first()
    os.makedirs(KERNEL_CACHE, exist_ok=True)
    with open(os.path.join(KERNEL_CACHE, ".tests.lock"), "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes: one compile for concurrent runs
        todo = [spec_argument(spec) for spec in specs if not cached(spec)]
        if not todo:
            return
        started = time.monotonic()
        factor, shares = slowness(), shares_of([parse_spec(word) for word in todo], CHILDREN)
        cpu, wall = sum(compile_seconds(share, factor) for share in shares), max(compile_seconds(share, factor) for share in shares)
        say(f"floatsim: compiling the numba kernels of {len(todo)} specialisations (the presets' and those the tests cover) in {len(shares)} processes, once per machine "
            f"(cached in {KERNEL_CACHE}; about {cpu:.0f} s of this machine's CPU, {wall:.0f} s on {len(shares)} free cores); the tests start after")  # fmt: skip
        # each child takes the next spec as it finishes one, the longest first: two cores busy to the end
        todo.sort(key=lambda word: -spec_cpu(parse_spec(word)))
        queue = list(todo)
        children = [subprocess.Popen([sys.executable, "-m", "sim.commands.compile", str(os.getpid()), "-"], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, text=True) for _ in range(min(CHILDREN, len(todo)))]  # fmt: skip
        watch = selectors.DefaultSelector()
        for child in children:
            watch.register(child.stdout, selectors.EVENT_READ, child)
            _hand(child, queue)
        done, open_pipes = 0, len(children)
        while open_pipes:
            for key, _ in watch.select():
                line = key.fileobj.readline()
                if not line:
                    watch.unregister(key.fileobj)
                    open_pipes -= 1
                    continue
                if line.startswith("floatsim: compiled"):
                    done += 1
                    _hand(key.data, queue)
                say(f"[{done}/{len(todo)}] {line.rstrip()}")
        for child in children:
            assert child.wait() == 0, "the kernels did not compile"
        say(f"floatsim: the kernels are ready after {time.monotonic() - started:.0f} s (others compile only under -m exhaustive, "
            "in the tests that first need them)")  # fmt: skip


def _hand(child, queue: list) -> None:
    """Give the compiling child the next spec of the queue, or close its input when none is left (it then exits)."""
    if queue:
        child.stdin.write(queue.pop(0) + "\n")
        child.stdin.flush()
    else:
        child.stdin.close()


@pytest.fixture(scope="session", autouse=True)
def _compiled_kernels():
    """Load the presets' kernels into this process (a worker) from the disk cache before any test times anything
    (the covering set compiled first if pytest_sessionstart did not run here: pytest started without this conftest's hooks)."""
    from sim.compiling import default_backend

    if default_backend() != "numba":
        return
    from sim.commands.compile import preset_specs
    from sim.compiling import warm_up

    _compile_covering()
    for spec in preset_specs():
        warm_up(spec)  # from the disk cache


@pytest.fixture(autouse=True)
def _covered_kernels_only(request, monkeypatch):
    """Outside -m exhaustive a test's simulations load only the covering set's kernels (tests/covering.py): any other
    compiles for a minute on a cold cache, in the middle of the default run."""
    if request.node.get_closest_marker("exhaustive") or request.node.get_closest_marker("slow"):
        return  # (the slow tests, run after the exhaustive ones, may load any: each is minutes anyway)
    import sim.kernels
    from tests.covering import covered

    load = sim.kernels.specialised

    def covered_only(spec):
        if not covered(spec):
            pytest.fail(f"the kernels for the {spec.describe()} are not in the default run's covering set (tests/covering.py): "
                        "use covered ones, or mark the case exhaustive (covering.cases)")  # fmt: skip
        return load(spec)

    monkeypatch.setattr(sim.kernels, "specialised", covered_only)  # (tests calling specialised directly imported their own)


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
    from app.recording.browser import launch, missing

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
