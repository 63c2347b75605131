"""`python -m studies report`: the accuracy report, OUT_DIR/accuracy.md with figures in OUT_DIR/accuracy/.

Nine parts, every number computed from runs made by this command (nothing hand-typed): work-precision
diagrams with observed orders, the sampled model's error against the exact panel model as N grows, a
stability map of the fixed-step integrators over damping and density, a verdict table (cheapest
method per target accuracy), a table of stiff and extreme cases, and where the energy can rise with
a map of the sampled model's steady rocking and drift over density and N (`leak`), and the response in waves
with and without the diffraction force, time domain against frequency domain (`excitation`), the radiation memory's
passivity: its fitted damping's smallest eigenvalue for every shipped solve and rm3 without a damper kicked in still water
(`passivity`), and drifting bodies: a free sphere's heave a quarter wave from its start against a slide, and its start-up
with and without the wave ramp (`drifting`).

`compute` runs the simulations and returns plain data, `numbers` derives what the text quotes, `plot`
draws and `text` writes the markdown. Wall-clock figures are medians of `repeats` runs, single-threaded.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import common
from . import numbers, plot, plot_bodies, text
from .compute import (
    ADAPTIVE,
    FIXED,
    FULL,
    QUICK,
    Extreme,
    ModelError,
    Settings,
    StabilityMap,
    StiffRow,
    WPPoint,
    WPResult,
    extreme_cases,
    model_error,
    stability_map,
    stiff_rows,
    work_precision,
)
from .drifting import FULL_DRIFT, QUICK_DRIFT, Drifting, DriftSettings, compute_drifting
from .excitation import FULL_EXCITATION, QUICK_EXCITATION, Excitation, ExcitationSettings, compute_excitation
from .leak import FULL_LEAK, QUICK_LEAK, Leak, LeakSettings, compute_leak
from .passivity import FULL_PASSIVITY, QUICK_PASSIVITY, Passivity, PassivitySettings, compute_passivity


@dataclass
class ReportArgs:
    """Write the accuracy report (work-precision, model error, stability map, verdict, stiff and extreme cases, energy and the sampled model's
    leak, excitation, the radiation memory's passivity, drifting bodies)."""

    out_dir: str = "reports"
    """Folder for accuracy.md; the figures go to OUT_DIR/accuracy/."""
    quick: bool = False
    """A short setting (fewer and shorter runs, ~20 s) for the test suite; the numbers are coarser."""
    repeats: int = 3
    """Timing repeats per run (wall-clock figures are their median)."""


@dataclass
class ReportData:
    settings: Settings
    machine: dict[str, str]
    wp: list[WPResult]
    model: ModelError
    stability: StabilityMap
    stiff: list[StiffRow]
    extremes: list[Extreme]
    messages: list[tuple[str, str]]
    verdict: dict[float, dict[str, WPPoint | None]]
    leak: Leak
    excitation: Excitation
    passivity: Passivity
    drifting: Drifting
    figures: list[str]
    seconds: float
    markdown: str = ""


@dataclass(frozen=True)
class Parts:
    """The settings of the parts after the integrators' (6 to 9)."""

    leak: LeakSettings
    excitation: ExcitationSettings
    passivity: PassivitySettings
    drifting: DriftSettings

    def jobs(self) -> int:
        return self.leak.jobs() + self.excitation.jobs() + self.passivity.jobs() + self.drifting.jobs()


FULL_PARTS = Parts(FULL_LEAK, FULL_EXCITATION, FULL_PASSIVITY, FULL_DRIFT)
QUICK_PARTS = Parts(QUICK_LEAK, QUICK_EXCITATION, QUICK_PASSIVITY, QUICK_DRIFT)


def compute_all(cfg: Settings, repeats: int, blas: str, parts: Parts) -> ReportData:
    """Every run of the report, with a progress bar; the orders, rates and verdict filled in."""
    bar = common.progress(cfg.jobs() + parts.jobs(), unit="run")

    def tick(n=1):
        bar.update(n)

    try:
        with np.errstate(over="ignore", invalid="ignore", divide="ignore", under="ignore"):
            info = common.machine(blas)
            common.warm_up((*FIXED, *ADAPTIVE))
            wp = [work_precision(case, cfg, repeats, tick) for case in cfg.cases]
            me = model_error(cfg, repeats, tick)
            st = stability_map(cfg, tick)
            stiff = stiff_rows(cfg, tick)
            extremes, messages = extreme_cases(cfg, tick)
            leak = compute_leak(parts.leak, tick)
            excitation = compute_excitation(parts.excitation, tick)
            passivity = compute_passivity(parts.passivity, tick)
            drifting = compute_drifting(parts.drifting, tick)
    finally:
        bar.close()
    for res in wp:
        res.orders = numbers.observed_orders(res)
    me.rates = numbers.model_rates(me)
    return ReportData(cfg, info, wp, me, st, stiff, extremes, messages, numbers.verdict(wp, cfg.targets), leak, excitation, passivity, drifting,
                      [], 0.0)  # fmt: skip


def draw_all(data: ReportData, fig_dir: Path, repeats: int) -> None:
    """Every figure, into fig_dir; their names go to data.figures."""
    cfg, cpu = data.settings, data.machine["CPU (/proc/cpuinfo)"]
    label = f"{cfg.horizon:g} s; {cpu}, {repeats} repeats"
    for res in data.wp:
        name = f"wp_{res.case.key}.png"
        plot.work_precision(res, fig_dir / name, label)
        data.figures.append(name)
    plot.model_error(data.model, fig_dir / "model_error.png", f"{cpu}, {repeats} repeats")
    plot.stability(data.stability, cfg, fig_dir / "stability.png")
    plot.creep(data.stiff, fig_dir / "stiff_creep.png")
    plot.leak(data.leak, fig_dir / "leak.png")
    plot.excitation(data.excitation, fig_dir / "excitation.png")
    plot_bodies.passivity(data.passivity, fig_dir / "passivity.png")
    plot_bodies.drifting(data.drifting, fig_dir / "drifting.png")
    data.figures += ["model_error.png", "stability.png", "stiff_creep.png", "leak.png", "excitation.png", "passivity.png", "drifting.png"]


def run_report(args: ReportArgs) -> ReportData:
    """Compute everything and write the markdown and figures; return the data (for tests)."""
    started = time.perf_counter()
    cfg = QUICK if args.quick else FULL
    out = Path(args.out_dir)
    fig_dir = out / "accuracy"
    fig_dir.mkdir(parents=True, exist_ok=True)
    blas = common.single_thread_blas()
    repeats = max(1, args.repeats)
    data = compute_all(cfg, repeats, blas, QUICK_PARTS if args.quick else FULL_PARTS)
    draw_all(data, fig_dir, repeats)
    data.seconds = time.perf_counter() - started
    data.markdown = text.markdown(data, args)
    (out / "accuracy.md").write_text(data.markdown)
    return data


def report(args: ReportArgs) -> int:
    data = run_report(args)
    print(f"wrote {Path(args.out_dir) / 'accuracy.md'} and {len(data.figures)} figures in {data.seconds:.0f} s")
    return 0


__all__ = ["FULL", "QUICK", "ReportArgs", "ReportData", "report", "run_report"]
