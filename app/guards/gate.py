"""One gate for every message a page sends, in every viewer (one body or several).

viser 1.1.1 hands each message a page sends to two dispatchers: the server's handlers (the shared controls,
file transfers to shared upload buttons, the share tunnel) and the page's own connection (its camera, its own
controls, renders). Any page may send any kind of message naming any control: a file transfer aimed at Pause
set Pause to a file for good; a transfer aimed at a page's own text box was buffered whole. `Gate` puts one
check in front of both dispatchers, then hands what passes to viser's handlers as before (the server's
first, then the page's):

- a control update carries only a value a browser sets on that control (app/guards/gui_guard.py: finite, bounded,
  of the control's type), from a page that finished connecting, and with a token only from a page that
  showed it (the page's own address probe, which carries the token, excepted);
- a file transfer may only fill a shared upload button, and its parts only that transfer, within the caps of
  app/guards/upload_guard.py: anything else is refused at its start, before a byte is kept;
- the share tunnel opens only with --share; the kinds of message these viewers do not use are dropped.

It also owns the rest of what keeps a shared viewer safe: the token read from each page's address (wrong
guesses slowed per address), tracebacks from broken connections shown once per kind, and a thread that hands
freed memory back and drops uploads left idle.
"""

from __future__ import annotations

import hmac
import math
import threading
import time
from collections.abc import Callable
from urllib.parse import parse_qsl

from viser import GuiUploadButtonHandle
from viser import _messages as m

from app.guards.guard import big_blocks_go_back, quiet_repeated_tracebacks, release_memory
from app.guards.gui_guard import NO_TOKEN, NOT_CONNECTED, Refusals, refusal
from app.guards.upload_guard import UploadGuard
from app.live.share import PROBE, probe_address

TRIM_SECONDS = 5.0
"""How often freed memory is handed back and idle uploads dropped."""
PASSED = (m.ViewerCameraMessage, m.GetRenderResponseMessage, m.LocalStorageGetItemResponseMessage)
"""Kinds that change nothing shared: the page's camera, and answers to what the server asked of that page."""
CHECKED = (m.GuiUpdateMessage, m.FileTransferStartUpload, m.FileTransferPart, m.ShareUrlRequest, m.ShareUrlDisconnect)
FREE_GUESSES = 3
"""Wrong tokens an address may send before each further guess waits (1 s, 2 s, 4 s, ... at most GUESS_WAIT_MAX)."""
GUESS_WAIT_MAX = 60.0


class Guesses:
    """Wrong tokens per address: after FREE_GUESSES, a guess before the address's wait is over is not compared."""

    def __init__(self):
        self._wrong: dict[str, tuple[int, float]] = {}  # address -> (wrong guesses, may guess again from)
        self._lock = threading.Lock()

    def check(self, address: str, given: str, token: str) -> str | None:
        """None when `given` is the token; else why not (a wrong token, or a guess too soon)."""
        now = time.monotonic()
        with self._lock:
            wrong, after = self._wrong.get(address, (0, -math.inf))
            if now < after:
                return f"too many wrong tokens from this address: wait {after - now:.0f} s"
        if hmac.compare_digest(given.encode(), token.encode()):
            with self._lock:
                self._wrong.pop(address, None)
            return None
        with self._lock:
            wrong += 1
            wait = min(2.0 ** (wrong - FREE_GUESSES), GUESS_WAIT_MAX) if wrong >= FREE_GUESSES else 0.0
            self._wrong[address] = (wrong, now + wait)
            if len(self._wrong) > 10_000:  # a bound on what many addresses can make us keep
                self._wrong.pop(next(iter(self._wrong)))
        return "wrong token"


