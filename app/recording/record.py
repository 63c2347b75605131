"""`floatsim run` with the viewer's outputs: `--record run.html` (a replay that opens offline) and
`--video run.mp4 [--fps 30] [--video-size 640x360]`. Registered as the `run` plugin of `floatsim`, it
extends sim's headless run (which knows nothing of viser) with a recorder watching it."""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from app.recording.take import Take, shot_of
from sim.commands.interrupt import EXIT
from sim.commands.output import write_whole
from sim.commands.progress import progress_bar
from sim.commands.run import RunArgs, check_output, scene_from_args
from sim.commands.run import run as headless_run
from sim.errors import ConfigError, WriteFailed


@dataclass
class RecordArgs(RunArgs):
    """Run a scene headless and write its trajectory to CSV; optionally a replay page and a video. Flags override the scene."""

    record: str | None = None
    """Write a self-contained HTML replay of the run (opens offline: play, pause, seek), e.g. run.html."""
    video: str | None = None
    """Write an MP4 video of the run, rendered by the viewer's own renderer in headless chromium, e.g. run.mp4."""
    fps: float = 30.0
    """Frames per second of the replay and the video."""
    video_size: Literal["640x360", "960x540", "1280x720"] = "640x360"
    """Video frame size, WIDTHxHEIGHT."""


class Recorder:
    """Takes a shot of the run every `every` steps (the `watch` of sim's run)."""

    def __init__(self, every: int):
        self.every = every
        self.take = Take()
        self.full = False

    def __call__(self, simulation) -> None:
        if not self.full and not self.take.add(shot_of(simulation)):
            self.full = True


def run(args: RecordArgs) -> int:
    if not args.record and not args.video:
        return headless_run(args)
    check_output(args.record, "record", ".html")
    check_output(args.video, "video", ".mp4")
    if not 1.0 <= args.fps <= 120.0:
        raise ConfigError(f"--fps must be in 1..120, got {args.fps:g}")
    if args.video:
        from app.recording.video import check_video_tools  # viser and PyAV (.[video]) only for a run that records

        check_video_tools()  # before the run, not after it
    dt = float(scene_from_args(args).step.dt)
    recorder = Recorder(max(1, round(1.0 / (args.fps * dt))))
    status = headless_run(args, watch=recorder)
    if status in (EXIT, 2):  # Ctrl-C or a CSV that could not be written (said): no replay or video of a run cut short
        return status
    take = recorder.take
    if recorder.full:
        print(
            f"floatsim: note: the replay and video stop at {take.duration:.4g} s ({len(take)} frames, the most a take keeps)",
            file=sys.stderr,
        )
    for write in (write_replay, write_video):
        failed = write(args, take)
        if failed is not None:
            return failed
    return status


def csv_note(args: RecordArgs) -> str:
    return "; the CSV is whole" if args.out else ""


def write_replay(args: RecordArgs, take: Take) -> int | None:
    """The replay page, if asked (whole or absent: a full disk leaves no half page); an exit status if it failed."""
    if not args.record:
        return None
    from app.recording.replay import replay_html  # viser only for a run that records

    html = replay_html(take)
    try:
        write_whole(args.record, lambda tmp: Path(tmp).write_text(html))
    except WriteFailed as e:
        print(f"floatsim: {e} (no replay written{csv_note(args)})", file=sys.stderr)
        return 2
    print(f"replay: {len(take)} frames over {take.duration:.4g} s -> {args.record} ({len(html) / 1e6:.2f} MB; opens offline in a browser)")
    return None


def write_video(args: RecordArgs, take: Take) -> int | None:
    """The video, if asked: rendered aside and renamed, so a full disk leaves no half video under its name (Ctrl-C
    after a frame keeps the frames so far, which play); an exit status if it failed or was stopped."""
    if not args.video:
        return None
    from app.recording.video import frame_count, render_video  # viser and PyAV (.[video]) only for a run that records

    bar = progress_bar(frame_count(take, args.fps), flag=args.progress, unit="frame")
    written = [0]

    def advanced(done: int, total: int) -> None:
        written[0] = done
        bar.update(1)

    def render(tmp: str) -> int | None:
        try:
            return render_video(take, tmp, args.fps, args.video_size, progress=advanced)
        except KeyboardInterrupt:
            if not written[0]:
                raise
            return None  # renamed like a whole video
        except OSError as e:
            if e.filename != tmp:  # not the file's: the browser's or the server's, a failure of the video's making
                raise RuntimeError(f"{type(e).__name__}: {e}") from None
            raise

    try:
        n = write_whole(args.video, render, suffix=".mp4")
    except KeyboardInterrupt:
        print("floatsim: video interrupted before its first frame: no video written", file=sys.stderr)
        return 130
    except WriteFailed as e:
        print(f"floatsim: {e} (no video written{csv_note(args)})", file=sys.stderr)
        return 2
    except Exception as e:  # noqa: BLE001 -- the run and its other outputs are kept; say why the video is not
        print(f"floatsim: video failed: {type(e).__name__}: {e}", file=sys.stderr)
        return 4
    finally:
        bar.close()
    if n is None:
        print(f"floatsim: video interrupted: the first {written[0]} frames are in {args.video}", file=sys.stderr)
        return 130
    print(f"video: {n} frames at {args.fps:g} fps, {args.video_size} -> {args.video}")
    return None


if __name__ == "__main__":
    from sim.commands import dispatch

    sys.exit(dispatch({"run": "app.recording.record:run"}))
