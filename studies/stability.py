"""`floatsim stability` (or `python -m studies stability`): how a cube floats, against its density
ratio r = rho_body / rho_water, two independent ways.

- Dynamic: a sweep (sim/sweeps/grid.py, run on any backend) of r from 0.02 to 0.98, each from random initial
  orientations, on the exact panel model with damping, run until at rest; the final tilt of the face
  normal nearest the vertical (0: face up, 45: edge up, 54.7: corner up).
- Static: at each r, the orientation of least potential U = M g (z_G - z_B) over all orientations
  (sim/hydro/hydrostatics.py: Nelder-Mead from face-, edge- and corner-up and random starts), with no
  dynamics at all.

Each dynamic case is a dot, coloured by how it settled: at rest in the lowest-energy state the sweep
found at its r, at rest elsewhere (a local minimum), or still moving at the end. The static answer is
drawn over them. Writes reports/stability.png and reports/stability.md.
"""

from __future__ import annotations

import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from sim.commands.sweep import SweepArgs
from sim.commands.sweep import sweep as run_sweep
from sim.errors import ConfigError
from sim.scene.config import FluidConfig

REPORTS = Path(__file__).resolve().parent.parent / "reports"


@dataclass
class StabilityArgs:
    """The floating cube's stability diagram: final tilt against density ratio, by simulation and by energy minimisation."""

    ratios: int = 49
    """Density ratios from 0.02 to 0.98."""
    seeds: int = 8
    """Random initial orientations per ratio."""
    t_end: float = 120.0
    """Longest simulated time per case, s (cases stop once at rest)."""
    damping: float = 300.0
    """Viscous damping, N s/m^3 (enough to settle within t_end)."""
    backend: Literal["serial", "local", "dask"] = "local"
    """Where the sweep runs."""
    workers: int | None = None
    scheduler: str | None = None
    out: str = str(REPORTS / "stability")
    """Figure and page: OUT.png and OUT.md; the sweep's results in OUT-sweep/."""
    resume: bool = False
    """Finish an interrupted sweep in OUT-sweep/."""
    progress: bool | None = None


CANDIDATES = {"face up": 0.0, "edge up": 45.0, "corner up": math.degrees(math.acos(1 / math.sqrt(3)))}


def starts() -> list[np.ndarray]:
    from scipy.spatial.transform import Rotation

    corner = Rotation.align_vectors([[0.0, 0.0, 1.0]], [[1.0, 1.0, 1.0]])[0].as_matrix()
    return [np.eye(3), Rotation.from_euler("x", 45, degrees=True).as_matrix(), corner, *Rotation.random(3, random_state=1).as_matrix()]


