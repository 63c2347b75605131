"""Uploads are capped as their bytes arrive, not after.

viser 1.1.1 keeps every part of a file transfer in memory until the last one arrives, trusting the
size and part count the page declares: one page that declared 10^6 parts and sent 480 MiB grew the
server by 498 MiB before app/upload.py could refuse the file. `guard_uploads` puts a check in front of
viser's two handlers: a transfer is refused at its start when it declares more than MAX_BYTES, more
parts than MAX_PARTS (or than bytes), or would take the bytes in flight past MAX_IN_FLIGHT; a page has
one transfer in flight at a time; and a transfer is dropped as soon as its parts bring more bytes than
it declared. Each refusal gets a short note (the same one at most once per NOTICE_SECONDS)."""

from __future__ import annotations

import inspect
import math
import threading
import time
from collections.abc import Callable

from .upload import MAX_BYTES

MAX_PARTS = 1024
"""Most parts a transfer may declare (a browser sends 512 KiB parts: 96 for MAX_BYTES)."""
MAX_IN_FLIGHT = 2 * MAX_BYTES
"""Most bytes all unfinished transfers together may declare."""
NOTICE_SECONDS = 2.0


def start_refusal(size: int, parts: int, in_flight: int) -> str | None:
    """Why a transfer declaring `size` bytes in `parts` parts may not start, or None."""
    if not (isinstance(size, int) and isinstance(parts, int)) or size < 0 or parts < 0:
        return "it declared no valid size"
    if size > MAX_BYTES:
        return f"it is {size / 1e6:.0f} MB, more than {MAX_BYTES / 1e6:.0f} MB"
    if parts > MAX_PARTS or parts > size or (size and not parts):
        return f"it declared {parts:,} parts for {size:,} bytes"
    if in_flight + size > MAX_IN_FLIGHT:
        return "other uploads are still arriving; try again when they are done"
    return None


class UploadGuard:
    """The checks, with a count of refusals (tests read it) and a rate-limited note through `notify`."""

    def __init__(self, gui, notify: Callable[[str], None]):
        self.gui, self.notify = gui, notify
        self.refused = 0
        self._last_note = ("", -math.inf)  # (text, when)
        self._lock = threading.Lock()

    @property
    def _transfers(self) -> dict:
        return self.gui._current_file_upload_states

    def start(self, client_id: int, message) -> bool:
        """Whether viser may take this FileTransferStartUpload; the page's unfinished transfers are dropped."""
        transfers = self._transfers
        for uuid in [u for u, state in list(transfers.items()) if state.get("client_id") == client_id]:
            transfers.pop(uuid, None)  # a page uploads one file at a time: an abandoned one frees its bytes
        in_flight = sum(int(state.get("total_bytes", 0)) for state in list(transfers.values()))
        why = start_refusal(message.size_bytes, message.part_count, in_flight)
        if why is not None:
            self._refuse(why)
        return why is None

    def part(self, client_id: int, message) -> bool:
        """Whether viser may keep this FileTransferPart: only its own page's, within what was declared."""
        state = self._transfers.get(message.transfer_uuid)
        if state is None:
            return False  # refused or dropped already (or never started): nothing to keep
        if state.get("client_id") != client_id:
            return False  # another page's transfer: not this one's to fill
        arrived = int(state.get("transferred_bytes", 0)) + len(message.content)
        if arrived > min(int(state.get("total_bytes", 0)), MAX_BYTES):
            self._transfers.pop(message.transfer_uuid, None)
            self._refuse("more bytes arrived than it declared")
            return False
        return True

    def _refuse(self, why: str) -> None:
        text = f"Upload refused: {why}. The running body is unchanged."
        with self._lock:
            self.refused += 1
            now = time.monotonic()
            if text == self._last_note[0] and now - self._last_note[1] < NOTICE_SECONDS:
                return  # a flood of the same refusal: one note
            self._last_note = (text, now)
        self.notify(text)


def guard_uploads(gui, body_file, loop) -> UploadGuard:
    """Guard `gui`'s (a viser GuiApi's) file-transfer handlers (whatever is registered for them, e.g.
    the token check of app/gui_guard.py, runs after the guard); and tell the Your body folder which
    file the running body came from, which the uploads folder's bound never removes."""
    from viser import _messages

    guard = UploadGuard(gui, lambda text: loop.post("notice", text))
    handlers = gui._websock_interface._incoming_handlers
    for kind, check in ((_messages.FileTransferStartUpload, guard.start), (_messages.FileTransferPart, guard.part)):
        chain = handlers.get(kind, [])
        chain[:] = [_guarded(handler, check) for handler in chain]
    body_file.running = lambda: _running_mesh(loop)
    return guard


def _guarded(handler, check):
    if getattr(handler, "upload_guarded", False):
        return handler

    async def guarded(client_id, message) -> None:
        if not check(client_id, message):
            return
        result = handler(client_id, message)
        if inspect.isawaitable(result):
            await result

    guarded.upload_guarded = True
    return guarded


def _running_mesh(loop) -> str | None:
    body = loop.latest().settings.config.body
    return str(body.mesh) if body.shape == "mesh" and body.mesh else None
