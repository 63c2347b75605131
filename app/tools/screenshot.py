"""`python -m app.tools.screenshot`: the viewer as a newcomer sees it, in a 1280x800 headless chromium
(README's picture; also the check that the panel leaves the body in view)."""

from __future__ import annotations

import contextlib
import io
import sys
import time
from dataclasses import dataclass

import tyro

from app.args import ViewArgs
from app.main import start
from app.recording.browser import launch, missing


@dataclass
class ShotArgs:
    """Save a screenshot of the viewer on a scene."""

    out: str = "reports/viewer-1280x800.png"
    scene: str = "damped"
    width: int = 1280
    height: int = 800
    wait: float = 6.0
    """Seconds after the page loads (the drop is under way)."""
    tab: str = ""
    """Open this tab of the panel first (e.g. Live: the numbers and plots)."""


def main(args: ShotArgs) -> int:
    if why := missing():
        print(f"app.tools.screenshot: {why}", file=sys.stderr)
        return 1
    from playwright.sync_api import sync_playwright

    with contextlib.redirect_stdout(io.StringIO()):
        app = start(ViewArgs(scene=args.scene, port=0))
    try:
        with sync_playwright() as p:
            browser = launch(p)
            page = browser.new_page(viewport={"width": args.width, "height": args.height})
            page.goto(app.url + "/?fixedDpr=0.75", timeout=60_000)
            page.wait_for_selector("canvas", timeout=60_000)
            if args.tab:
                page.get_by_role("tab", name=args.tab).click()
            time.sleep(args.wait)
            for close in page.locator(".mantine-Notification-closeButton").all():  # the software-WebGL toast
                close.click()
            time.sleep(0.5)
            page.screenshot(path=args.out)
            browser.close()
    finally:
        with contextlib.redirect_stdout(io.StringIO()):
            app.stop()
    print(f"{args.out}: the viewer on '{args.scene}' at {args.width}x{args.height}")
    return 0


if __name__ == "__main__":
    sys.exit(main(tyro.cli(ShotArgs)))
