"""Issue 23 over viser's real websocket protocol (tests/page.py): what every page shows is what the run
uses, dropdowns take only their choices, the token lets the right page drive, no page opens a public
share tunnel, pages from other sites cannot connect, and link setups refuse repeats and bad values
without restarting anyone's run."""

from __future__ import annotations

import asyncio
import contextlib
import io

import pytest
import websockets
from viewer import wait_for

from app.live.loop import CONTROLLED
from app.tools.page import Page, opened_with
from sim.scene.config import load_scene

DENSITY_MAX = (CONTROLLED["density"].live or (CONTROLLED["density"].lo, CONTROLLED["density"].hi))[1]


@contextlib.contextmanager
def viewer(scene: str = "damped", **kwargs):
    from app.args import ViewArgs
    from app.main import start

    with contextlib.redirect_stdout(io.StringIO()):
        app = start(ViewArgs(scene=scene, port=0, **kwargs), kernels=False, publish_hz=20.0)
    try:
        yield app
    finally:
        app.stop()


async def fresh_page(port: int) -> Page:
    """What a page that connects now is shown (the scene's state comes in several windows: read them all)."""
    async with Page.open(port) as page:
        await page.read(1.5, until=lambda p: "Mesh unit" in p.controls)
        await page.read(0.5)
        return page


def test_every_page_shows_what_the_run_uses_after_bad_values():
    """A page that never sent a camera message (viser applied its updates, broadcast them and ran no
    callback), a connected page with an out-of-range density, and both with dropdown values that are
    not choices: a fresh page then shows the run's own values."""
    with viewer() as app:

        async def attack():
            async with Page.open(app.port) as silent:
                await silent.read(1.5, until=lambda p: "Mesh unit" in p.controls)
                for label, value in (("Density", 1e11), ("Integrator", "../../etc/passwd"), ("Mesh unit", "../../etc/passwd")):
                    await silent.update(label, value)
                await silent.read(0.5)
            wait_for(app, lambda s: "not finished connecting" in s.notice, what="the note on the unconnected page")
            async with Page.open(app.port) as page:
                await page.read(1.5, until=lambda p: "Mesh unit" in p.controls)
                await page.camera()
                await page.read(0.5)
                for label, value in (("Density", 1e11), ("Integrator", "../../etc/passwd"), ("Mesh unit", "../../etc/passwd")):
                    await page.update(label, value)
                await page.read(0.5)
                snap = wait_for(app, lambda s: s.density == DENSITY_MAX, what="the clamped density")
                await page.read(1.0)
                assert page.value("Density") == DENSITY_MAX  # the page that sent it is shown the clamp
            return snap

        snap = asyncio.run(attack())
        assert "outside" in snap.notice or app.refusals.count >= 3
        shown = asyncio.run(fresh_page(app.port))
        assert shown.value("Density") == snap.density == DENSITY_MAX
        assert shown.value("Integrator") == snap.settings.value("integrator") == "implicit"
        assert shown.value("Mesh unit") == "m" and app.body_file.unit.value == "m"
        assert app.refusals.count >= 5  # three from the unconnected page, two dropdown values not among the choices


def test_a_new_page_is_shown_every_control_as_it_is_in_the_message_that_makes_it():
    """viser replays a new page's backlog in windows. A control's creation message comes early and its later
    values come as updates further on. Under load the later window came over 0.3 s after the controls, and
    for that time a new page showed the values the scene started with. The hostile campaign on rm3-moored
    found this: a mesh body's Samples 600 and Density 933 while the run used 6 and 500. Now every control
    comes with the value it has now, whether the run or a page set it. Small windows here make sure the
    updates are in other windows than the controls, whatever the backlog's size."""
    from app.tools.hostile import _fields
    from app.tools.page import decode

    with viewer() as app:
        app.controls.dt.value = 0.01
        app.controls.speed.value = 2.0

        async def from_a_page():  # viser echoes a page's value to the other pages only: an update, not the control's creation
            async with Page.open(app.port) as page:
                await page.read(1.5, until=lambda p: "Mesh unit" in p.controls)
                await page.camera()
                await page.read(0.5)
                await page.update("Density", 500.0)
                await page.read(0.5)

        asyncio.run(from_a_page())
        snap = wait_for(app, lambda s: s.density == 500.0 and s.settings.value("dt") == 0.01 and s.settings.speed == 2.0, what="the values")
        app.server._websock_server._broadcast_buffer.max_window_size = 16
        handles = _fields(app)

        async def made_with() -> dict:
            made = {}
            async with Page.open(app.port) as page:
                while not {h.label for h in handles.values()} <= made.keys():
                    for m in decode(await asyncio.wait_for(page.ws.recv(), timeout=5.0)):
                        if m.get("type") != "GuiUpdateMessage" and "value" in m and isinstance(m.get("props"), dict):
                            made[m["props"].get("label")] = m["value"]
            return made

        made = asyncio.run(made_with())
        used = (snap.density, snap.settings.value("dt"), snap.settings.speed)
        assert (made["Density (kg/m³)"], made["Time step (s)"], made["Speed (×)"]) == (500.0, 0.01, 2.0) == used
        shown = {key: tuple(made[h.label]) if isinstance(made[h.label], list) else made[h.label] for key, h in handles.items()}
        assert shown == {key: h.value for key, h in handles.items()}  # every control, as the server has it


