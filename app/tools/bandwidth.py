"""Bytes a second the viewer sends one page (not a unit test): a page spoken over viser's own protocol (app/tools/page.py)
connects, sends its camera as a browser does, and counts the compressed frames it receives after a warm-up.

    python -m app.tools.bandwidth --scene storm --seconds 20
"""

from __future__ import annotations

import asyncio
import sys
import time
from dataclasses import dataclass

import tyro

from app.args import ViewArgs
from app.main import start
from app.tools.page import Page


@dataclass
class BandwidthArgs:
    """Measure what one page of the viewer receives a second."""

    scene: str = "storm"
    """Scene preset or .toml path."""
    seconds: float = 20.0
    """How long to count, after the warm-up."""
    warmup: float = 5.0
    """Seconds left out first (the page's initial scene and GUI)."""


async def measure(port: int, warmup: float, seconds: float) -> tuple[int, float]:
    """(bytes received, seconds counted) by one page over `seconds` after `warmup`."""

    async with Page.open(port) as page:
        await page.camera()
        received, started, end = 0, None, time.monotonic() + warmup + seconds
        while (now := time.monotonic()) < end:
            try:
                frame = await asyncio.wait_for(page.ws.recv(), timeout=0.5)
            except asyncio.TimeoutError:
                continue
            if now - (end - seconds) >= 0:
                started = now if started is None else started
                received += len(frame)
        return received, time.monotonic() - (started or time.monotonic())


def main(args: BandwidthArgs) -> int:

    app = start(ViewArgs(scene=args.scene, port=0))
    try:
        received, counted = asyncio.run(measure(app.port, args.warmup, args.seconds))
        t = app.latest().frame.t
    finally:
        app.stop()
    print(
        f"bandwidth: scene {args.scene}: {received / counted / 1e6:.3f} MB/s to one page ({received} bytes in {counted:.1f} s; sim t {t:.1f} s)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main(tyro.cli(BandwidthArgs)))
