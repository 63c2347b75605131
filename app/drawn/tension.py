"""The mooring lines coloured by their tension, and the colour bar that reads it (a small legend at the panel's top).

Each line segment's ends take the colour of MoorDyn's tension at their nodes (frame.line_tensions), interpolated
along the segment by the page; the scale runs over the range of tensions the lines have held lately (TensionScale), rounded
outward to a round number of newtons, so the legend changes rarely and a colour keeps its meaning.
"""

from __future__ import annotations

import math

import numpy as np
import viser

STOPS = np.array([[255, 215, 0], [255, 110, 0], [210, 0, 30]], float)
"""Slack to taut: yellow, orange, red, saturated, so that each still reads through the sea over it (pale yellow read as
grey under the sea's blue)."""
MEMORY = 20.0
"""Simulated seconds over which the scale forgets a tension the lines no longer hold."""
THICKNESS = 4.0
"""The lines' width on the page, pixels (a line 30 m off stays wide enough to read its colour)."""
LEGEND_ORDER = 0.5
"""The legend's place in the panel: above the tabs (viser's default orders count up from 1)."""


def tension_colours(tension: np.ndarray, low: float, high: float) -> np.ndarray:
    """(n, 3) uint8 colours of the tensions on the scale low .. high, N."""
    s = np.clip((np.asarray(tension, float) - low) / max(high - low, 1e-12), 0.0, 1.0) * (len(STOPS) - 1)
    k = np.minimum(s.astype(int), len(STOPS) - 2)
    f = (s - k)[:, None]
    return np.round(STOPS[k] * (1 - f) + STOPS[k + 1] * f).astype(np.uint8)


def segment_colours(tensions, low: float, high: float) -> np.ndarray:
    """(segments, 2, 3) uint8: each segment's ends coloured by the tension at its nodes (lines as in frame.lines)."""
    return np.concatenate([np.stack([c[:-1], c[1:]], axis=1) for c in (tension_colours(t, low, high) for t in tensions)])


def nice_step(span: float) -> float:
    """A round step (1, 2 or 5 times a power of ten) about a tenth of `span`."""
    raw = max(span / 10.0, 1e-9)
    power = 10.0 ** math.floor(math.log10(raw))
    return next(m * power for m in (1.0, 2.0, 5.0, 10.0) if m * power >= raw)


class TensionScale:
    """The range of tensions the lines have held lately, rounded outward (low, high), N: it widens at once to any
    tension and narrows back toward the present range over about `memory` simulated seconds (a drop's first jerk does
    not squash the scale for the rest of the run)."""

    def __init__(self, memory: float = MEMORY):
        self.memory = memory
        self.reset()

    def reset(self) -> None:
        self.seen, self.t = None, -math.inf
        self.low = self.high = 0.0

    def take(self, tensions, t: float) -> bool:
        """Take the tensions at time t; whether the rounded range changed."""
        values = np.concatenate([np.asarray(x, float) for x in tensions]) if len(tensions) else np.zeros(0)
        values = values[np.isfinite(values)]
        if not len(values):
            return False
        now = (float(values.min()), float(values.max()))
        if self.seen is None or t < self.t:
            self.seen = now
        else:
            w = min(1.0, (t - self.t) / self.memory)
            low, high = self.seen
            self.seen = (min(now[0], low + w * (now[0] - low)), max(now[1], high + w * (now[1] - high)))
        self.t = t
        step = nice_step(max(self.seen[1] - self.seen[0], 0.1 * abs(self.seen[1]), 1.0))
        low, high = step * math.floor(self.seen[0] / step), step * math.ceil(self.seen[1] / step)
        high = high if high > low else low + step
        changed = (low, high) != (self.low, self.high)
        self.low, self.high = low, high
        return changed


def _hex(c) -> str:
    return "#" + "".join(f"{int(v):02x}" for v in c)


def legend_html(low: float, high: float) -> str:
    """A colour bar from `low` to `high` N."""
    gradient = ", ".join(_hex(c) for c in STOPS)
    unit = lambda v: f"{v / 1e3:.4g} kN" if max(abs(low), abs(high)) >= 1e4 else f"{v:.4g} N"  # noqa: E731
    return (
        '<div style="font-size: 0.85em; padding: 0 0.2em;"><b>Mooring lines</b>: coloured by tension'
        f'<div style="height: 0.8em; margin: 0.2em 0; border-radius: 2px; background: linear-gradient(to right, {gradient});"></div>'
        f'<div style="display: flex; justify-content: space-between;"><span>{unit(low)}</span><span>{unit(high)}</span></div></div>'
    )


class TensionLegend:
    """The colour bar in the panel (hidden without lines); updated only when the rounded range changes."""

    def __init__(self, server: viser.ViserServer):
        self.html = server.gui.add_html(legend_html(0.0, 1.0), order=LEGEND_ORDER, visible=False)

    def show(self, scale: TensionScale | None) -> None:
        """The scale's range, or hidden (None)."""
        if scale is None:
            if self.html.visible:
                self.html.visible = False
            return
        content = legend_html(scale.low, scale.high)
        if self.html.content != content:
            self.html.content = content
        if not self.html.visible:
            self.html.visible = True