def static_tilts(ratios: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Tilt (degrees) and potential (J) of the least-energy orientation of the 1 m cube at each ratio."""
    from sim.bodies.body import make_box
    from sim.bodies.rotation import matrix_to_quat
    from sim.hydro.hydrostatics import lowest_orientation
    from sim.sweeps.chunk import nearest_face_tilt

    fluid = FluidConfig()
    tilts, energies = [], []
    for r in ratios:
        body = make_box((1.0, 1.0, 1.0), 2, float(r) * fluid.rho)
        R, U = lowest_orientation(body, fluid, starts())
        tilts.append(nearest_face_tilt(body, matrix_to_quat(R)))
        energies.append(U)
    return np.array(tilts), np.array(energies)


def sweep_args(args: StabilityArgs, out: str) -> SweepArgs:
    return SweepArgs(param=(f"density=20:980:{args.ratios}", f"orientation_seed=0:{args.seeds - 1}:{args.seeds}"), scene="rest",
                     set=("fluid.forces=panels", f"fluid.damping={args.damping}", "step.integrator=implicit", "step.dt=0.01"),
                     t_end=args.t_end, settle=True, out=out, backend=args.backend, workers=args.workers, scheduler=args.scheduler,
                     resume=args.resume, progress=args.progress, chunk=16)  # fmt: skip


def classify(results, tol_deg: float = 2.0):
    """Per case: 'lowest' (at rest within tol of the least-energy rest state found at its ratio),
    'other' (at rest elsewhere), 'moving' (not at rest by the end), 'diverged'."""
    import pandas as pd

    results = results.copy()
    results["r"] = results["density"] / 1000.0
    kinds = []
    best = results[results.status == "rest"].groupby("r")["E_total"].min()
    for _, row in results.iterrows():
        if row.status == "diverged":
            kinds.append("diverged")
        elif row.status != "rest":
            kinds.append("moving")
        else:
            kinds.append("lowest" if row.E_total <= best[row.r] + 1e-3 * 1000 * row.r * 9.81 else "other")
    results["settled"] = pd.Categorical(kinds, ["lowest", "other", "moving", "diverged"])
    return results


def lowest_found(results) -> dict[float, float]:
    """Tilt of the lowest-energy rest state the sweep found at each ratio."""
    rest = results[results.status == "rest"]
    return {r: float(g.loc[g.E_total.idxmin(), "tilt_deg"]) for r, g in rest.groupby("r")}


def figure(results, ratios, static, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colours = {"lowest": "#1c7ed6", "other": "#f59f00", "moving": "#868e96", "diverged": "#e03131"}
    labels = {"lowest": "at rest, lowest energy found", "other": "at rest in another (local) minimum", "moving": "still moving at the end",
              "diverged": "diverged"}  # fmt: skip
    fig, ax = plt.subplots(figsize=(8, 4.6))
    for name, colour in colours.items():
        sel = results[results.settled == name]
        if len(sel):
            ax.scatter(sel.r, sel.tilt_deg, s=14, color=colour, alpha=0.8, label=f"{labels[name]} ({len(sel)})", zorder=3)
    ax.plot(ratios, static, "k-", lw=1.2, label="static: least potential M g (z_G - z_B)", zorder=2)
    for name, angle in CANDIDATES.items():
        ax.axhline(angle, color="0.8", lw=0.8, zorder=1)
        ax.text(0.99, angle + 0.8, name, transform=ax.get_yaxis_transform(), ha="right", fontsize=8, color="0.4")
    ax.set_xlabel("density ratio r = ρ_body / ρ_water")
    ax.set_ylabel("tilt of the nearest face normal (°)")
    ax.set_title("A floating cube's stable orientation: simulation (dots) and energy minimum (line)")
    ax.set_xlim(0, 1)
    ax.set_ylim(-2, 58)
    ax.legend(fontsize=8, loc="center", bbox_to_anchor=(0.5, 0.42))
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def stability(args: StabilityArgs) -> int:
    import pandas as pd

    if args.ratios < 2 or args.seeds < 1:
        raise ConfigError("--ratios must be >= 2 and --seeds >= 1")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    folder = str(out) + "-sweep"
    if not args.resume and Path(folder).is_dir():  # a fresh run: results of an older one (older code, too) are not mixed in
        import shutil

        shutil.rmtree(folder)
    started = time.perf_counter()
    code = run_sweep(sweep_args(args, folder))
    if code not in (0, 3):
        return code
    dynamic_wall = time.perf_counter() - started
    results = classify(pd.read_parquet(folder))
    ratios = np.linspace(20.0, 980.0, args.ratios) / 1000.0  # exactly the sweep's densities / rho
    started = time.perf_counter()
    static, _ = static_tilts(ratios)
    static_wall = time.perf_counter() - started
    figure(results, ratios, static, out.with_suffix(".png"))
    found = lowest_found(results)
    rows = []
    for r, s in zip(ratios, static):
        d = found.get(float(r), math.nan)
        group = results[results.r == r]
        share = (group.settled == "lowest").mean()
        rows.append((r, s, d, share))
    agree = sum(abs(s - d) <= 2.0 for _, s, d, _ in rows if not math.isnan(d))
    lines = [
        "# A floating cube's stability diagram",
        "",
        f"Generated by `floatsim stability` ({args.ratios} ratios x {args.seeds} random orientations, panels, damping {args.damping:g} N s/m^3, "
        f"backend {args.backend}; sweep {dynamic_wall:.0f} s, static minimisation {static_wall:.0f} s).",
        "",
        f"![stability diagram]({out.with_suffix('.png').name})",
        "",
        f"The lowest-energy rest state the simulations found agrees with the static minimum within 2° at {agree} of {len(rows)} ratios.",
        "",
        "| r | static tilt (°) | lowest found by simulation (°) | cases reaching it |",
        "|---|---|---|---|",
        *(f"| {r:.2f} | {s:.2f} | {d:.2f} | {share:.0%} |" for r, s, d, share in rows),
    ]
    out.with_suffix(".md").write_text("\n".join(lines) + "\n")
    print(f"{out.with_suffix('.png')} and {out.with_suffix('.md')}: agreement within 2° at {agree} of {len(rows)} ratios")
    return 0


if __name__ == "__main__":
    import tyro

    sys.exit(stability(tyro.cli(StabilityArgs)))
