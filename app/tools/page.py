"""A page of the viewer spoken over viser's real websocket protocol (no browser): it reads what the server
sends (zstd-compressed msgpack windows), keeps every control's last label, options and value, and can
send what a browser sends: a camera message, its address into the link probe, control updates."""

from __future__ import annotations

import asyncio
import contextlib
import time

import msgspec
import viser
import websockets
import zstandard

CAMERA = {"type": "ViewerCameraMessage", "wxyz": [1.0, 0.0, 0.0, 0.0], "position": [3.0, 3.0, 3.0], "fov": 1.0, "near": 0.01,
          "far": 100.0, "image_height": 600, "image_width": 800, "look_at": [0.0, 0.0, 0.0], "up_direction": [0.0, 0.0, 1.0]}  # fmt: skip
PROBE = "floatsim-address"


def decode(frame: bytes) -> list[dict]:
    """The messages of one server window (binary buffers are left out)."""
    size, compressed = int.from_bytes(frame[:8], "little"), int.from_bytes(frame[8:16], "little")
    inner = zstandard.ZstdDecompressor().decompress(frame[16 : 16 + compressed], max_output_size=size)
    return msgspec.msgpack.decode(inner)["messages"]


class Page:
    """One websocket connection; `controls[label]` is {'uuid', 'value', 'options', 'kind' (viser's message: the control's
    kind), 'step'} as the page would show it."""

    def __init__(self, ws):
        self.ws = ws
        self.controls: dict[str, dict] = {}
        self._by_uuid: dict[str, dict] = {}
        self.messages: list[dict] = []
        self.texts: dict[str, str] = {}
        """Every markdown block's content as the page shows it, by uuid."""
        self.nodes: dict[str, dict] = {}
        """Every scene node's last properties as the page has them (position, wxyz, ...), by name."""
        self.camera_moves: list[tuple[str, list[float]]] = []
        """The camera moves the server sent this page, in order: ('position' or 'look_at', value)."""

    @classmethod
    @contextlib.asynccontextmanager
    async def open(cls, port: int, origin: str | None = None):
        headers = {"Origin": origin} if origin else None
        async with websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=[f"viser-v{viser.__version__}"], max_size=None,
                                      additional_headers=headers) as ws:  # fmt: skip
            yield cls(ws)

    async def send(self, message: dict) -> None:
        await self.ws.send(msgspec.msgpack.encode(message))

    async def camera(self) -> None:
        """What every browser sends first: viser counts a page as connected from its first camera message."""
        await self.send(CAMERA)

    def control(self, label: str) -> dict:
        """The control labelled `label` (its unit, as in 'Density (kg/m³)', may be left out)."""
        return next(c for name, c in self.controls.items() if name == label or name.startswith(label + " ("))

    def value(self, label: str):
        return self.control(label)["value"]

    async def update(self, label: str, value) -> None:
        """What a browser does when its user sets a control: it shows the value and sends it (viser echoes it to
        the other pages only)."""
        control = self.control(label)
        control["value"] = value
        await self.send({"type": "GuiUpdateMessage", "uuid": control["uuid"], "updates": {"value": value}})

    async def read(self, seconds: float, until=None) -> None:
        """Take in what the server sends for `seconds` (or until `until(self)` holds)."""
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline and not (until and until(self)):
            try:
                frame = await asyncio.wait_for(self.ws.recv(), timeout=max(0.05, min(0.5, deadline - time.monotonic())))
            except asyncio.TimeoutError:
                continue
            for m in decode(frame):
                self._take(m)

    def _take(self, m: dict) -> None:
        self.messages.append({k: v for k, v in m.items() if k == "type" or k in ("uuid", "updates", "share_url")})
        kind = m.get("type", "")
        if "name" in m and isinstance(m.get("props"), dict):  # a scene node made
            self.nodes[m["name"]] = dict(m["props"])
        elif kind == "SceneNodeUpdateMessage" and m.get("name") in self.nodes:
            self.nodes[m["name"]].update(m.get("updates", {}))
        elif kind in ("SetPositionMessage", "SetOrientationMessage"):
            self.nodes.setdefault(m["name"], {}).update({k: m[k] for k in ("position", "wxyz") if k in m})
        if kind in ("SetCameraPositionMessage", "SetCameraLookAtMessage") and not m.get("initial"):  # (not a new page's start)
            key = "position" if kind == "SetCameraPositionMessage" else "look_at"
            self.camera_moves.append((key, list(m[key])))
        if kind == "GuiMarkdownMessage" and isinstance(m.get("props"), dict):
            self.texts[m["uuid"]] = m["props"].get("_markdown", "")  # viser 1.1.1's name for the content
        elif kind == "GuiUpdateMessage" and m.get("uuid") in self.texts and "_markdown" in m.get("updates", {}):
            self.texts[m["uuid"]] = m["updates"]["_markdown"]
        if kind.startswith("Gui") and kind != "GuiUpdateMessage" and isinstance(m.get("props"), dict) and "value" in m and "uuid" in m:
            c = {"uuid": m["uuid"], "value": m["value"], "options": m["props"].get("options"), "kind": kind, "step": m["props"].get("step")}
            self._by_uuid[m["uuid"]] = c
            self.controls[m["props"].get("label", "")] = c
        elif kind == "GuiUpdateMessage" and m.get("uuid") in self._by_uuid:
            c = self._by_uuid[m["uuid"]]
            c["value"] = m["updates"].get("value", c["value"])
            c["options"] = m["updates"].get("options", c["options"])
            c["step"] = m["updates"].get("step", c["step"])

    def text(self, containing: str) -> str:
        """The markdown block that contains `containing` ('' when none does)."""
        return next((t for t in self.texts.values() if containing in t), "")

    async def give_address(self, query: str) -> None:
        """What the page's script does with its address: put `location.search` into the link probe."""
        await self.read(10.0, until=lambda p: PROBE in p.controls)
        await self.update(PROBE, query)


async def opened_with(port: int, query: str, seconds: float = 1.0) -> Page:
    """A page opened at `?query` (it sends its camera, then its address), kept open for `seconds`."""
    async with Page.open(port) as page:
        await page.read(1.0)
        await page.camera()
        await page.give_address(query)
        await page.read(seconds)
        return page