@pytest.mark.slow
def test_with_a_token_only_the_page_opened_with_it_drives_the_run():
    with viewer(token="s3 cret&x") as app:  # a token that needs quoting in the banner's link
        query = app.address().split("/?", 1)[1]

        async def drive(address: str, density: float) -> int:
            async with Page.open(app.port) as page:
                await page.read(1.5, until=lambda p: "Mesh unit" in p.controls)
                await page.camera()
                await page.give_address(address)
                await page.read(1.0)
                await page.update("Density", density)
                await page.read(1.0)
                return len(app.drivers)  # while it is here (a page that leaves is forgotten)

        assert asyncio.run(drive("?", 321.0)) == 0
        assert asyncio.run(drive("?token=wrong&density=321", 321.0)) == 0
        snap = app.sync()
        assert snap.density == 900.0 and app.refusals.count >= 2
        assert asyncio.run(drive("?" + query, 500.0)) == 1
        wait_for(app, lambda s: s.density == 500.0 and not app.drivers, what="the page with the token to set density, then be forgotten")


def fake_tunnels(monkeypatch) -> list:
    """viser's share tunnel replaced by one that records that it was made (and never connects)."""
    made = []

    class Tunnel:
        def __init__(self, *args):
            made.append(args)

        def on_connect(self, fn):
            return fn

        on_disconnect = on_connect

        def get_status(self):
            return "failed"

        def get_url(self):
            return None

        def close(self):
            pass

    monkeypatch.setattr("viser._viser.ViserTunnel", Tunnel)
    return made


async def ask_for_a_share_link(port: int) -> Page:
    async with Page.open(port) as page:
        await page.read(1.0)
        await page.camera()
        await page.send({"type": "ShareUrlRequest"})
        await page.send({"type": "ShareUrlDisconnect"})
        await page.read(1.5)
        return page


@pytest.mark.slow
def test_no_page_opens_a_public_share_tunnel(monkeypatch):
    made = fake_tunnels(monkeypatch)
    with viewer() as app:
        page = asyncio.run(ask_for_a_share_link(app.port))
        snap = wait_for(app, lambda s: "share link" in s.notice, what="the refusal note")
        assert made == [] and app.server._share_tunnel is None
        assert "--share" in snap.notice and not any(m["type"] == "ShareUrlUpdated" for m in page.messages)
    with viewer(share=True) as app:  # asked for on the command line: viser's own handler runs
        asyncio.run(ask_for_a_share_link(app.port))
        assert made and made[0][1] == app.port


def test_pages_from_another_site_cannot_connect():
    async def status(port: int, origin: str | None):
        try:
            async with Page.open(port, origin) as page:
                await page.read(1.0, until=lambda p: "Density (kg/m³)" in p.controls)
                return "Density (kg/m³)" in page.controls
        except websockets.exceptions.InvalidStatus as e:
            return e.response.status_code

    with viewer() as app:
        port = app.port
        assert asyncio.run(status(port, "http://evil.example")) == 403
        assert asyncio.run(status(port, f"http://evil.example:{port}")) == 403  # a rebound name for 127.0.0.1
        assert asyncio.run(status(port, "null")) == 403
        assert asyncio.run(status(port, f"http://127.0.0.1:{port}")) is True
        assert asyncio.run(status(port, f"http://localhost:{port}")) is True
        assert asyncio.run(status(port, None)) is True  # a script, not a page
        assert upgrade_status(port, ("Origin: http://127.0.0.1", "Origin: http://evil.example")) == 403  # not a 500
        assert upgrade_status(port, ("Host: 127.0.0.1", "Host: evil.example")) == 403
        assert upgrade_status(port, ("Origin: http://127.0.0.1",)) == 101
        assert app.loop.is_alive()


def upgrade_status(port: int, headers: tuple[str, ...]) -> int:
    """The HTTP status a websocket handshake with these extra header lines gets (a raw request: clients send one of each)."""
    import socket

    lines = ["GET / HTTP/1.1", "Upgrade: websocket", "Connection: Upgrade", "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==",
             "Sec-WebSocket-Version: 13", f"Sec-WebSocket-Protocol: viser-v{__import__('viser').__version__}", *headers]  # fmt: skip
    if not any(h.startswith("Host:") for h in headers):
        lines.insert(1, f"Host: 127.0.0.1:{port}")
    with socket.create_connection(("127.0.0.1", port), timeout=10) as s:
        s.sendall(("\r\n".join(lines) + "\r\n\r\n").encode())
        return int(s.recv(1024).split(b" ", 2)[1])


