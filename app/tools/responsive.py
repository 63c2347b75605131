"""`python -m app.tools.responsive`: at high resolution, does the viewer keep real time and the GUI stay responsive?

Starts the viewer in-process at N points per edge with a headless chromium client watching, then
measures over a window: the real-time factor, the lag of viser's event loop (a callback scheduled
every 50 ms from another thread: how long until it runs, i.e. whether the simulation thread starves
the server), and the click latency (a DOM click on Pause in the page; time until the simulation
thread has applied it: browser event, websocket, viser, command queue). Prints a markdown table. A benchmark, not a test: the machine is shared.
"""

from __future__ import annotations

import resource
import statistics
import sys
import threading
import time
from dataclasses import dataclass

import tyro

from app.args import ViewArgs
from app.main import start
from app.recording.browser import launch, missing


@dataclass
class ResponsiveArgs:
    points_per_edge: int = 50
    """Samples per face edge (6 N^2 samples)."""
    seconds: float = 20.0
    """Length of the measuring window."""
    clicks: int = 10
    """Pause clicks timed through the browser."""
    scene: str = "damped"


def event_loop_lags(server, seconds: float, period: float = 0.05) -> list[float]:
    loop = server.get_event_loop()
    lags = []
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        ran = threading.Event()
        stamp: list[float] = []
        t0 = time.perf_counter()
        loop.call_soon_threadsafe(lambda: (stamp.append(time.perf_counter()), ran.set()))
        ran.wait(5.0)
        lags.append(stamp[0] - t0 if stamp else 5.0)
        time.sleep(period)
    return lags


def main(args: ResponsiveArgs) -> int:
    from playwright.sync_api import sync_playwright

    if why := missing():
        print(f"floatsim: {why}", file=sys.stderr)
        return 2
    app = start(ViewArgs(scene=args.scene, port=0))
    try:
        app.controls.points_per_edge.value = args.points_per_edge
        snap = app.sync()
        with sync_playwright() as p:
            browser = launch(p)
            page = browser.new_page(viewport={"width": 800, "height": 600})
            page.set_default_timeout(120_000)
            page.goto(app.url + "/?fixedDpr=0.5")
            page.get_by_label("Pause").wait_for()
            time.sleep(3.0)
            cpu0, wall0 = resource.getrusage(resource.RUSAGE_SELF), time.monotonic()
            rates: list[float] = []
            sampler_stop = threading.Event()

            def sample_rates():
                while not sampler_stop.wait(0.5):
                    rates.append(app.latest().real_time_factor)

            sampler = threading.Thread(target=sample_rates, daemon=True)
            sampler.start()
            lags = event_loop_lags(app.server, args.seconds)
            sampler_stop.set()
            cpu1, wall1 = resource.getrusage(resource.RUSAGE_SELF), time.monotonic()
            latencies, server_side = [], []
            posted_at: list[float] = []
            post, apply = app.loop.post, app.loop._cmd_pause

            def timed_post(name, value=None):  # the GUI callback, on viser's thread pool, as the message arrives
                if name == "pause":
                    posted_at.append(time.perf_counter())
                post(name, value)

            def timed_apply(value):  # on the simulation thread
                apply(value)
                if posted_at:
                    server_side.append(time.perf_counter() - posted_at.pop())

            app.controls._post, app.loop._cmd_pause = timed_post, timed_apply
            checkbox = page.get_by_label("Pause")
            for _ in range(args.clicks):
                want = not app.loop.settings.paused
                t0 = time.perf_counter()
                checkbox.evaluate("el => el.click()")  # the DOM click itself (Playwright's click adds its own checks)
                while app.loop.settings.paused != want and time.perf_counter() - t0 < 10:
                    time.sleep(0.0005)
                latencies.append(time.perf_counter() - t0)
                time.sleep(0.3)
            browser.close()
        steps = [r for r in rates if r == r]
        cores = (cpu1.ru_utime + cpu1.ru_stime - cpu0.ru_utime - cpu0.ru_stime) / (wall1 - wall0)
        print(f"viewer at N = {args.points_per_edge} ({snap.body.n_samples} samples), scene {args.scene}, integrator {snap.settings.integrator}, "
              f"dt {snap.settings.dt:g} s, one chromium client; {args.seconds:g} s window")  # fmt: skip
        print()
        print("| measure | median | worst |")
        print("|---|---|---|")
        print(f"| real-time factor (asked 1) | {statistics.median(steps):.3f} | {min(steps):.3f} |")
        print(f"| viser event-loop lag (ms) | {statistics.median(lags) * 1e3:.2f} | {max(lags) * 1e3:.1f} |")
        print(
            f"| Pause click in the page -> applied by the simulation (ms) | {statistics.median(latencies) * 1e3:.0f} | {max(latencies) * 1e3:.0f} |"
        )
        print(
            f"| of which on the server: message in -> applied (ms) | {statistics.median(server_side) * 1e3:.2f} | {max(server_side) * 1e3:.1f} |"
        )
        print(f"| server process CPU (cores) | {cores:.2f} | |")
    finally:
        app.stop()
    return 0


if __name__ == "__main__":
    sys.exit(main(tyro.cli(ResponsiveArgs)))
