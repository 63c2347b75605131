"""The WAMIT runs the numeric-file reader is checked on: WEC-Sim's BEMIO examples, a subset of their periods.

WEC-Sim (github.com/WEC-Sim/WEC-Sim, Apache-2.0, commit a23d299) ships, in examples/BEMIO/WAMIT/, WAMIT 7.2 runs
with both their `.out` and their numeric files `.1`, `.3` and `.hst`:

- Cylinder/cyl: a vertical cylinder 0.35 m in radius, 0.63 m draft, in water 3 m deep; 525 frequencies, 0.04 to
  21 rad/s, heading 0;
- Ellipsoid/ellipsoid: a half ellipsoid of revolution 9 m across and 1.8 m deep (semi-axes 4.5, 4.5, 1.8 m) in deep
  water; 308 frequencies, 0.03 to 9.3 rad/s, heading 0.

And WEC-Sim Applications (github.com/WEC-Sim/WEC-Sim_Applications, Apache-2.0, commit 03c12b0) ships, in
Mean_Drift/WAMIT/outputFiles/, a WAMIT 7 run of a floating hemisphere 1 m in radius (its centre, origin and centre of
gravity at the water line; 400 panels, no irregular-frequency removal) in deep water, 200 frequencies 0.05 to 10
rad/s, heading 0, with its mean drift by momentum conservation (`.8`) and by pressure integration (`.9`).

Both bodies' origins are at the water line on their axis, as are their centres of gravity. Kept here (assets/
coefficients/wamit/) are every STRIDE-th period of each file, the files otherwise as WAMIT wrote them: the `.out`'s
blocks of the other periods (and their lines in its table of the solve's times) are dropped, the numeric files' rows of
the other periods too. The hemisphere's `.out` keeps every OUT_STRIDE-th (it is read for g, ULEN, the origins and the
depth only).

And RAFT (github.com/WISDEM/RAFT, Apache-2.0, commit e6cb69e) ships, in examples/OC4semi-WAMIT_Coefs/, the OC4
DeepCwind semi-submersible's WAMIT difference-frequency QTFs `marin_semi.12d` (56 periods, 2.1 to 25 s, heading 0, one
triangle of the period pairs): kept are the pairs of every SEMI_STRIDE-th period, under a title line naming the source.

Run: python -m studies.wamit_examples PATH/TO/WEC-Sim/examples/BEMIO/WAMIT [PATH/TO/WEC-Sim_Applications [PATH/TO/RAFT]]
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TARGET = ROOT / "assets" / "coefficients" / "wamit"
RUNS = {"Cylinder/cyl": 25, "Ellipsoid/ellipsoid": 8}
"""Each run and its STRIDE: about 21 and 39 periods of 525 and 308."""
DRIFT_RUN, DRIFT_STRIDE, OUT_STRIDE = "Mean_Drift/WAMIT/outputFiles/sphere", 2, 10
"""The hemisphere: 100 of its 200 periods (0.1 rad/s apart, to follow its drift's peak), 20 in its .out."""
SEMI_RUN, SEMI_STRIDE = "examples/OC4semi-WAMIT_Coefs/marin_semi.12d", 2
"""The semi's QTFs: 28 of its 56 periods (0.1 rad/s apart)."""
STAR = re.compile(r"^\s*\*{20,}\s*$")
PERIOD = re.compile(r"Wave period \(sec\)\s*=\s*(\S+)")


def kept_periods(one: Path, stride: int) -> set[str]:
    """The positive periods of the `.1`, as printed, every `stride`-th from the longest."""
    periods = []
    for line in one.read_text().splitlines():
        words = line.split()
        if len(words) == 5 and float(words[0]) > 0 and words[0] not in periods:
            periods.append(words[0])
    return set(periods[::stride])


def numeric(source: Path, target: Path, kept: set[str]) -> None:
    """`source`'s title and the rows of the periods kept (and PER = -1 and 0); `.hst` whole."""
    lines = source.read_text().splitlines(keepends=True)
    values = sorted(float(p) for p in kept)  # as numbers: a .8 prints 0.125664E+03 where the .1 has 1.256637E+02

    def keep(line: str) -> bool:
        period = float(line.split()[0])
        return period <= 0 or any(abs(period - v) <= 1e-5 * v for v in values)

    out = [line for n, line in enumerate(lines) if n == 0 or source.suffix == ".hst" or keep(line)]
    target.write_text("".join(out))


def out_file(source: Path, target: Path, kept: set[str]) -> None:
    """The `.out` with the blocks of the other periods dropped (and their rows in the header's table of times)."""
    values = {float(p) for p in kept}
    blocks, block = [], []
    for line in source.read_text().splitlines(keepends=True):
        block.append(line)
        if STAR.match(line):
            blocks.append(block)
            block = []
    blocks.append(block)
    kept_blocks = []
    for block in blocks:
        found = PERIOD.search("".join(block))
        if found is None or float(found.group(1)) in values:
            kept_blocks.append(block)
    text = "".join(line for block in kept_blocks for line in block)
    table = re.compile(r"^\s+(\d+\.\d+)\s+\d\d:\d\d:\d\d\s+-?\d+\s+-?\d+\s*$", re.M)  # "157.0796  11:57:08  -1  -1"
    text = table.sub(lambda m: m.group(0) if any(abs(float(m.group(1)) - v) < 1e-3 for v in values) else "\x00", text)
    target.write_text(text.replace("\x00\n", ""))


def main(folder: Path) -> None:
    TARGET.mkdir(parents=True, exist_ok=True)
    for run, stride in RUNS.items():
        stem = folder / run
        kept = kept_periods(stem.with_suffix(".1"), stride)
        for suffix in (".1", ".3", ".hst"):
            numeric(stem.with_suffix(suffix), TARGET / (stem.name + suffix), kept)
        out_file(stem.with_suffix(".out"), TARGET / (stem.name + ".out"), kept)
        print(f"{stem.name}: {len(kept)} periods -> {TARGET.relative_to(ROOT)}")


def hemisphere(applications: Path) -> None:
    """The mean drift case's files, its numeric ones (with the drift's .8 and .9) at every DRIFT_STRIDE-th period."""
    stem = applications / DRIFT_RUN
    kept = kept_periods(stem.with_suffix(".1"), DRIFT_STRIDE)
    for suffix in (".1", ".3", ".8", ".9", ".hst"):
        numeric(stem.with_suffix(suffix), TARGET / ("hemisphere" + suffix), kept)
    out_file(stem.with_suffix(".out"), TARGET / "hemisphere.out", kept_periods(stem.with_suffix(".1"), OUT_STRIDE))
    print(f"hemisphere: {len(kept)} periods -> {TARGET.relative_to(ROOT)}")


def semi(raft: Path) -> None:
    """The OC4 semi's `.12d`, the rows whose both periods are every SEMI_STRIDE-th of the file's, from the longest."""
    lines = (raft / SEMI_RUN).read_text().splitlines(keepends=True)
    periods = sorted({float(line.split()[0]) for line in lines if line.split()}, reverse=True)
    kept = periods[::SEMI_STRIDE]

    def keep(line: str) -> bool:
        words = line.split()
        return all(any(abs(float(w) - p) <= 1e-5 * p for p in kept) for w in words[:2])

    title = " WAMIT Numeric Output -- marin_semi.12d of RAFT (Apache-2.0) commit e6cb69e, every 2nd period (floatsim's subset)\n"
    out = [line for line in lines if line.split() and keep(line)]
    (TARGET / "marin_semi.12d").write_text(title + "".join(out))
    print(f"marin_semi.12d: {len(kept)} periods, {len(out)} rows -> {TARGET.relative_to(ROOT)}")


if __name__ == "__main__":
    main(Path(sys.argv[1]))
    if len(sys.argv) > 2:
        hemisphere(Path(sys.argv[2]))
    if len(sys.argv) > 3:
        semi(Path(sys.argv[3]))
