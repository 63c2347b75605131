"""A recorded run: the frames a replay, a CSV and a video are made from (app/replay.py, app/video.py).

The live viewer records the snapshots it publishes; `floatsim run --record` the frames it takes at the
replay's rate. Each shot carries what the scene draws: the frame, the body, the water, the fluid.
"""

from __future__ import annotations

import dataclasses
import io
from dataclasses import dataclass

import numpy as np

import sim
from sim.simulation import CSV_COLUMNS

from .loop import Posed

MAX_SHOTS = 30 * 600
"""Ten minutes at 30 frames a second: a longer recording stops itself (memory and file size)."""


@dataclass(frozen=True, eq=False)
class Shot(Posed):
    frame: sim.Frame
    body: sim.Body
    water: object
    params: object
    """The fluid table in use (g scales the arrows)."""


def shot_of(simulation: sim.Simulation) -> Shot:
    return Shot(simulation.frame(), simulation.body, simulation.model.water, simulation.params)


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
        mask = np.zeros(shot.body.n_samples, bool)
        mask[shot.frame.wet_index] = True
        frame = dataclasses.replace(shot.frame, wet_index=np.packbits(mask))
        self._shots.append(Shot(frame, shot.body, shot.water, shot.params))
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
        packed = self._shots[i]
        mask = np.unpackbits(packed.frame.wet_index, count=packed.body.n_samples).astype(bool)
        return dataclasses.replace(packed, frame=dataclasses.replace(packed.frame, wet_index=np.flatnonzero(mask)))

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
        out.write(",".join(CSV_COLUMNS) + "\n")
        for shot in self._shots:
            out.write(",".join(f"{v:.12g}" for v in shot.frame.row()) + "\n")
        return out.getvalue()
