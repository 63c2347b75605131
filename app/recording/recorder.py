"""Record and share from the viewer: Record / Stop keeps the published snapshots as a take; stopping
writes the replay page (app/recording/replay.py) and the run's CSV into `floatsim-recordings/` and hands both to
the browser that asked; "Export video" renders the last take to MP4 (app/recording/video.py) with a progress bar.

`capture` runs on the simulation thread and only appends; everything slow runs on the callback's thread
or a worker thread, never on the simulation's.

The folder is bounded: at most KEPT_TAKES takes and KEPT_BYTES, the oldest takes removed first (only
files named as the recorder names them); a take never overwrites another (two in one second get
`-2`, `-3`...)."""

from __future__ import annotations

import re
import threading
import time
from collections.abc import Callable
from pathlib import Path

import viser

from app.recording.replay import replay_html
from app.recording.take import MAX_SHOTS, Take
from app.recording.video import MAX_RENDER_SECONDS, check_render_time, check_video_tools, longest_take, render_video

KEPT_TAKES = 30
KEPT_BYTES = 1_000_000_000
"""The recordings folder keeps at most this many takes (replay, CSV, video) and bytes; the oldest go first."""
TAKE_FILE = re.compile(r"(floatsim-\d{8}-\d{6}(?:-\d+)?)\.(html|csv|mp4)")


def stamp() -> str:
    return time.strftime("%Y%m%d-%H%M%S")


def new_take_files(folder: Path) -> dict[str, Path]:
    """Names for a new take's replay and CSV that no file has: the time to the second, then -2, -3, ...
    The replay is created empty at once (exclusively), so two takes never get the same name."""
    base = f"floatsim-{stamp()}"
    for n in range(1, 1000):
        name = base if n == 1 else f"{base}-{n}"
        files = {kind: folder / f"{name}.{kind}" for kind in ("html", "csv")}
        if any(folder.joinpath(f"{name}.{kind}").exists() for kind in ("csv", "mp4")):
            continue
        try:
            files["html"].open("x").close()
        except FileExistsError:
            continue
        return files
    raise FileExistsError(f"too many recordings named {base}-N in {folder}")


def prune_recordings(folder: Path, keep: set[str], takes: int | None = None, size: int | None = None) -> list[Path]:
    """Remove the oldest takes' files until at most `takes` (KEPT_TAKES) takes and `size` (KEPT_BYTES)
    bytes are left; never a take named in `keep` (file stems), nor a file the recorder did not name."""
    takes, size = takes or KEPT_TAKES, size or KEPT_BYTES
    groups: dict[str, list[Path]] = {}
    for path in folder.iterdir():
        match = TAKE_FILE.fullmatch(path.name)
        if match and path.is_file() and not path.is_symlink():
            groups.setdefault(match.group(1), []).append(path)
    sizes = {name: sum(p.stat().st_size for p in files) for name, files in groups.items()}
    newest = {name: max(p.stat().st_mtime for p in files) for name, files in groups.items()}
    count, total = len(keep & set(groups)), sum(sizes[name] for name in keep & set(groups))
    removed = []
    for name in sorted(set(groups) - keep, key=lambda name: (newest[name], name), reverse=True):
        if count < takes and total + sizes[name] <= size:
            count, total = count + 1, total + sizes[name]
            continue
        for path in groups[name]:
            try:
                path.unlink()
                removed.append(path)
            except OSError:
                pass  # gone already: the bound is best effort
    return removed


