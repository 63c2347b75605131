"""Who may open the viewer's websocket, and what a page may not ask of viser.

Origin: a web page on another site can open `ws://127.0.0.1:8080` from the user's own browser (websockets
are not bound by the same-origin rule; the browser only says where the page came from, in `Origin`). viser
1.1.1 accepts every handshake: it hands websockets' `serve` a `process_request` (its static file server)
and nothing else. `own_origin_only` wraps that `process_request` while viser builds its server, so a
websocket handshake whose `Origin` is present and is not this viewer's own address is answered 403 before
any message is read. Connections with no `Origin` (scripts, tests) are not pages: they stay allowed.

What a page may send once connected is app/guards/gate.py's concern.
"""

from __future__ import annotations

import contextlib
import http
import ipaddress
import threading
from urllib.parse import quote, urlsplit

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
        if "websocket" in (v.lower() for v in headers.get_all("Upgrade")):
            port = connection.local_address[1]
            origins, hosts = headers.get_all("Origin"), headers.get_all("Host")
            if len(origins) > 1 or len(hosts) > 1:  # which one would a check believe? neither (and .get raised: HTTP 500)
                return connection.respond(http.HTTPStatus.FORBIDDEN, "Repeated Origin or Host headers.\n")
            if not origin_allowed(origins[0] if origins else None, host, port, hosts[0] if hosts else None):
                return connection.respond(http.HTTPStatus.FORBIDDEN, "A page from another site may not use this viewer.\n")
        return inner(connection, request) if inner is not None else None

    return process_request


def viewer_address(host: str, port: int, token: str | None = None) -> str:
    """The viewer's address as a browser opens it (a wildcard host as localhost); with a token, the link whose page
    may drive the run."""
    shown = "localhost" if host in WILDCARDS else (f"[{host}]" if ":" in host else host)
    url = f"http://{shown}:{port}"
    return f"{url}/?token={quote(token, safe='')}" if token else url
