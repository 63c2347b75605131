"""A recorded run: the frames a replay, a CSV and a video are made from (app/recording/replay.py, app/recording/video.py).

The live viewer records the snapshots it publishes; `floatsim run --record` the frames it takes at the
replay's rate. Each shot carries what the scene draws: the frame, the body, the water, the fluid, and for a scene of
several bodies every body's part and the run's own frame (its CSV row).
"""

from __future__ import annotations

import dataclasses
import io
from dataclasses import dataclass

import numpy as np

import sim
from app.live.loop import Part, Posed
from sim.system.frame import CSV_COLUMNS, csv_line

MAX_SHOTS = 30 * 600
"""Ten minutes at 30 frames a second: a longer recording stops itself (memory and file size)."""


@dataclass(frozen=True, eq=False)
class Shot(Posed):
    frame: sim.Frame
    """The chosen body's (the one body's: the run's own)."""
    body: sim.Body
    water: object
    params: object
    """The fluid table in use (g scales the arrows)."""
    parts: tuple = ()
    """Every body (loop.Part) of a scene of several bodies; () for one body."""
    run_frame: object = None
    """The run's own frame where it is not `frame` (several bodies): its CSV row."""

    @property
    def run(self):
        return self.frame if self.run_frame is None else self.run_frame


def shot_of(simulation: sim.Simulation) -> Shot:
    run, frames = simulation.frame(), simulation.parts()
    if len(frames) == 1:
        return Shot(run, simulation.body, simulation.water, simulation.params)
    parts = tuple(Part(n, b, f) for n, b, f in zip(simulation.body_names, simulation.bodies, frames))
    return Shot(frames[0], parts[0].body, simulation.water, simulation.params, parts, run)


def _packed(frame, body, pack: bool):
    """The frame of one body with its wet set as a bit mask (pack) or back as indices (not pack)."""
    if pack:
        mask = np.zeros(body.n_samples, bool)
        mask[frame.wet_index] = True
        wet = np.packbits(mask)
    else:
        wet = np.flatnonzero(np.unpackbits(frame.wet_index, count=body.n_samples).astype(bool))
    return dataclasses.replace(frame, bodies=(dataclasses.replace(frame.bodies[0], wet_index=wet),))


def _shot(shot, pack: bool) -> Shot:
    parts = tuple(Part(p.name, p.body, _packed(p.frame, p.body, pack)) for p in shot.parts)
    focus = next((p.frame for p, q in zip(parts, shot.parts) if q.frame is shot.frame), None)
    frame = focus if focus is not None else _packed(shot.frame, shot.body, pack)
    return Shot(frame, shot.body, shot.water, shot.params, parts, shot.run_frame)


class Take:
    """Shots in the order they were taken, each on a take clock (seconds from the first shot) that
    follows simulated time; a reset or a pause never runs it backwards. The wet set of each shot is
    kept as a bit mask (15 000 samples: 2 KB a shot rather than 120 KB)."""

    def __init__(self, limit: int = MAX_SHOTS):
        self._shots: list[Shot] = []
        self.times: list[float] = []
        self.limit = limit

    def add(self, shot) -> bool:
        """Keep a shot (a repeat of the last simulated time, as while paused, is skipped); False once full."""
        if len(self._shots) >= self.limit:
            return False
        if not self._tick(shot.frame.t):
            return True
        self._shots.append(_shot(shot, pack=True))
        return True

    def _tick(self, t: float) -> bool:
        """Put a shot at simulated time t on the take clock; False for a repeat of the last one's time (a paused run)."""
        if self._shots:
            step = t - self._shots[-1].frame.t
            if step == 0.0:
                return False
            self.times.append(self.times[-1] + (step if step > 0 else 1.0 / 30.0))  # after a reset: one frame on
        else:
            self.times.append(0.0)
        return True

    def __len__(self) -> int:
        return len(self._shots)

    def __getitem__(self, i: int) -> Shot:
        return _shot(self._shots[i], pack=False)

    @property
    def shots(self):
        """Every shot, as taken (wet sets unpacked one at a time)."""
        return (self[i] for i in range(len(self)))

    @property
    def duration(self) -> float:
        return self.times[-1] if self.times else 0.0

    def at(self, time: float):
        """The shot shown at take time `time` (the last one taken at or before it)."""
        i = int(np.searchsorted(self.times, time + 1e-9, side="right")) - 1
        return self[max(i, 0)]

    def csv(self) -> str:
        """Every shot as a row of the run CSV (the columns of `floatsim run --out`)."""
        out = io.StringIO()
        out.write(csv_line(self._shots[0].run.columns() if self._shots else CSV_COLUMNS) + "\n")
        for shot in self._shots:
            out.write(csv_line(shot.run.row()) + "\n")
        return out.getvalue()