class Gate:
    """The guard of one viser server. `notify(text)` shows a note to the user (rate-limited by `Refusals`);
    `on_link(client, query)` gets a page's address once its token (if any) checked out; `token`: only pages
    whose address carries it drive the run; `share`: pages may open viser's public share tunnel."""

    def __init__(self, server, notify: Callable[[str], None], *, token: str | None = None, share: bool = False,
                 on_link: Callable[[object, str], None] | None = None):  # fmt: skip
        self.server, self.token, self.share, self.on_link = server, token, share, on_link
        self.refusals = Refusals(notify)
        """Counts control updates refused before viser applied them."""
        self.share_refusals = Refusals(notify, "request for a public share link")
        self.uploads = UploadGuard(server.gui, notify)
        """Caps and counts file transfers (app/guards/upload_guard.py)."""
        self.dropped = 0
        """Messages of kinds these viewers do not use."""
        self.drivers: set[int] = set()
        """Pages that showed the token (with no token, every page drives)."""
        self.guesses = Guesses()
        self._pages: dict[int, Callable] = {}  # client id -> its connection's own dispatcher
        self._stopped = threading.Event()
        quiet_repeated_tracebacks()
        big_blocks_go_back()
        ws = server._websock_server
        self._server_dispatch = ws._handle_incoming_message
        ws._handle_incoming_message = self._dispatch  # viser looks it up per message: from now on every message comes here
        ws.on_client_connect(self._attach)  # runs before the page's first message is read
        ws.on_client_disconnect(self._detach)
        server.on_client_connect(self._connected)
        threading.Thread(target=self._tend, name="floatsim-tend", daemon=True).start()

    def stop(self) -> None:
        self._stopped.set()

    # ---- the event loop: every message a page sends

    def _attach(self, conn) -> None:
        self._pages[conn.client_id] = conn._handle_incoming_message
        conn._handle_incoming_message = _nothing  # the page's handlers now get its messages through _dispatch only

    def _detach(self, conn) -> None:
        self._pages.pop(conn.client_id, None)
        self.drivers.discard(conn.client_id)

    async def _dispatch(self, client_id: int, message) -> None:
        if not self.admits(client_id, message):
            return
        await self._server_dispatch(client_id, message)
        page = self._pages.get(client_id)
        if page is not None:
            await page(client_id, message)

    def admits(self, client_id: int, message) -> bool:
        """Whether viser may handle this message from page `client_id`; a refusal is counted (and noted where a
        user may have caused it)."""
        if isinstance(message, PASSED):
            return True
        if not isinstance(message, CHECKED):
            self.dropped += 1
            return False
        if isinstance(message, (m.ShareUrlRequest, m.ShareUrlDisconnect)):
            if not self.share:
                self.share_refusals("this viewer was started without --share")
            return self.share
        if isinstance(message, m.FileTransferPart):
            return self.uploads.part(client_id, message)
        client = self.server._connected_clients.get(client_id)
        if isinstance(message, m.FileTransferStartUpload):
            handle = self.server.gui._gui_input_handle_from_uuid.get(message.source_component_uuid)
            if client is None or not self._may_drive(client_id, None):
                self.uploads.refuse(NOT_CONNECTED if client is None else NO_TOKEN)
                return False
            return self.uploads.start(client_id, message, isinstance(handle, GuiUploadButtonHandle))
        handle = self.server.gui._gui_input_handle_from_uuid.get(message.uuid)
        if handle is None and client is not None:
            handle = client.gui._gui_input_handle_from_uuid.get(message.uuid)
        if handle is None:
            return False  # no such control (a removed one, or another page's): viser would ignore it too
        why = NOT_CONNECTED if client is None else (None if self._may_drive(client_id, handle) else NO_TOKEN)
        why = why or refusal(handle._impl, message.updates)
        if why is not None:
            self.refusals(why)
        return why is None

    def _may_drive(self, client_id: int, handle) -> bool:
        """With a token, a page drives the run once its address showed it; its address probe always passes."""
        if self.token is None or client_id in self.drivers:
            return True
        props = getattr(getattr(handle, "_impl", None), "props", None)
        return getattr(props, "label", None) == PROBE

    # ---- viser's thread pool: a new page

    def _connected(self, client) -> None:
        probe_address(client, self._address)

    def _address(self, client, query: str) -> None:
        """A page's address: with a token, it drives only if the address carries it (slowed guesses per address)."""
        if self.token is not None:
            given = dict(parse_qsl(query.lstrip("?"))).get("token", "")
            if not given:
                return  # a page without the token watches, as the banner says
            why = self.guesses.check(self._remote(client.client_id), given, self.token)
            if why is not None:
                self.refusals(f"{why} (this page may watch, not drive)")
                return
            self.drivers.add(client.client_id)
        if self.on_link is not None:
            self.on_link(client, query)

    def _remote(self, client_id: int) -> str:
        connection = self.server._websock_server._live_connections.get(client_id)
        address = getattr(connection, "remote_address", None)
        return str(address[0]) if address else "?"

    # ---- its own thread

    def _tend(self) -> None:
        """Every few seconds: drop uploads left idle, hand back to the system what freed messages took (~5 ms)."""
        while not self._stopped.wait(TRIM_SECONDS):
            self.uploads.drop_idle()
            release_memory()


async def _nothing(client_id, message) -> None:
    return None
