"""Load your own body: an upload control for STL, OBJ or PLY. The file is read and checked on the
callback's thread (sim.body.load_mesh: a mesh, closed, at most 200 000 triangles, a plausible size in
the unit chosen); a good one is kept on disk and handed to the simulation thread as a command, a bad
one gets its one-line reason in the panel and the running scene is untouched."""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from pathlib import Path
from typing import Any

import viser

from sim.body import MAX_TRIANGLES, MESH_FORMATS, UNITS, load_mesh
from sim.errors import ConfigError

UPLOADS = Path.home() / ".cache" / "floatsim" / "uploads"
MAX_BYTES = 50_000_000
"""A larger file is refused before parsing (a 200 000-triangle binary STL is 10 MB)."""


def keep_upload(name: str, content: bytes, folder: Path = UPLOADS) -> Path:
    """Store an uploaded mesh under a name from its content (the same file twice, one copy)."""
    folder.mkdir(parents=True, exist_ok=True)
    suffix = Path(name).suffix.lower()
    path = folder / f"{Path(name).stem[:40]}-{hashlib.sha256(content).hexdigest()[:12]}{suffix}"
    if not path.exists():
        path.write_bytes(content)
    return path


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

    def _uploaded(self, event) -> None:
        file = self.button.value
        name = Path(file.name).name or "upload"
        try:
            check_upload(name, file.content, self.unit.value)
            path = keep_upload(name, file.content)
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
