"""Helpers shared by the viewer tests."""

import time


def wait_for(app, condition, timeout=30.0, what="condition"):
    """Poll fresh snapshots of a running viewer until condition(snapshot) holds."""
    deadline = time.monotonic() + timeout
    while True:
        snap = app.sync()
        if condition(snap):
            return snap
        if time.monotonic() > deadline:
            where = f"z={snap.frame.x_world[2]}, density={snap.density}" if hasattr(snap, "density") else f"paused={snap.paused}"
            raise AssertionError(f"timed out waiting for {what}; last: t={snap.frame.t}, {where}, notice={snap.notice!r}")
        time.sleep(0.05)
