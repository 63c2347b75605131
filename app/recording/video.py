"""A recorded run as an MP4: each frame drawn by viser's own renderer (`client.get_render`) in a
headless chromium watching a private server that shows the take, encoded with PyAV (H.264).

A frame costs software WebGL (SwiftShader, no GPU here) time in proportion to the pixels it draws,
and the render comes at the page canvas's resolution: the page is opened at the video's size with a
pixel ratio that keeps about RENDER_PIXELS drawn (480 x 270), scaled up to the size asked for, without
the environment map and shadows. About 12 frames a second at 640 x 360 and 9 at 960 x 540 on this 2-core machine; with a
GPU, raise RENDER_PIXELS.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from fractions import Fraction
from pathlib import Path

from app.recording.browser import launch, missing
from app.recording.replay import FixedLayers, private_server, stage
from app.recording.take import Take
from sim.errors import ConfigError

RENDER_PIXELS = 130_000
SIZES = {"640x360": (360, 640), "960x540": (540, 960), "1280x720": (720, 1280)}
FRAMES_PER_SECOND = {"640x360": 12.0, "960x540": 9.0, "1280x720": 6.0}
"""Frames rendered and encoded per wall second at each size on a 2-core machine without a GPU (about; the start costs STARTUP_SECONDS)."""
STARTUP_SECONDS = 5.0
MAX_RENDER_SECONDS = 600.0
"""The viewer's Export video refuses a take whose render would take longer than this (the CLI's --video has no limit)."""


def check_video_tools() -> None:
    """ConfigError saying what is missing to export a video (before a long run, not after)."""
    if why := missing():
        raise ConfigError(f"cannot export video: {why}")
    try:
        import av  # noqa: F401
    except ImportError:
        raise ConfigError("cannot export video: PyAV is not installed (pip install -e '.[video]')") from None


def frame_count(take: Take, fps: float) -> int:
    return int(math.floor(take.duration * fps + 1e-9)) + 1


def render_seconds(take: Take, fps: float, size: str) -> float:
    """About how long rendering the take takes here, s (from its frame count)."""
    return STARTUP_SECONDS + frame_count(take, fps) / FRAMES_PER_SECOND[size]


def longest_take(fps: float = 30.0, size: str = "640x360", limit: float | None = None) -> float:
    """The longest take, s, whose render stays within `limit` (MAX_RENDER_SECONDS)."""
    return ((limit or MAX_RENDER_SECONDS) - STARTUP_SECONDS) * FRAMES_PER_SECOND[size] / fps


def check_render_time(take: Take, fps: float, size: str, limit: float | None = None) -> None:
    """ConfigError (one line, stating the limit) when rendering the take would take longer than `limit` (MAX_RENDER_SECONDS)."""
    limit = limit or MAX_RENDER_SECONDS
    estimate = render_seconds(take, fps, size)
    if estimate > limit:
        longest = longest_take(fps, size, limit)
        raise ConfigError(f"this {take.duration:.1f} s take is {frame_count(take, fps):,} frames at {fps:g} fps, about "
                          f"{estimate / 60:.1f} min to render here, over the limit of {limit / 60:.1f} min: record a take of at most "
                          f"{longest:.0f} s, or make the video with `floatsim run ... --video FILE` (no limit there)")  # fmt: skip


def render_video(take: Take, path: str | Path, fps: float = 30.0, size: str = "640x360", layers: FixedLayers | None = None,
                 progress: Callable[[int, int], None] | None = None) -> int:  # fmt: skip
    """Write the take as an H.264 MP4 at `fps`, `size` (WIDTHxHEIGHT); frame i shows the take at i / fps.
    Returns the number of frames. `progress(done, total)` is called after each frame."""
    import av
    from playwright.sync_api import sync_playwright

    check_video_tools()
    height, width = SIZES[size]
    total = frame_count(take, fps)
    with private_server() as server, sync_playwright() as p:
        view = stage(server, take, layers)
        server.scene.configure_environment_map(hdri=None)  # both cost software rendering more than they add
        server.scene.configure_default_lights(enabled=True, cast_shadow=False)
        browser = launch(p)
        try:
            page = browser.new_page(viewport={"width": width, "height": height})
            ratio = min(1.0, math.sqrt(RENDER_PIXELS / (width * height)))
            page.goto(f"http://127.0.0.1:{server.get_port()}/?fixedDpr={ratio:.3f}")
            deadline = time.monotonic() + 60.0
            while not server.get_clients():
                if time.monotonic() > deadline:
                    raise RuntimeError("the headless browser did not connect within 60 s")
                time.sleep(0.05)
            client = next(iter(server.get_clients().values()))
            time.sleep(1.0)  # the first scene arrives
            with av.open(str(path), "w") as container:
                stream = container.add_stream("libx264", rate=Fraction(fps).limit_denominator(1001))  # 29.97 as 30000/1001
                stream.width, stream.height, stream.pix_fmt = width, height, "yuv420p"
                try:
                    for i in range(total):
                        t = i / fps
                        view.show(take.at(t), now=t)
                        image = client.get_render(height, width, transport_format="jpeg", timeout=60.0)
                        for packet in stream.encode(av.VideoFrame.from_ndarray(image, format="rgb24")):
                            container.mux(packet)
                        if progress is not None:
                            progress(i + 1, total)
                finally:  # interrupted too: the frames so far make a playable, shorter video
                    for packet in stream.encode():
                        container.mux(packet)
        finally:
            browser.close()
    return total
