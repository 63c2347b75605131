"""The NEMOH run the NEMOH reader is checked on: WEC-Sim's BEMIO example of the half ellipsoid, a subset of its
frequencies.

WEC-Sim (github.com/WEC-Sim/WEC-Sim, Apache-2.0, commit a23d299) ships, in examples/BEMIO/NEMOH/NEMOH_v2.3/Ellipsoid/,
a NEMOH 2.3 run of the same half ellipsoid as its WAMIT example (9 m across, 1.8 m deep, deep water; 1250 panels,
308 frequencies 0.03 to 9.24 rad/s, heading 0): its Nemoh.cal, Results/RadiationCoefficients.tec and
Results/ExcitationForce.tec, Mesh/KH.dat and Mesh/Hydrostatics.dat.

Kept here (assets/coefficients/nemoh/ellipsoid/, the run's layout): every STRIDE-th frequency from the first, the
Tecplot zones' row counts and Nemoh.cal's frequency line changed to match, the files otherwise as NEMOH wrote them.

Run: python -m studies.nemoh_examples PATH/TO/WEC-Sim/examples/BEMIO/NEMOH/NEMOH_v2.3/Ellipsoid
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TARGET = ROOT / "assets" / "coefficients" / "nemoh" / "ellipsoid"
STRIDE = 4
"""77 of the 308 frequencies, 0.12 rad/s apart (0.03 to 9.15 rad/s)."""
ZONE = re.compile(r"(Zone t=\"[^\"]*\",\s*I=\s*)(\d+)")


def tecplot(source: Path, target: Path) -> int:
    """`source` with every STRIDE-th row of each zone (one row a line, as NEMOH writes them); the rows kept."""
    out, row, kept = [], 0, 0
    for line in source.read_text().splitlines(keepends=True):
        if ZONE.search(line):
            count = int(ZONE.search(line).group(2))
            kept = len(range(0, count, STRIDE))
            out.append(ZONE.sub(lambda m: f"{m.group(1)}{kept:6d}", line))
            row = 0
        elif line.strip() and line.split()[0][0] in "-0123456789." and not line.startswith(("VARIABLES", '"')):
            if row % STRIDE == 0:
                out.append(line)
            row += 1
        else:
            out.append(line)
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_text("".join(out))
    return kept


def main(folder: Path) -> None:
    kept = 0
    for name in ("RadiationCoefficients.tec", "ExcitationForce.tec"):
        kept = tecplot(folder / "Results" / name, TARGET / "Results" / name)
    cal = (folder / "Nemoh.cal").read_text()
    first, last = 0.03, 0.03 + (kept - 1) * 0.03 * STRIDE
    cal = re.sub(r"^308\s+0\.03\s+9\.24", f"{kept}\t{first:.2f}\t{last:.2f}", cal, flags=re.MULTILINE)
    (TARGET / "Nemoh.cal").write_text(cal)
    for name in ("KH.dat", "Hydrostatics.dat"):
        (TARGET / "Mesh").mkdir(parents=True, exist_ok=True)
        (TARGET / "Mesh" / name).write_text((folder / "Mesh" / name).read_text())
    print(f"ellipsoid: {kept} frequencies -> {TARGET.relative_to(ROOT)}")


if __name__ == "__main__":
    main(Path(sys.argv[1]))
