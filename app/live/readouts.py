"""Numbers and live plots in the GUI: time, height, |F|, |L|, energy, real-time factor, with a warning when the machine lags.

The plots keep a fixed window sampled at `PLOT_HZ` (a decimation of the published frames) and
replace their data whole: uPlot has no append, so the window bounds what each update costs.

Each update also names the window's x range (`window_range`). Without it viser's client moves the x axis
by a window it remembers relative to the data's extent; a Live tab that opens mid-run builds its charts at
0 px, then rebuilds them at their width (uplot-react), and that memory can be taken from a chart whose x
scale is not set yet (read as 0..1): from then on the plots draw the window's first few percent (opened at
t = 26 s they drew 0.9-2.1 s of a 1-26 s window) and, after a Reset, negative times. A named range turns
that memory off and is applied whenever a chart is built. A window whose values vary by less than 1 % of
its quantity's natural scale (`flat_range`) gets an explicit y range too, on tick steps uPlot labels exactly.
"""

from __future__ import annotations

import collections
import math
import time

import numpy as np
import viser

from app.live.loop import Snapshot

PLOT_HZ = 10.0
WINDOW = 200
"""Samples per plot: 20 s of wall time at PLOT_HZ."""
SERIES = (
    ("z", "z (m)", "#1c7ed6", lambda f: f.x_world[2]),
    ("L", "|L| (kg·m²/s)", "#2b8a3e", lambda f: float(np.linalg.norm(f.L_world))),
    ("F", "|F| (N)", "#c92a2a", lambda f: float(np.linalg.norm(f.force_world))),
    ("E", "E total (J)", "#7048e8", lambda f: f.E_total),
    ("P", "P take-off (W)", "#e8590c", lambda f: f.P_pto),
    ("Fp", "F take-off (N)", "#d6336c", lambda f: f.F_pto),
)
JOINT_ONLY = ("P", "Fp")
"""Plots shown only while the body has a joint to the world."""
NOISE = 1e-9
"""Plotted values are rounded to this fraction of the body's own scale (`scales`): round-off (|F| of 1e-13 N
at rest) then plots as the flat zero it is, not as swings with every tick labelled 0."""
Y_AXIS_PX = 76
"""Room for the y labels, px: uPlot's default 50 cuts the leading digits and the sign of '-1,226.3'."""
NONNEGATIVE = ("L", "F")
"""Plots of magnitudes: a flat one at zero gets [0, 2q], not [-q, q]."""
FLAT = 1e-2
"""A window varying by less than this fraction of its quantity's scale is flat: it gets an explicit y range."""
MIN_TICK = 1e-3
TICKS = tuple(m * 10.0**k for k in range(-3, 16) for m in (1, 2, 2.5, 5) if m * 10.0**k >= MIN_TICK and (m, k) != (2.5, -3))
"""The y axes' tick steps (uPlot's own, less those under MIN_TICK and 0.0025): uPlot writes its labels with Intl's
default of at most 3 decimals, so a finer step labels ticks alike or wrongly ('0.001, 0.001, 0, 0')."""
X_MIN_SPAN = 0.1
"""The x axis spans at least this (s): a window of one sample after a reset still has an axis."""
X_STEPS = 20
"""The x range moves in steps of a 20th of the window (about a second at PLOT_HZ and WINDOW)."""


def scales(body, g: float) -> np.ndarray:
    """The natural size of each plotted quantity for a body (SERIES order): its radius, M r sqrt(g r),
    its weight, its weight times its radius, its weight times sqrt(g r), its weight."""
    r, weight = max(body.radius, 1e-6), body.mass * max(g, 1e-6)
    speed = np.sqrt(max(g, 1e-6) * r)
    return np.array([r, body.mass * r * speed, weight, weight * r, weight * speed, weight])


