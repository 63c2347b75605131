"""Wave gauges at run time: the sea's elevation at fixed points, and a measured record beside it (scene/gauges.py)."""

from __future__ import annotations

import numpy as np


class Gauges:
    """The readings of `names` at `xy` ((k, 2), m); those flagged `at_record` also read the record (dt, eta) there."""

    def __init__(self, names: list[str], xy, at_record: list[bool], record: tuple[float, np.ndarray] | None = None):
        self.names, self.at_record = list(names), list(at_record)
        self.xy = np.asarray(xy, float).reshape(-1, 2)
        if record is not None:
            dt, eta = record
            self._times = dt * np.arange(len(eta) + 1)  # one period of the record's periodic extension, its first sample repeated
            self._values = np.append(eta, eta[0]) - eta.mean()

    def record_at(self, t: float) -> float:
        """The record at time t: linear between its samples, periodic, its mean removed (as the sea made from it)."""
        return float(np.interp(t % self._times[-1], self._times, self._values))

    def read(self, water, t: float) -> tuple:
        """((name, x, y, eta, record or None), ...) at time t in `water` (the running sea)."""
        if not self.names:
            return ()
        eta = water.elevation(self.xy, t)
        return tuple((name, float(x), float(y), float(e), self.record_at(t) if at else None)
                     for name, (x, y), e, at in zip(self.names, self.xy, eta, self.at_record))  # fmt: skip
