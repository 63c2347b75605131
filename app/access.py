"""Who may open the viewer's websocket, and what a page may not ask of viser.

Origin: a web page on another site can open `ws://127.0.0.1:8080` from the user's own browser (websockets
are not bound by the same-origin rule; the browser only says where the page came from, in `Origin`). viser
1.1.1 accepts every handshake: it hands websockets' `serve` a `process_request` (its static file server)
and nothing else. `own_origin_only` wraps that `process_request` while viser builds its server, so a
websocket handshake whose `Origin` is present and is not this viewer's own address is answered 403 before
any message is read. Connections with no `Origin` (scripts, tests) are not pages: they stay allowed.

Share tunnel: viser registers `ShareUrlRequest` / `ShareUrlDisconnect` for every client; one message makes
the server open a tunnel to viser's public share service, after which anyone with its URL can reach the
run. `refuse_share` replaces both handlers unless the user gave `--share`.
"""

from __future__ import annotations

import contextlib
import http
import ipaddress
import threading
from collections.abc import Callable
from urllib.parse import urlsplit

WILDCARDS = ("0.0.0.0", "::", "")
_SERVE_LOCK = threading.Lock()


def is_loopback_name(name: str) -> bool:
    if name.lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(name).is_loopback
    except ValueError:
        return False


def origin_allowed(origin: str | None, host: str, port: int, host_header: str | None) -> bool:
    """Whether a page from `origin` may open the websocket of a viewer bound to `host`:`port`.

    Allowed: no Origin (not a page); a page on this machine (loopback name, any port: an SSH tunnel may
    forward another local port, and local code can connect without a browser anyway); the host given, at
    the viewer's port; with a wildcard host (0.0.0.0), a page served by this very server under the name
    the browser used (Origin equal to the Host header)."""
    if origin is None:
        return True
    try:
        parts = urlsplit(origin)
        name, origin_port = parts.hostname or "", parts.port or 80
    except ValueError:
        return False
    if parts.scheme != "http":
        return False
    if is_loopback_name(name):
        return True
    if host not in WILDCARDS:
        return name == host.strip("[]").lower() and origin_port == port
    return host_header is not None and parts.netloc.lower() == host_header.lower()


@contextlib.contextmanager
def own_origin_only(host: str):
    """While viser builds its server inside this block, its websocket handshakes get the Origin check.

    viser's server thread calls `websockets.asyncio.server.serve(..., process_request=...)` before
    `ViserServer()` returns (it waits until the port is bound), so the wrapped `serve` is in place exactly
    for that call; the lock keeps two viewers started at once from swapping it under each other."""
    import websockets.asyncio.server as ws_server

    real = ws_server.serve

    def serve(*args, process_request=None, **kwargs):
        return real(*args, process_request=_checked(process_request, host), **kwargs)

    with _SERVE_LOCK:
        ws_server.serve = serve
        try:
            yield
        finally:
            ws_server.serve = real


def _checked(inner, host: str):
    def process_request(connection, request):
        headers = request.headers
        if headers.get("Upgrade", "").lower() == "websocket":
            port = connection.local_address[1]
            if not origin_allowed(headers.get("Origin"), host, port, headers.get("Host")):
                return connection.respond(http.HTTPStatus.FORBIDDEN, "A page from another site may not use this viewer.\n")
        return inner(connection, request) if inner is not None else None

    return process_request


def refuse_share(server, refused: Callable[[str], None]) -> None:
    """Replace viser's handlers of a page's share-tunnel messages with a refusal (`refused(why)`)."""
    from viser import _messages

    handlers = server._websock_server._incoming_handlers

    def refuse(client_id, message) -> None:
        refused("this viewer was started without --share")

    for kind in (_messages.ShareUrlRequest, _messages.ShareUrlDisconnect):
        handlers[kind] = [refuse]
