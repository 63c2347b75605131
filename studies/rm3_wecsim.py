"""What the `rm3-wecsim-moorings` preset ships, derived from WEC-Sim's and SEA-Stack's open files.

WEC-Sim's RM3 with three catenary chains on MoorDyn (WEC-Sim Applications' Mooring/MoorDyn case, WEC-Sim 6.1), as
SEA-Stack (github.com/Project-SEA-Stack/SEA-Stack, MIT licence, commit 4d1eae6) keeps its results. Four things,
each written by a subcommand from the other projects' files (none of those files is kept here):

- `meshes`: the float and the spar with its heave plate as WEC-Sim's WAMIT panels outline them (SEA-Stack's
  float_global.obj and spar_global.obj, half meshes): the float an annulus 3 to 10 m in radius, 2 m freeboard, its
  bottom at -2 m at the rim sloping to -3 m at r = 5 m; the spar a column 6 m across, 29 m draft, on a plate 30 m
  across and 0.1 m thick; 72 sections round (WAMIT's waterplanes to 0.02 %).
- `coefficients PATH/rm3.out`: WEC-Sim's WAMIT run of the two bodies (WEC-Sim's examples/RM3/hydroData/rm3.out,
  Apache-2.0, commit a23d299; infinite depth, 260 periods, heading 0) read by sim/io/wamit.py and split over these
  meshes (sim/io/bem_file.py), into assets/coefficients/imported/rm3_wecsim.npz. A Capytaine solve cannot stand in:
  its constant panels resolve a 0.1 m plate only slowly (heave added mass 8.3e6 kg at 9760 panels against WAMIT's
  9.0e6, itself the thin disc's 8/3 rho a^3).
- `record PATH/TO/SEA-Stack`: the sea WEC-Sim ran, its elevation at the origin (data/verification/rm3_mooring/
  normalized/wecsim_moordyn_wave_elevation.txt: WEC-Sim's imported etaData.mat with its 40 s ramp, as it ran), band
  limited to 5 rad/s and resampled at 0.1 s, ending in a 10 s fade to still water (so that the record's periodic
  extension has no jump), into assets/records/rm3_wecsim_eta.csv.
- `reference PATH/TO/SEA-Stack`: statistics of WEC-Sim's results over 100-400 s (the fairlead tensions of its three
  upper lines, the float's and the plate's heave), into assets/reference/rm3_mooring.json.

Run: python -m studies.rm3_wecsim meshes | coefficients FILE | record DIR | reference DIR
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
MESHES = ROOT / "assets" / "meshes"
COEFFICIENTS = ROOT / "assets" / "coefficients" / "imported" / "rm3_wecsim.npz"
RECORD = ROOT / "assets" / "records" / "rm3_wecsim_eta.csv"
REFERENCE = ROOT / "assets" / "reference" / "rm3_mooring.json"
NORMALIZED = "data/verification/rm3_mooring/normalized"
SEA_STACK = "4d1eae6453f0cd775ab3184d579ce7d943dbfda7"
WEC_SIM = "a23d2993807410fe78cc63546c1ba9d81912024f"
SECTIONS = 72
WINDOW = (100.0, 400.0)
"""The span the statistics cover, s: after the ramp (40 s) and the lines' and bodies' start-up."""


def meshes() -> None:
    from sim.hydro.bem import wet_mesh
    from studies.rm3_meshes import _outline, revolved

    parts = {
        "rm3_wecsim_float": [(3.0, -3.0), (5.0, -3.0), (10.0, -2.0), (10.0, 2.0), (3.0, 2.0), (3.0, -3.0)],
        "rm3_wecsim_spar": [(0.0, -29.0), (15.0, -29.0), (15.0, -28.9), (3.0, -28.9), (3.0, 8.9), (0.0, 8.9)],
    }
    for name, corners in parts.items():
        mesh = revolved(_outline(corners, 2.0), SECTIONS)
        mesh.export(MESHES / f"{name}.stl")
        wv, wf = wet_mesh(mesh.vertices, mesh.faces, 100.0)
        W = wv[wf]  # the lid at z = 0 adds nothing to the divergence theorem's r . n
        below = -np.einsum("ki,ki->k", W.mean(axis=1), np.cross(W[:, 1] - W[:, 0], W[:, 2] - W[:, 0])).sum() / 6
        print(f"{MESHES / name}.stl: {len(mesh.faces)} triangles, {below:.2f} m^3 under the water line")


def coefficients(out: str) -> None:
    """The preset's bodies with the WAMIT file, through the same path a scene naming the .out takes."""
    import dataclasses

    from sim.scene.config import load_scene
    from sim.system.tree import build

    scene = load_scene("rm3-wecsim-moorings")
    scene = dataclasses.replace(scene, fluid=dataclasses.replace(scene.fluid, bem_file=str(Path(out).resolve())),
                                moorings=dataclasses.replace(scene.moorings, line_file=""))  # fmt: skip
    system, _ = build(scene)
    COEFFICIENTS.parent.mkdir(parents=True, exist_ok=True)
    system.radiation.coefficients.save(COEFFICIENTS)
    print(COEFFICIENTS)


