"""`python -m studies figures`: the source report's figures reproduced with floatsim, and where the corrected model differs.

Writes OUT_DIR/seed-figures.md with its PNGs in OUT_DIR/seed-figures/, plus numbers.json there: every number
the page states, as computed by the runs (nothing in the text is typed by hand). One section per figure
group of the report (`seed/000_069c8b0ce5e5c6f5.txt`). `compute` runs the simulations and force probes,
`numbers` derives each section's numbers, `plot` draws, `text` writes; this module assembles the page.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from pathlib import Path

from .. import common
from ..common import fmt
from . import numbers, plot, text
from .compute import DAMPING_SCALE, DENSITIES, REPORT_DAMPING, Cube, Trace, damped_probes, grid_study, plan, record, report_grid

PAGE = "seed-figures.md"
ASSETS = "seed-figures"


@dataclass
class FiguresArgs:
    """Regenerate OUT_DIR/seed-figures.md: the source report's figures reproduced with floatsim, section by section."""

    out_dir: str = "reports"
    """Folder for seed-figures.md; the PNGs and numbers.json go to OUT_DIR/seed-figures/."""
    quick: bool = False
    """Short runs (a few simulated seconds, dt 0.01 s) and no browser render: the same sections in seconds, for tests."""
    viewer: bool = True
    """Render the resting cube in the live viewer (app/, headless chromium); a matplotlib render is used if that fails."""
    progress: bool | None = None
    """Show a progress bar (default: only on a terminal, never under CI)."""


class Page:
    """The markdown page, built section by section; figures are saved as they are made, numbers kept for numbers.json."""

    def __init__(self, out: Path, assets: Path):
        self.out, self.assets = out, assets
        self.nums: dict = {}
        self.parts: list[str] = []
        self.images: list[str] = []

    def add(self, section: str) -> None:
        self.parts.append(section.strip() + "\n")

    def save(self, fig, name: str, alt: str) -> str:
        """Write `fig` next to the page; its markdown image link."""
        common.save(fig, self.assets / name, dpi=100, tight=True)
        return self.image(name, alt)

    def image(self, name: str, alt: str) -> str:
        self.images.append(name)
        return f"![{alt}]({ASSETS}/{name})"

    def write(self) -> None:
        (self.out / PAGE).write_text("\n".join(self.parts))
        (self.assets / "numbers.json").write_text(json.dumps(self.nums, indent=1, sort_keys=True) + "\n")


def figures(args: FiguresArgs) -> int:
    common.pyplot()  # the Agg backend before anything draws
    started = time.perf_counter()
    out = Path(args.out_dir)
    assets = out / ASSETS
    assets.mkdir(parents=True, exist_ok=True)
    d_low, d_high = (DAMPING_SCALE * c for c in REPORT_DAMPING)
    specs = plan(args.quick, d_low, d_high)
    bar = common.progress(sum(s.steps() for s in specs), flag=args.progress)
    try:
        traces = {spec.key: record(spec, bar) for spec in specs}
    finally:
        bar.close()
    cube = Cube()
    page = Page(out, assets)
    page.nums["quick"] = args.quick
    rest = traces["rest"]
    page.add(text.intro(args.quick, cube, rest.body.n_samples, rest.spec.config().body.points_per_edge))
    _samples(page, cube)
    _rest(page, cube, traces)
    _angular_momentum(page, traces)
    _force_at_rest(page, traces)
    _densities(page, cube, traces)
    _damped(page, args, cube, traces)
    page.write()
    wall = time.perf_counter() - started
    sim_wall = sum(t.wall for t in traces.values())
    print(f"wrote {out / PAGE} with {len(page.images)} figures in {wall:.1f} s wall ({sim_wall:.1f} s simulating)")
    return 0


# ---- the sections: numbers, figures, text -----------------------------------------------------------------


