"""The F3OF decay tests' statistics from five other codes (assets/reference/f3of_decay.json), derived from open data.

Source: the SEA-Stack repository (github.com/Project-SEA-Stack/SEA-Stack, MIT licence), commit
4d1eae6453f0cd775ab3184d579ce7d943dbfda7, folder data/verification/f3of_decay_multicode/raw: the time series of
InWave, WEC-Sim, WaveDyn and ProteusDS (the OES Wave Energy Modelling Task's F3OF decay tests) and HydroChrono's.
Only statistics derived from them are kept here (their files stay in their repository): for each test and code, the
periods (from each extremum to the next of its sign) and the extrema (time, value) of the free decay, rotations in degrees.

The tests: DT1 the base displaced 5 m in surge, flaps locked; DT2 the base pitched 10 degrees, flaps locked; DT3 the
base held, the fore flap (SEA-Stack's body2, FLAP1 in the codes' files, hinge at x = -12.5 m) turned 10 degrees.

Run (with a SEA-Stack checkout): python -m studies.f3of_reference PATH/TO/SEA-Stack
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

OUT = Path(__file__).resolve().parent.parent / "assets" / "reference" / "f3of_decay.json"
RAW = "data/verification/f3of_decay_multicode/raw"
COMMIT = "4d1eae6453f0cd775ab3184d579ce7d943dbfda7"
EXTERNAL = {"WEC-Sim": "wsm/WSM", "InWave": "inw/INW", "WaveDyn": "wdn/WDN", "ProteusDS": "pds/PDS"}
CHRONO = {"DT1": "DT1_SURGE", "DT2": "DT2_PITCH", "DT3": "DT3_PITCH"}
SIGNALS = {
    ("DT1", "surge"): ("SURGE", 1),
    ("DT2", "pitch"): ("PITCH", 2),
    ("DT3", "flap"): ("FLAP1", 3),
    ("DT3", "other flap"): ("FLAP2", 4),
}
"""(test, signal): the external codes' file suffix and HydroChrono's column (its files: time, surge m, base pitch,
fore flap, aft flap in radians)."""
UNITS = {"surge": "m", "pitch": "deg", "flap": "deg", "other flap": "deg"}
SPAN = 300.0
"""Seconds of each record the statistics cover (HydroChrono's records end there)."""


def extrema(t: np.ndarray, y: np.ndarray) -> list[tuple[float, float]]:
    """The largest |y| between successive zero crossings, each refined by a parabola through its sample and their
    neighbours: not the release (the first sample), not the record's last half-cycle (cut short), not the rounding
    noise of a signal still at rest (under 1 % of its largest)."""
    s = np.sign(y)
    for i in np.flatnonzero(s == 0):  # a sample rounded to zero keeps the sign before it: no spurious crossing
        s[i] = s[i - 1] if i else 1.0
    cuts = np.concatenate([[0], np.flatnonzero(s[:-1] * s[1:] < 0) + 1])
    found, floor = [], 0.01 * float(np.abs(y).max())
    for a, b in zip(cuts[:-1], cuts[1:]):
        k = a + int(np.argmax(np.abs(y[a:b])))
        if 0 < k < len(y) - 1 and abs(y[k]) > floor:
            y0, y1, y2 = y[k - 1 : k + 2]
            p = 0.5 * (y0 - y2) / (y0 - 2 * y1 + y2) if y0 - 2 * y1 + y2 else 0.0
            found.append((float(t[k] + p * (t[k + 1] - t[k])), float(y1 - 0.25 * (y0 - y2) * p)))
    return found


def _external(root: Path, code: str, test: str, suffix: str) -> tuple[np.ndarray, np.ndarray]:
    path = root / RAW / f"{EXTERNAL[code]}_F3OF_{test}_{suffix}.dat"
    skip = 1 if path.read_text().startswith("#") else 5  # ProteusDS: one '#' line; the others: five
    d = np.loadtxt(path, skiprows=skip)
    return d[:, 0], d[:, 1]


def _chrono(root: Path, test: str, column: int) -> tuple[np.ndarray, np.ndarray]:
    d = np.loadtxt(root / RAW / f"hydrochrono/CHRONO_F3OF_{CHRONO[test]}.txt", skiprows=1)
    return d[:, 0], d[:, column] if column == 1 else np.degrees(d[:, column])


def statistics(t: np.ndarray, y: np.ndarray) -> dict:
    keep = t <= SPAN
    t, y = t[keep], y[keep]
    found = extrema(t, y)
    periods = [b[0] - a[0] for a, b in zip(found[:-2], found[2:])]  # from each extremum to the next of its sign
    return {"periods": [round(p, 3) for p in periods], "extrema": [[round(a, 3), round(b, 5)] for a, b in found]}


def derive(root: Path) -> dict:
    tests: dict = {}
    for (test, signal), (suffix, column) in SIGNALS.items():
        codes = {code: statistics(*_external(root, code, test, suffix)) for code in EXTERNAL}
        codes["HydroChrono"] = statistics(*_chrono(root, test, column))
        tests.setdefault(test, {})[signal] = {"unit": UNITS[signal], "codes": codes}
    return {
        "source": f"github.com/Project-SEA-Stack/SEA-Stack (MIT licence), commit {COMMIT}, {RAW}",
        "derived_by": "python -m studies.f3of_reference PATH/TO/SEA-Stack",
        "span_s": SPAN,
        "notes": "HydroChrono holds the base to the one degree of freedom of the test (surge in DT1, pitch in DT2); the "
        "other four codes let it surge, heave and pitch. WEC-Sim's DT3 holds the other flap still.",
        "tests": tests,
    }


def main(argv: list[str]) -> None:
    if len(argv) != 1 or not (Path(argv[0]) / RAW).is_dir():
        sys.exit(f"usage: python -m studies.f3of_reference PATH/TO/SEA-Stack (a checkout holding {RAW})")
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(derive(Path(argv[0])), indent=1) + "\n")
    print(OUT)


if __name__ == "__main__":
    main(sys.argv[1:])
