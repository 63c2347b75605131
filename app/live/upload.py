"""Load your own body: an upload control for STL, OBJ or PLY. The file is read and checked on the
callback's thread (sim.bodies.body.load_mesh: a mesh, closed, at most 200 000 triangles, a plausible size in
the unit chosen); a good one is kept on disk and handed to the simulation thread as a command, a bad
one gets its one-line reason in the panel and the running scene is untouched. The bytes are capped
as they arrive (app/guards/upload_guard.py) and the folder kept uploads go to is bounded (`prune_uploads`)."""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import viser

from sim.bodies.body import MAX_MESH_BYTES, MAX_TRIANGLES, MESH_FORMATS, UNITS, load_mesh, printable
from sim.errors import ConfigError

UPLOADS = Path.home() / ".cache" / "floatsim" / "uploads"
MAX_BYTES = MAX_MESH_BYTES
"""A larger file is refused as it arrives (app/guards/upload_guard.py), before parsing (a 200 000-triangle binary STL is 10 MB)."""
KEPT_FILES = 20
KEPT_BYTES = 200_000_000
"""The uploads folder keeps at most this many files and bytes: the oldest go first, never the running body's."""


def keep_upload(name: str, content: bytes, folder: Path | None = None, running: str | None = None) -> Path:
    """Store an uploaded mesh under a name from its content (the same file twice, one copy), then
    bound the folder (`prune_uploads`), keeping this file and the `running` body's."""
    folder = folder or UPLOADS
    folder.mkdir(parents=True, exist_ok=True)
    suffix = Path(name).suffix.lower()
    stem = "".join(c if c.isalnum() or c in "-_." else "_" for c in Path(name).stem[:40])
    path = folder / f"{stem}-{hashlib.sha256(content).hexdigest()[:12]}{suffix}"
    if path.exists():
        os.utime(path)  # the newest again: the last to go
    else:
        path.write_bytes(content)
    prune_uploads(folder, {path} | ({Path(running)} if running else set()))
    return path


def prune_uploads(folder: Path, keep: set[Path], files: int | None = None, size: int | None = None) -> list[Path]:
    """Remove the oldest mesh files of `folder` until at most `files` (KEPT_FILES) files and `size`
    (KEPT_BYTES) bytes are left; never one of `keep` (the new upload, the running body's file).
    Returns what was removed."""
    files, size = files or KEPT_FILES, size or KEPT_BYTES
    keep = {p.resolve() for p in keep}
    meshes = [p for p in folder.iterdir() if p.suffix.lstrip(".") in MESH_FORMATS and p.is_file() and not p.is_symlink()]
    stats = {p: p.stat() for p in meshes}
    kept = [p for p in meshes if p.resolve() in keep]
    count, total = len(kept), sum(stats[p].st_size for p in kept)
    removed = []
    for p in sorted((p for p in meshes if p not in kept), key=lambda p: stats[p].st_mtime, reverse=True):  # newest first
        if count < files and total + stats[p].st_size <= size:
            count, total = count + 1, total + stats[p].st_size
            continue
        try:
            p.unlink()
            removed.append(p)
        except OSError:
            pass  # gone already, or not ours to remove: the bound is best effort
    return removed


def check_upload(name: str, content: bytes, unit: str) -> None:
    """ConfigError with the reason when `content` cannot become a body."""
    if not content:
        raise ConfigError(f"'{name}' is empty")
    if len(content) > MAX_BYTES:
        raise ConfigError(f"'{name}' is {len(content) / 1e6:.0f} MB, more than {MAX_BYTES / 1e6:.0f} MB")
    load_mesh(content, name, unit)


class BodyFile:
    """The "Your body" folder: unit, upload button and what the running body is."""

    def __init__(self, server: viser.ViserServer, post: Callable[[str, Any], None], show_error: Callable[[str, Any], None]):
        gui = server.gui
        self._post, self._show_error = post, show_error
        with gui.add_folder("Your body", expand_by_default=False):
            self.unit = gui.add_dropdown("Mesh unit", tuple(UNITS), initial_value="m", hint="The unit of the file's coordinates")
            self.button = gui.add_upload_button(
                "Load mesh (STL, OBJ, PLY)", icon=viser.Icon.UPLOAD, mime_type=",".join(f".{f}" for f in MESH_FORMATS),
                hint=f"A closed (watertight) triangle mesh, at most {MAX_TRIANGLES:,} triangles; density and the other settings are kept",
            )  # fmt: skip
            self.info = gui.add_markdown("")
        self.button.on_upload(self._uploaded)
        self.running: Callable[[], str | None] = lambda: None
        """The running body's mesh file, which the uploads folder's bound never removes (set by app/guards/upload_guard.py)."""

    def _uploaded(self, event) -> None:
        file = self.button.value
        self.button._impl.value = None  # the upload's bytes are not kept on the button (up to MAX_BYTES each)
        if file is None:
            return
        name = printable(Path(file.name.replace("\\", "/")).name, 60) or "upload"  # no NUL or other control character shown or stored
        try:
            check_upload(name, file.content, self.unit.value)
            path = keep_upload(name, file.content, running=self.running())
        except ConfigError as e:
            self._show_error(f"Mesh not loaded: {e}. The running body is unchanged.", event.client)
            return
        except OSError as e:
            self._show_error(f"Mesh not loaded: cannot keep the file ({e.strerror}).", event.client)
            return
        self._post("mesh", (str(path), self.unit.value))

    def describe(self, text: str) -> None:
        if self.info.content != text:
            self.info.content = text
