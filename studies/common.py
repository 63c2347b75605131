"""What both studies share: the machine they ran on, single-threaded BLAS, matplotlib set-up and saving,
markdown tables, number formatting, kernel warm-up and the progress bar."""

from __future__ import annotations

import ctypes
import math
import os
import platform
from pathlib import Path

import numpy as np

from sim import Simulation, load_scene, with_overrides

from . import probes

# ---- the machine ----------------------------------------------------------------------------------------


def single_thread_blas() -> str:
    """Limit the loaded OpenBLAS libraries to one thread (numpy may be imported before this module,
    so the environment variable can be too late); say what was done."""
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    os.environ.setdefault("MKL_NUM_THREADS", "1")
    done = []
    try:
        with open("/proc/self/maps") as f:
            libs = sorted({line.split()[-1] for line in f if "openblas" in line.lower() and line.split()[-1].startswith("/")})
    except OSError:
        libs = []
    for path in libs:
        try:
            lib = ctypes.CDLL(path)
        except OSError:
            continue
        for name in ("openblas_set_num_threads", "scipy_openblas_set_num_threads64_", "openblas_set_num_threads64_"):
            fn = getattr(lib, name, None)
            if fn is not None:
                fn(1)
                done.append(Path(path).name)
                break
    return f"set to 1 at run time in {', '.join(done)}" if done else f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}"


def cpu_name() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return "unknown"


def machine(blas: str) -> dict[str, str]:
    """The machine and software a timing was taken on, as (what, value) rows."""
    import scipy

    return {
        "CPU (/proc/cpuinfo)": cpu_name(),
        "platform.processor()": platform.processor() or "(empty)",
        "machine": f"{platform.machine()}, {os.cpu_count()} logical CPUs, load average {' '.join(f'{x:.2f}' for x in os.getloadavg())} at start",
        "Python / numpy / scipy": f"{platform.python_version()} / {np.__version__} / {scipy.__version__}",
        "stepping backend": f"{probes.stepping_backend()} for the fixed-step integrators; adaptive ones are scipy solve_ivp (numpy forces)",
        "BLAS threads": blas,
    }


def warm_up(methods: tuple[str, ...], forces: tuple[str, ...] = ("points", "panels")) -> None:
    """One short run of each integrator and force model, so one-off compilation is not timed."""
    for force_model in forces:
        for method in methods:
            sim = Simulation(with_overrides(load_scene("damped"), fluid__forces=force_model, step__integrator=method, step__dt=0.01))
            sim.step(2)


def progress(total: int, unit: str = "step", flag: bool | None = None):
    """A progress bar on a terminal, silent in CI logs and pipes (update(n), close())."""
    return probes.progress_bar(total, unit=unit, flag=flag)


# ---- matplotlib -----------------------------------------------------------------------------------------


def pyplot():
    """matplotlib.pyplot on the non-interactive Agg backend (imported only when a study draws)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save(fig, path: Path, dpi: int, tight: bool = False) -> None:
    """Write `fig` as a PNG and free it."""
    plt = pyplot()
    with np.errstate(divide="ignore", invalid="ignore"):  # log axes of values that reach zero
        fig.savefig(path, dpi=dpi, **({"bbox_inches": "tight"} if tight else {}))
    plt.close(fig)


# ---- markdown -------------------------------------------------------------------------------------------


def md_table(header: list[str], rows: list[list]) -> list[str]:
    """A markdown table as lines (a '|' inside a cell becomes '/')."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c).replace("|", "/") for c in row) + " |" for row in rows]
    return lines


def fmt(x: float, digits: int = 3) -> str:
    """A number for the text: plain for ordinary magnitudes, a x 10^k otherwise."""
    if x == 0 or not math.isfinite(x):
        return f"{x:g}"
    if 1e-3 <= abs(x) < 1e5:
        text = f"{x:.{digits}g}"
        return f"{float(text):.0f}" if "e" in text else text
    mantissa, exponent = f"{x:.{digits - 1}e}".split("e")
    return f"{mantissa} x 10^{int(exponent)}"


def pct(x: float, digits: int = 3) -> str:
    return f"{fmt(100 * x, digits)} %"


def fmt_spec(x: float | None, spec: str = ".2e") -> str:
    """`format(x, spec)`, or 'n/a' for a missing or non-finite number."""
    return "n/a" if x is None or not np.isfinite(x) else format(x, spec)


def publish_cross_code(name: str, runs, compare, table, figure, page: str, source: str) -> int:
    """A cross-code page (`python -m studies f3of`, `rm3-mooring`): `runs(folder)` runs floatsim's scenes as their user
    does, `compare` takes their statistics against the other codes', `table` prints them; the figure goes to
    reports/accuracy/NAME.png and the page (`page` formatted with the table and the data's `source`) to reports/NAME.md."""
    import tempfile

    reports = Path(__file__).resolve().parent.parent / "reports"
    with tempfile.TemporaryDirectory() as tmp:
        results = runs(Path(tmp))
    rows = compare(results)
    text = table(rows)
    print(text)
    (reports / "accuracy").mkdir(parents=True, exist_ok=True)
    figure(rows, results, reports / "accuracy" / f"{name}.png")
    (reports / f"{name}.md").write_text(page.format(table=text, source=source))
    return 0