@pytest.mark.slow
def test_link_repeats_and_refused_values_restart_nobody():
    with viewer() as app:

        async def scenario():
            async with Page.open(app.port) as watcher:  # someone already watching: a link may not restart their run for nothing
                await watcher.read(1.0)
                await watcher.camera()
                await watcher.read(1.0)
                await opened_with(app.port, "?density=500&density=600")
                snap = wait_for(app, lambda s: s.density == 500.0 and "more than once" in s.notice, what="the first density and a note")
                epoch = snap.epoch
                await opened_with(app.port, "?density=1e11&integrator=bogus&scene=nowhere&dt=nan")
                snap = wait_for(app, lambda s: "is not a preset" in s.notice, what="the refusals' note")
                assert snap.epoch == epoch and snap.density == 500.0 and snap.settings.value("integrator") == "implicit"
                assert "outside" in snap.notice and "not one of" in snap.notice
                await opened_with(app.port, "?damping=40&density=1e11")
                return wait_for(app, lambda s: s.damping == 40.0, what="the accepted damping"), epoch

        snap, epoch = asyncio.run(scenario())
        assert snap.epoch > epoch and snap.density == 500.0  # an accepted setting restarts the run; the refused one is not used


@pytest.mark.slow
@pytest.mark.parametrize("query", ["?token=s3cret", "?fixedDpr=0.5"])
def test_a_link_with_no_setting_restarts_nobody(query):
    with viewer() as app:

        async def scenario():
            async with Page.open(app.port) as watcher:
                await watcher.read(1.0)
                await watcher.camera()
                await watcher.read(1.0)
                epoch = app.sync().epoch
                await opened_with(app.port, query)
                return epoch

        epoch = asyncio.run(scenario())
        assert app.sync().epoch == epoch


def test_a_burst_of_updates_leaves_every_control_showing_what_runs():
    """Out-of-range values each followed at once by a valid one (a fast drag, or a hostile page): the clamp of
    the first was written back after the second already showed, so pages showed the clamp while the run used
    the second value. After the burst a fresh page shows exactly what the run uses."""
    pairs = [("Period", 30000.0, 30.0), ("Damping", -1.0, 5e4), ("Density", 1e11, 450.0), ("Tp", 0.01, 12.0)] * 12
    with viewer() as app:

        async def burst():
            async with Page.open(app.port) as page:
                await page.read(1.5, until=lambda p: "Mesh unit" in p.controls)
                await page.camera()
                await page.read(0.5)
                for label, bad, good in pairs:
                    await page.update(label, bad)
                    await page.update(label, good)
                # the server may still be reading the page's messages on a loaded machine
                await page.read(20.0, until=lambda _page: runs_last(app.latest()))
                # and what it writes back then (a clamp it wrote before the page's next value arrived is written over:
                # on a loaded machine that can take more than a second to reach the page)
                await page.read(20.0, until=lambda p: all(p.value(label) == good for label, _, good in pairs[:4]))
                return page

        last = {p[0].lower(): p[2] for p in pairs[:4]}
        runs_last = lambda snap: all(snap.settings.value(key) == good for key, good in last.items())  # noqa: E731
        page = asyncio.run(burst())
        snap = wait_for(app, runs_last, timeout=20.0, what="the burst's last values")
        shown = asyncio.run(fresh_page(app.port))
        for label, key, _bad, good in ((p[0], p[0].lower(), *p[1:]) for p in pairs[:4]):
            assert snap.settings.value(key) == good, key
            assert shown.value(label) == good and page.value(label) == good, label


def test_a_page_cannot_slow_the_shared_run_below_a_tenth_of_real_time():
    """Issue 59: a page setting Time step to -1 got the range's 1e-5 s, 500 times the steps, slowing the shared run for
    every page. A time step that would run below a tenth of real time at the measured cost of a step is refused with a
    note giving that cost; a shorter step that keeps up is taken. (storm on the numpy reference: about a millisecond a
    step, so 1e-5 s would run at about 0.01x.)"""
    with viewer("storm") as app:

        async def steer():
            async with Page.open(app.port) as page:
                await page.read(1.5, until=lambda p: "Mesh unit" in p.controls)
                await page.camera()
                wait_for(app, lambda s: s.frame.t > 0.2, what="storm running")
                await page.update("Time step", -1.0)
                refused = wait_for(app, lambda s: "real time here" in s.notice, what="the refusal")
                await page.read(0.5)
                shown = page.value("Time step")
                await page.update("Time step", 0.004)
                return refused, shown, wait_for(app, lambda s: s.settings.value("dt") == 0.004, what="the shorter step that keeps up")

        refused, shown, taken = asyncio.run(steer())
        assert refused.settings.value("dt") == load_scene("storm").step.dt and shown == refused.settings.value("dt")
        assert "µs a step" in refused.notice and "kept" in refused.notice, refused.notice
        rate = float(refused.notice.split("would run at ")[1].split("x real time")[0])
        assert rate < 0.1, refused.notice
        assert taken.settings.value("dt") == 0.004
