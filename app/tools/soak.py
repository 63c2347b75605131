"""Soak benchmark (not a unit test): the viewer on a scene with a headless browser watching, for minutes.

    python -m app.tools.soak --minutes 10

This process is the server (viewer + simulation thread); the browser is Debian's chromium driven
by Playwright from a child process, so the RSS sampled here is the server's alone. Every
`--every` seconds it prints RSS, the real-time factor and viser's broadcast buffer size, then a
summary: start/end RSS, largest growth, median and minimum real-time factor.
"""

from __future__ import annotations

import math
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import tyro

from app.args import ViewArgs
from app.main import start
from app.recording.browser import launch


@dataclass
class SoakArgs:
    """Run the viewer with a headless browser client and sample memory and speed."""

    minutes: float = 10.0
    """How long to run."""
    every: float = 10.0
    """Seconds between samples."""
    scene: str = "damped"
    """Scene preset or .toml path."""
    speed: float = 1.0
    """Simulation speed (x real time)."""
    points_per_edge: int | None = None
    """Samples per edge of a cube or box (the scene's own without it), as the viewer's slider sets it."""
    browser: bool = True
    """Connect a headless chromium client (needs /usr/bin/chromium and playwright)."""
    record: bool = False
    """Record the whole run as the Record button does (then writes the replay to a temporary folder): compare the CPU line with and without."""


def rss_mib(pid: str = "self") -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return math.nan


def browse(url: str, seconds: float) -> None:
    """The child process: keep one page open on the viewer (small viewport, as a laptop tab would be throttled to)."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = launch(p)
        page = browser.new_page(viewport={"width": 800, "height": 600})
        page.goto(url + "/?fixedDpr=0.5", timeout=60_000)
        page.wait_for_selector("canvas", timeout=60_000)
        print("browser: page loaded", flush=True)
        time.sleep(seconds)
        browser.close()


def main(args: SoakArgs) -> int:

    app = start(ViewArgs(scene=args.scene, port=0))
    app.controls.speed.value = args.speed
    if args.points_per_edge is not None:
        app.controls.points_per_edge.value = args.points_per_edge
    duration = args.minutes * 60.0
    child = None
    if args.browser:
        child = subprocess.Popen([sys.executable, "-c", f"from app.tools.soak import browse; browse({app.url!r}, {duration + 30.0!r})"])
        deadline = time.monotonic() + 90
        while not app.server.get_clients() and time.monotonic() < deadline:
            time.sleep(0.5)
        if not app.server.get_clients():
            print("soak: the browser did not connect", file=sys.stderr)
            child.kill()
            app.stop()
            return 1
    if args.record:
        app.recorder.folder = Path(tempfile.mkdtemp(prefix="floatsim-soak-"))
        app.recorder.start()
    buffer = app.server._websock_server._broadcast_buffer  # viser internals: only to watch for unbounded growth
    print(f"soak: {app.url}, scene {args.scene}, {args.minutes:g} min, browser {'on' if child else 'off'}")
    print(f"{'wall s':>7} {'RSS MiB':>8} {'RTF':>6} {'behind':>6} {'sim t':>8} {'steps':>8} {'clients':>7} {'buffered':>8}")
    rows = []
    started, cpu_started = time.monotonic(), time.process_time()
    try:
        while True:
            wall = time.monotonic() - started
            snap = app.latest()
            row = (
                wall,
                rss_mib(),
                snap.real_time_factor,
                snap.behind,
                snap.frame.t,
                snap.steps,
                len(app.server.get_clients()),
                len(buffer.message_from_id),
            )
            rows.append(row)
            print(f"{row[0]:7.0f} {row[1]:8.1f} {row[2]:6.3f} {row[3]!s:>6} {row[4]:8.1f} {row[5]:8d} {row[6]:7d} {row[7]:8d}", flush=True)
            if wall >= duration:
                break
            time.sleep(min(args.every, max(0.0, duration - wall)))
    except KeyboardInterrupt:
        pass
    finally:
        cpu = (time.process_time() - cpu_started) / max(time.monotonic() - started, 1e-9)
        files = app.recorder.stop() if args.record else {}
        app.stop()
        if child is not None:
            child.kill()
    rss = [r[1] for r in rows]
    rates = [r[2] for r in rows[1:] if math.isfinite(r[2])] or [math.nan]
    wall, t = rows[-1][0] - rows[0][0], rows[-1][4] - rows[0][4]
    print()
    print("| measure | value |")
    print("|---|---|")
    print(f"| duration | {wall / 60:.1f} min, {len(rows)} samples, browser {'connected' if child else 'off'} |")
    print(f"| RSS start / end | {rss[0]:.1f} / {rss[-1]:.1f} MiB |")
    print(f"| max RSS growth | {max(rss) - rss[0]:+.1f} MiB |")
    print(f"| real-time factor median / min | {statistics.median(rates):.3f} / {min(rates):.3f} (asked {args.speed:g}) |")
    print(f"| overall sim time / wall time | {t / wall if wall > 0 else math.nan:.3f} |")
    print(f"| samples flagged behind | {sum(r[3] for r in rows)} of {len(rows)} |")
    print(f"| server CPU (all threads) | {cpu:.3f} s per wall s |")
    if args.record:
        html = files.get("html")
        print(f"| recording | {'on: ' + f'{html.stat().st_size / 1e6:.2f} MB replay' if html else 'on, nothing written'} |")
    return 0


if __name__ == "__main__":
    sys.exit(main(tyro.cli(SoakArgs)))