class RecordPanel:
    def __init__(self, server: viser.ViserServer, notify: Callable[[str, object, bool], None], folder: Path | None = None,
                 new_take: Callable[[], Take] = Take):  # fmt: skip
        """new_take: what a recording keeps (app/recording/take.py)."""
        gui = server.gui
        self.server, self._notify, self._new_take = server, notify, new_take
        self.folder = folder or Path.cwd() / "floatsim-recordings"
        self._lock = threading.Lock()
        self._take: Take | None = None  # being recorded
        self.last: Take | None = None  # the last finished take
        self.files: dict[str, Path] = {}  # kind -> file of the last take
        self._exporting = False
        with gui.add_folder("Record and share"):
            self.record = gui.add_button("Record", icon=viser.Icon.PLAYER_RECORD, color="red",
                                         hint=f"Record the run (up to {MAX_SHOTS // 30 // 60} min); Stop writes a replay page and a CSV")  # fmt: skip
            self.status = gui.add_markdown("Nothing recorded yet.")
            self.replay = gui.add_button("Download replay (HTML)", icon=viser.Icon.DOWNLOAD, disabled=True,
                                         hint="One self-contained page: opens offline, play, pause and seek")  # fmt: skip
            self.csv = gui.add_button("Download CSV", icon=viser.Icon.TABLE, disabled=True, hint="The recorded run, one row per frame")
            self.video = gui.add_button("Export video (MP4)", icon=viser.Icon.MOVIE, disabled=True,
                                        hint=f"Render the recording to MP4 (headless chromium on the server); refused when that would "
                                             f"take over {MAX_RENDER_SECONDS / 60:.0f} min (a take of about {longest_take() / 60:.0f} min)")  # fmt: skip
            self.progress = gui.add_progress_bar(0.0, visible=False)
        self.record.on_click(lambda event: self.toggle(event.client))
        self.replay.on_click(lambda event: self._send(event.client, "html"))
        self.csv.on_click(lambda event: self._send(event.client, "csv"))
        self.video.on_click(lambda event: self.export_video(event.client))

    @property
    def recording(self) -> bool:
        return self._take is not None

    def capture(self, snap) -> None:
        """Simulation thread: keep the snapshot while recording; a full take stops itself (on a worker)."""
        take = self._take
        if take is not None and not take.add(snap):
            with self._lock:  # the first full shot stops it, once
                full, self._take = self._take, None
            if full is not None:
                threading.Thread(target=self._finish, args=(full, None), name="floatsim-record-stop", daemon=True).start()

    def toggle(self, client=None) -> None:
        if self.recording:
            self.stop(client)
        else:
            self.start()

    def start(self) -> None:
        with self._lock:
            self._take = self._new_take()
        self.record.label, self.record.icon = "Stop recording", viser.Icon.PLAYER_STOP
        self.status.content = "**● Recording…** press *Stop recording* to keep it."

    def stop(self, client=None) -> dict[str, Path]:
        """Finish the take: write replay and CSV, offer them to `client`. Returns the files written."""
        with self._lock:
            take, self._take = self._take, None
        return self._finish(take, client)

    def _finish(self, take, client) -> dict[str, Path]:
        self.record.label, self.record.icon = "Record", viser.Icon.PLAYER_RECORD
        if take is None or not len(take):
            self.status.content = "Nothing recorded (the run was paused?)."
            return {}

        self.status.content = f"Writing the replay of {take.duration:.1f} s…"
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
            files = new_take_files(self.folder)
            files["html"].write_text(replay_html(take))
            files["csv"].write_text(take.csv())
            self._prune(files)
        except OSError as e:
            self.status.content = f"**Could not write the recording**: {e.strerror or e} ({self.folder})."
            return {}
        self.last, self.files = take, files
        for button in (self.replay, self.csv, self.video):
            button.disabled = False
        size = files["html"].stat().st_size / 1e6
        self.status.content = f"Recorded {take.duration:.1f} s ({len(take)} frames): `{files['html']}` ({size:.2f} MB) and its CSV."
        if client is not None:
            self._send(client, "html")
            self._send(client, "csv")
        return files

    def _prune(self, files: dict[str, Path]) -> None:
        """Bound the folder, keeping the take just written and the last one (a video may be exporting from it)."""
        keep = {p.stem for p in files.values()} | {p.stem for p in self.files.values()}
        prune_recordings(self.folder, keep)

    def _send(self, client, kind: str) -> None:
        path = self.files.get(kind)
        if client is None or path is None:
            return
        try:
            client.send_file_download(path.name, path.read_bytes(), save_immediately=True)
        except OSError as e:
            self._notify(f"Cannot read {path}: {e.strerror}", client, True)

    def export_video(self, client=None, fps: float = 30.0, size: str = "640x360") -> Path | None:
        """Render the last take to MP4 beside its replay; offer it to `client`. One export at a time."""

        with self._lock:
            if self._exporting or self.last is None:
                return None
            self._exporting = True
        files, take = self.files, self.last  # a take recorded meanwhile keeps its own files
        path = files["html"].with_suffix(".mp4")
        self.video.disabled = True
        self.progress.value, self.progress.visible = 0.0, True
        try:
            check_render_time(take, fps, size)
            check_video_tools()
            self.status.content = "Rendering the video…"
            render_video(take, path, fps, size, progress=lambda done, total: setattr(self.progress, "value", 100.0 * done / total))
        except Exception as e:  # noqa: BLE001 -- ConfigError, the browser's, the encoder's: said in the panel, never a traceback
            self._notify(f"Video not exported: {e}", client, True)
            self.status.content = f"Video not exported: {e}"
            return None
        finally:
            self.progress.visible = False
            self.video.disabled = False
            with self._lock:
                self._exporting = False
        files["mp4"] = path
        self.status.content = f"Video: `{path}` ({path.stat().st_size / 1e6:.2f} MB)."
        self._prune(files)
        if client is not None and files is self.files:
            self._send(client, "mp4")
        return path