def denoise(values: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """(k, m) values of the m series rounded to NOISE x their scale (m,)."""
    quantum = NOISE * scale
    return np.round(values / quantum) * quantum


def window_range(t: np.ndarray) -> tuple[float, float]:
    """The x range of a window of sample times t: first to last, each rounded out to a step of about a
    second's worth of samples (a 20th of the full window), so it changes about once a second (each change
    rebuilds the chart in the page) while the data in between update at PLOT_HZ."""
    lo, hi, n = float(t[0]), float(t[-1]), len(t)
    full = (hi - lo) / (n - 1) * (WINDOW - 1) if n > 1 and hi > lo else 0.0
    step = nice(max(full / X_STEPS, X_MIN_SPAN))
    a, b = math.floor(lo / step) * step, math.ceil(hi / step) * step
    return float(f"{a:.12g}"), float(f"{max(b, a + step):.12g}")


def nice(x: float) -> float:
    """The least of 1, 2, 5 x 10^k at or above x (x > 0)."""
    k = math.floor(math.log10(x))
    return next(m * 10.0**e for e in (k, k + 1) for m in (1, 2, 5) if m * 10.0**e >= x * (1 - 1e-12))


def flat_range(values: np.ndarray, scale: float, nonnegative: bool = False) -> tuple[float, float] | None:
    """A y range for a window that varies by less than q = FLAT x scale (rounded up to 1, 2, 5 x 10^k, at
    least 2 x MIN_TICK): 2q wide around the window's middle rounded to q (so it moves only when the value
    moves by q), from 0 for a magnitude near 0. None for a window that varies more (uPlot ranges it)."""
    finite = values[np.isfinite(values)]
    if finite.size == 0:
        return None
    lo, hi = float(finite.min()), float(finite.max())
    q = nice(max(FLAT * scale, 2 * MIN_TICK))
    if hi - lo >= q:
        return None
    k = round((lo + hi) / 2 / q)
    if nonnegative and lo >= 0 and k < 1:
        return 0.0, 2 * q
    return float(f"{(k - 1) * q:.12g}"), float(f"{(k + 1) * q:.12g}")


def plot_scales(t: np.ndarray, values: np.ndarray, scale: float, nonnegative: bool = False) -> dict:
    """One plot's uPlot scales for a window: x its time range, y explicit while the window is flat."""
    scales: dict = {"x": {"time": False, "range": window_range(t)}}
    if (y := flat_range(values, scale, nonnegative)) is not None:
        scales["y"] = {"range": y}
    return scales


class Readouts:
    """A markdown block of numbers and one uPlot per quantity; `update` runs on the simulation thread."""

    def __init__(self, server: viser.ViserServer):
        gui = server.gui
        self.text = gui.add_markdown("")
        self.plots = {}
        # the plots under the numbers, in the panel's "Live" tab (app/main.py)
        for key, label, colour, _ in SERIES:
            self.plots[key] = gui.add_uplot(
                (np.zeros(1), np.zeros(1)),
                ({"label": "t (s)"}, {"label": label, "stroke": colour, "width": 1.5}),
                scales=plot_scales(np.zeros(1), np.zeros(1), 1.0),
                legend={"show": True},
                axes=({}, {"size": Y_AXIS_PX, "incrs": TICKS}),
                aspect=2.2,
                visible=key not in JOINT_ONLY,
            )
        self._scales = {key: plot.scales for key, plot in self.plots.items()}
        """What each plot's scales were last set to (viser resends a dict at every assignment)."""
        self._history: collections.deque = collections.deque(maxlen=WINDOW)
        self._epoch = -1
        self._last = -math.inf
        self._last_text = ""

    def update(self, snap: Snapshot) -> None:
        now = time.monotonic()
        if now - self._last < 1.0 / PLOT_HZ:
            return
        self._last = now
        text = describe(snap)
        if text != self._last_text:
            self.text.content = self._last_text = text
        frame = snap.frame
        if snap.epoch != self._epoch:
            self._epoch = snap.epoch
            self._history.clear()
        if self._history and self._history[-1][0] == frame.t:
            return  # paused: nothing new to draw
        size = scales(snap.body, snap.params.g)
        raw = [f(frame) for *_, f in SERIES]
        if snap.system:  # the chosen body's take-off is its joint's (the run's frame lists each joint's power and force)
            raw[-2:] = next(((p, force) for name, _, _, p, _, force in snap.run.joints if name == snap.settings.focus), (0.0, 0.0))
        values = denoise(np.array(raw, dtype=float), size)
        self._history.append((frame.t, *values))
        data = np.array(self._history, dtype=float).T
        data[~np.isfinite(data)] = np.nan
        jointed = snap.settings.joint != "free"
        for i, (key, *_) in enumerate(SERIES):
            plot = self.plots[key]
            if key in JOINT_ONLY and plot.visible != jointed:
                plot.visible = jointed
            if not plot.visible:
                continue  # a hidden plot is not drawn: its data would only cost bytes
            wanted = plot_scales(data[0], data[i + 1], float(size[i]), key in NONNEGATIVE)
            if wanted != self._scales[key]:
                plot.scales = self._scales[key] = wanted
            plot.data = (data[0], data[i + 1])


def _model_energy(f) -> str:
    """The sampled models' own energy, where their potential differs from the exact one E total uses."""
    if f.E_hyd_model is None or abs(f.E_hyd_model - f.E_hyd) <= 1e-9 * max(1.0, abs(f.E_hyd)):
        return ""
    return f" (exact potential; the model's own {f.E_kin + f.E_grav + f.E_hyd_model:.6g} J)"


def quantity(value: float, unit: str) -> str:
    """A value in its unit with the SI prefix that suits its size (6 559 W: "6.559 kW"; 0.5 N: "0.5 N"), four figures."""
    size = abs(value)
    for scale, prefix in ((1e9, "G"), (1e6, "M"), (1e3, "k")):
        if size >= scale:
            return f"{value / scale:.4g} {prefix}{unit}"
    return f"{value:.4g} {unit}"


def _line_energy(energy: tuple) -> str:
    """The lines' energy where the scene counts it ([moorings] energy): what they store, what they have dissipated."""
    return f" · lines store {quantity(energy[0], 'J')}, have dissipated **{quantity(energy[1], 'J')}**" if energy else ""


def _readings(snap: Snapshot) -> list[str]:
    """What every scene's run reads (system/frame.Readings): each joint's take-off, the mooring lines' pull."""
    run, s, out = snap.run, snap.settings, []
    for name, theta, _, p, e, force in run.joints:
        what = (
            f"Joint {name}: stroke **{theta:+.4f}** · take-off"
            if snap.system
            else f"Joint: {s.joint} to the seabed · power take-off ({s.controller})"
        )
        out.append(f"{what} **{quantity(force, 'N m' if s.joint == 'revolute' and not snap.system else 'N')}**, "
                   f"**{quantity(p, 'W')}** now, **{quantity(e, 'J')}** absorbed")  # fmt: skip
    if run.mooring:
        (fx, fy, fz, largest), lines = run.mooring[:4], len(run.mooring) - 4
        out.append(f"Mooring: {lines} line{'s' if lines != 1 else ''} pull **{quantity(math.hypot(fx, fy), 'N')}** sideways, "
                   f"**{quantity(-fz, 'N')}** down · largest fairlead tension **{quantity(largest, 'N')}**" + _line_energy(run.line_energy))  # fmt: skip
    return out


def _system(snap: Snapshot) -> list[str]:
    """A scene of several bodies: where each body is and the energies of all."""
    run = snap.run
    return [" · ".join(f"{b.name}: z = {b.x_world[2]:+.3f} m, |u| = {np.linalg.norm(b.u_world):.3f} m/s" for b in run.bodies),
            f"All bodies: E total = **{run.E_total:.6g} J**, with the take-offs' {quantity(run.E_pto, 'J')} and the radiated "
            f"{quantity(run.E_rad, 'J')} · the numbers above are {snap.settings.focus}'s (choose the body under Body)"]  # fmt: skip


def _held_by(snap: Snapshot) -> str:
    """What holds the chosen body besides the water ('' for a body alone and free): its joints, its lines."""
    s, run = snap.settings, snap.run
    held = []
    if snap.system:
        held.append("the bodies it is joined to")
    elif s.joint not in (None, "", "free"):
        held.append(f"its {s.joint} joint")
    if run.mooring:
        held.append("its mooring lines")
    return " and ".join(held)


def _stability(snap: Snapshot, h) -> str:
    """The body's metacentric height: its own, as a free body; where joints or lines hold it, said to be the free body's."""
    held = _held_by(snap)
    if not held:
        verdict = "rights itself" if h.gm[0] > 0 else "rolls over: a heel grows"
    elif h.gm[0] > 0:
        verdict = f"as a free body it rights itself; {held} add to that"
    else:
        verdict = f"as a free body it would roll over; here {held} hold it upright, and the motion shows the whole system's stability"
    return (f"GM = **{h.gm[0]:+.3f} m** ({verdict}; the least of {h.gm[0]:+.3f}, {h.gm[1]:+.3f} m about the waterplane's axes) · "
            f"displaced {h.volume:.4g} m³")  # fmt: skip


def describe(snap: Snapshot) -> str:
    """The readout text of a snapshot (of several bodies: the chosen one's, then the system's)."""
    f, s = snap.frame, snap.settings
    rate = snap.real_time_factor
    state = "paused" if s.paused else (f"{rate:.2f}× real time" if math.isfinite(rate) else "starting")
    lines = [
        f"t = **{f.t:.2f} s** · z = **{f.x_world[2]:+.3f} m**",
        f"|F| = **{np.linalg.norm(f.force_world):.4g} N** · |L| = **{np.linalg.norm(f.L_world):.4g} kg·m²/s**",
        f"E total = **{f.E_total:.6g} J**{_model_energy(f)} · mass {snap.body.mass:.4g} kg · "
        f"inertia {'exact (mesh shell)' if snap.body.exact_inertia else 'of the samples'}",
        f"Speed: {state} (asked {s.speed:g}×){' on the ' + snap.engine if snap.engine else ''} · {snap.body.n_samples} samples",
    ]
    lines += _readings(snap) + (_system(snap) if snap.system else [])
    if (h := snap.hydrostatics) is not None:
        lines.append(_stability(snap, h))
    if snap.advice:
        lines.append(f"**⚠ {snap.advice}**")
    if snap.behind and snap.engine.startswith("numpy reference ("):  # compiling or loading: the cause passes by itself
        lines.append(f"**⚠ Slower than {s.speed:g}× real time until the fast kernels are ready**: the numpy reference steps meanwhile "
                     "(a scene's first run on a machine compiles them once, in the time said above); "
                     "nothing to change, the run speeds up by itself.")  # fmt: skip
    elif snap.behind:
        lines.append(
            f"**⚠ This machine cannot keep up with {s.speed:g}× real time**: lower the speed, the points per edge, or pick a faster integrator."
        )
    return "\n\n".join(lines)