def _series(root: Path, name: str) -> np.ndarray:
    return np.loadtxt(root / NORMALIZED / f"wecsim_moordyn_{name}.txt", comments="#")


BAND = 5.0
"""rad/s: the record's components above this are left out (they hold under 0.1 % of its variance)."""
STEP = 0.1
FADE = 10.0


def record(root: str) -> None:
    e = _series(Path(root), "wave_elevation")
    t, eta = e[:, 0], e[:, 1]
    dt = float(t[1] - t[0])
    tail = np.arange(1, round(FADE / dt) + 1) * dt
    eta = np.concatenate([eta, eta[-1] * 0.5 * (1 + np.cos(np.pi * tail / FADE))])  # still water at both ends: no jump to ring on
    t = np.concatenate([t, t[-1] + tail])
    spectrum = np.fft.rfft(eta)
    spectrum[2 * np.pi * np.fft.rfftfreq(len(eta), dt) > BAND] = 0.0
    times = np.arange(0.0, t[-1] + STEP / 2, STEP)
    values = np.interp(times, t, np.fft.irfft(spectrum, len(eta)))
    RECORD.parent.mkdir(parents=True, exist_ok=True)
    header = (f"# The sea of WEC-Sim's RM3 MoorDyn case (WEC-Sim Applications, Apache-2.0) as it ran, ramp included: SEA-Stack's "
              f"{NORMALIZED}/wecsim_moordyn_wave_elevation.txt (MIT, commit {SEA_STACK[:7]}), band-limited to {BAND:g} rad/s, "
              f"resampled at {STEP:g} s, a {FADE:g} s fade to still water appended (studies/rm3_wecsim.py)\ntime_s,eta_m\n")  # fmt: skip
    RECORD.write_text(header + "".join(f"{a:.1f},{b:.5f}\n" for a, b in zip(times, values)))
    print(f"{RECORD}: {len(times)} rows, std over {WINDOW} s {values[(times >= WINDOW[0]) & (times <= WINDOW[1])].std():.4f} m")


def statistics(t: np.ndarray, y: np.ndarray) -> dict:
    inside = (t >= WINDOW[0]) & (t <= WINDOW[1])
    return {"mean": float(y[inside].mean()), "std": float(y[inside].std()), "min": float(y[inside].min()), "max": float(y[inside].max())}


def reference(root: str) -> None:
    base = Path(root)
    motions, tensions, elevation = (_series(base, name) for name in ("body_motions", "fairlead_tensions", "wave_elevation"))
    stats = {
        "source": f"SEA-Stack (github.com/Project-SEA-Stack/SEA-Stack, MIT licence) commit {SEA_STACK}, {NORMALIZED}: WEC-Sim 6.1 "
        "with MoorDyn, WEC-Sim Applications' Mooring/MoorDyn RM3 case (Apache-2.0), dt 0.01 s, 400 s, 40 s ramp",
        "window_s": list(WINDOW),
        "units": {"tension": "N", "heave": "m (centre of mass z)", "elevation": "m"},
        "elevation": statistics(elevation[:, 0], elevation[:, 1]),
        "float heave": statistics(motions[:, 0], motions[:, 1]),
        "plate heave": statistics(motions[:, 0], motions[:, 2]),
        "tensions": {name: statistics(tensions[:, 0], tensions[:, k + 1]) for k, name in enumerate(("line 4", "line 5", "line 6"))},
    }
    REFERENCE.write_text(json.dumps(stats, indent=1) + "\n")
    print(REFERENCE)


def main(argv: list[str]) -> int:
    commands = {"meshes": meshes, "coefficients": coefficients, "record": record, "reference": reference}
    if not argv or argv[0] not in commands or len(argv) != (1 if argv[0] == "meshes" else 2):
        print(__doc__.strip().splitlines()[-1], file=sys.stderr)
        return 2
    commands[argv[0]](*argv[1:])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