def _samples(page: Page, cube: Cube) -> None:
    rows, sweep = grid_study(cube)
    n = numbers.samples(cube, rows, sweep)
    page.nums.update(n)
    fig1 = page.save(plot.samples_3d(cube), "fig1_samples.png", "Figure 1: the report's sample grid against floatsim's, with normals")
    fig2 = page.save(plot.sample_areas(cube, sweep), "fig2_area.png", "Figure 2: what each sample's area covers, and the errors against N")
    page.add(text.samples(cube, rows, n, fig1, fig2))


def _rest(page: Page, cube: Cube, traces: dict[str, Trace]) -> None:
    ours, spun = traces["rest"], traces["rest_spin"]
    n = page.nums["rest"] = numbers.rest(cube, ours, spun)
    image = page.save(
        plot.rest(cube, ours, spun, n["spin_omega"]), "fig3_rest.png", "Figure 3: z(t) of the cube placed at rest at z = -0.4"
    )
    page.add(text.rest(ours, spun, n, image))


def _angular_momentum(page: Page, traces: dict[str, Trace]) -> None:
    runs = [traces[k] for k in ("spin_euler_coarse", "spin_euler_fine", "spin_implicit")]
    free = traces["spin_free"]
    n = page.nums["spin"] = numbers.spin(runs, free)
    image = page.save(plot.angular_momentum(runs, free), "fig4_5_angular_momentum.png", "Figures 4-5: |L| against time for two time steps")
    page.add(text.angular_momentum(runs, free, n, image))


def _force_at_rest(page: Page, traces: dict[str, Trace]) -> None:
    tr = traces["rest"]
    n = page.nums["force_at_rest"] = numbers.force_at_rest(tr, page.nums["grid"]["10"])
    image = page.save(plot.force_at_rest(tr, n["report_grid_F_rel"]), "fig6_force_at_rest.png", "Figure 6: |F_total| of the cube at rest")
    page.add(text.force_at_rest(tr, n, image))


def _densities(page: Page, cube: Cube, traces: dict[str, Trace]) -> None:
    runs = [traces[f"drop_{d:g}"] for d in DENSITIES]
    n = page.nums["densities"] = numbers.densities(cube, runs)
    image = page.save(plot.densities(runs), "density.png", "z(t) for four densities")
    page.add(text.densities(cube, runs, n, image))


def _resting_pose(page: Page, args: FiguresArgs, yawed: Trace) -> tuple[list[str], str]:
    """Figure 7 from the viewer if it can be driven, else matplotlib: the image links and what rendered them."""
    paths = {name: page.assets / f"fig7_resting_pose_{name}.png" for name in plot.VIEWS}
    why = (
        "the quick setting skips the browser"
        if args.quick
        else ("--no-viewer was given" if not args.viewer else plot.viewer_render(yawed, paths))
    )
    page.nums["fig7_source"] = "viewer" if why is None else "matplotlib"
    if why is None:
        source = ("the live viewer (`app/`, viser in headless chromium, `client.get_render`), paused at the run's final pose "
                  "(samples blue under water, orange above; the top view has +x to the right, +y up, and the water grid's lines along x and y)")  # fmt: skip
        return [page.image(p.name, f"Figure 7: resting pose in the viewer, {name} view") for name, p in paths.items()], source
    source = f"matplotlib (the viewer render was not used: {why})"
    return [page.save(plot.render_mpl(yawed, name), p.name, f"Figure 7: resting pose, {name} view") for name, p in paths.items()], source


def _damped(page: Page, args: FiguresArgs, cube: Cube, traces: dict[str, Trace]) -> None:
    runs = [traces["damped_low"], traces["damped_high"]]
    yawed = traces["damped_yaw"]
    n = page.nums["damped"] = numbers.damped(cube, runs + [yawed], damped_probes(runs + [yawed], cube))
    images, source = _resting_pose(page, args, yawed)
    figure = page.save(plot.damped(runs, yawed), "fig8_9_damped.png", "Figures 8-9: |L| and |F| against time for two damping constants")
    page.add(text.damped(cube, runs, yawed, n, figure, images, source))


__all__ = ["ASSETS", "PAGE", "FiguresArgs", "figures", "fmt", "report_grid"]
