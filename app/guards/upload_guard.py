"""Uploads are capped as their bytes arrive, not after.

viser 1.1.1 keeps every part of a file transfer in memory until the last one arrives, trusting the
size and part count the page declares: one page that declared 10^6 parts and sent 480 MiB grew the
server by 498 MiB before app/live/upload.py could refuse the file. The gate (app/guards/gate.py) asks `UploadGuard`
about each transfer message: a transfer is refused at its start unless it fills a shared upload button,
when it declares more than MAX_BYTES, more parts than MAX_PARTS (or than bytes), or would take the bytes
in flight past MAX_IN_FLIGHT; a page has one transfer in flight at a time; a part must belong to a
transfer its own page started, name that transfer's button (viser finishes a transfer on the control its
*last part* names) and stay within what was declared; a transfer that brings no part for IDLE_SECONDS is
dropped (two idle pages held the in-flight cap for everyone). Each refusal gets a short note (the same one
at most once per NOTICE_SECONDS)."""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable

from app.live.upload import MAX_BYTES

MAX_PARTS = 1024
"""Most parts a transfer may declare (a browser sends 512 KiB parts: 96 for MAX_BYTES)."""
MAX_IN_FLIGHT = 2 * MAX_BYTES
"""Most bytes all unfinished transfers together may declare."""
IDLE_SECONDS = 30.0
"""A transfer with no part for this long is dropped and its bytes freed."""
NOTICE_SECONDS = 2.0
NO_UPLOAD_HERE = "it was aimed at a control that takes no file"


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
    """The checks on the transfers to `gui` (a viser GuiApi), with a count of refusals (tests read it) and a
    rate-limited note through `notify`."""

    def __init__(self, gui, notify: Callable[[str], None]):
        self.gui, self.notify = gui, notify
        self.refused = 0
        self.dropped_idle = 0
        self._open: dict[str, tuple[int, str, float]] = {}  # transfer -> (page, button uuid, when its last part came)
        self._last_note = ("", -math.inf)  # (text, when)
        self._lock = threading.Lock()

    @property
    def _transfers(self) -> dict:
        return self.gui._current_file_upload_states

    def start(self, client_id: int, message, to_upload_button: bool) -> bool:
        """Whether viser may take this FileTransferStartUpload; the page's unfinished transfers and idle ones are dropped."""
        self.drop_idle()
        with self._lock:
            for uuid in [u for u, (page, _, _) in self._open.items() if page == client_id]:
                self._drop(uuid)  # a page uploads one file at a time: an abandoned one frees its bytes
        in_flight = sum(int(state.get("total_bytes", 0)) for state in list(self._transfers.values()))
        why = NO_UPLOAD_HERE if not to_upload_button else start_refusal(message.size_bytes, message.part_count, in_flight)
        if why is None and message.transfer_uuid in self._transfers:
            why = "a transfer with its name is already arriving"
        if why is not None:
            self.refuse(why)
            return False
        with self._lock:
            self._open[message.transfer_uuid] = (client_id, message.source_component_uuid, time.monotonic())
        return True

    def part(self, client_id: int, message) -> bool:
        """Whether viser may keep this FileTransferPart: its own page's transfer, its button, within what was declared."""
        with self._lock:
            page, button, _ = self._open.get(message.transfer_uuid, (None, None, 0.0))
            state = self._transfers.get(message.transfer_uuid)
            if state is None or page != client_id or message.source_component_uuid != button:
                return False  # refused, dropped, finished, or not this page's: nothing to keep
            arrived = int(state.get("transferred_bytes", 0)) + len(message.content)
            if arrived > min(int(state.get("total_bytes", 0)), MAX_BYTES):
                self._drop(message.transfer_uuid)
                too_many = True
            else:
                self._open[message.transfer_uuid] = (page, button, time.monotonic())
                too_many = False
        if too_many:
            self.refuse("more bytes arrived than it declared")
        return not too_many

    def drop_idle(self, now: float | None = None) -> int:
        """Drop the transfers that brought no part for IDLE_SECONDS (and forget finished ones); how many were dropped."""
        now = time.monotonic() if now is None else now
        with self._lock:
            for uuid in [u for u in self._open if u not in self._transfers]:
                del self._open[uuid]  # finished (viser popped it) or dropped with its page
            idle = [u for u, (_, _, last) in self._open.items() if now - last > IDLE_SECONDS]
            for uuid in idle:
                self._drop(uuid)
            self.dropped_idle += len(idle)
        if idle:
            self.refuse(f"no part of it arrived for {IDLE_SECONDS:.0f} s")
        return len(idle)

    def _drop(self, uuid: str) -> None:
        self._transfers.pop(uuid, None)
        self._open.pop(uuid, None)

    def refuse(self, why: str) -> None:
        text = f"Upload refused: {why}. The running scene is unchanged."
        with self._lock:
            self.refused += 1
            now = time.monotonic()
            if text == self._last_note[0] and now - self._last_note[1] < NOTICE_SECONDS:
                return  # a flood of the same refusal: one note
            self._last_note = (text, now)
        self.notify(text)
