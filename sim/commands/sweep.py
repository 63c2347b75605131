"""`floatsim sweep`: a grid of cases (any parameters, each a list or a range, and random initial
orientations), run in chunks on one core, every core or a Dask cluster, each chunk's results written
as a Parquet file as it completes; `--resume` finishes only what is missing."""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
import os
import re
import shlex
import sys
import time
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Literal

import tyro

from sim.errors import ConfigError, Interrupted, WriteFailed
from sim.io import netcdf
from sim.limits import BYTES_PER_SAMPLE, MAX_CASES, MAX_HISTORY_BYTES, check_memory, size
from sim.scene.config import available_scenes
from sim.sweeps.backends import WorkerLost, run
from sim.sweeps.grid import BODY_VARIABLE, START, VARIABLE, Sweep, case_scene, chunks, load_sweep_file, parse_param

from .interrupt import EXIT, StopOnCtrlC
from .output import reason, temporaries, write_whole
from .progress import progress_bar
from .run import check_output

MANIFEST = "_manifest.json"
"""Names starting with '_' are skipped by pyarrow/pandas when reading the folder as one table."""
HISTORY = "_history"


@dataclass
class SweepArgs:
    """Run a grid of cases and write one row of results per case (Parquet, one file per chunk, in --out)."""

    param: Annotated[tuple[str, ...], tyro.conf.UseAppendAction] = ()
    """NAME=VALUES, repeatable: a range FROM:TO:COUNT (ends included) or a list V1,V2,... The product of all is run.
    NAME: a body, water, wave or step parameter (density, damping, drag_coefficient, hs, integrator, ...), z0, tilt or orientation_seed."""
    file: str | None = None
    """A TOML sweep file (scene, params, set, settle, ...); flags given here override it."""
    scene: Annotated[
        str | None,
        tyro.conf.arg(metavar="NAME|FILE", help=f"Preset name ({', '.join(available_scenes())}) or scene .toml (default: damped)."),
    ] = None
    """Preset name or scene .toml (default: damped; the presets are listed in --help)."""
    set: Annotated[tuple[str, ...], tyro.conf.UseAppendAction] = ()
    """SECTION.KEY=VALUE, repeatable: a fixed change to the scene for every case (e.g. fluid.forces=panels)."""
    t_end: float | None = None
    """Simulated duration of each case, s (default: the scene's)."""
    dt: float | None = None
    """Time step, s."""
    integrator: str | None = None
    """Integrator (fixed-step ones run compiled)."""
    settle: bool = False
    """Stop each case once it is at rest, and record when (default: run to the end, or the file's `settle`)."""
    out: str = "sweep"
    """Folder of results: chunk-NNNNN.parquet (read the folder with pandas.read_parquet), _manifest.json, _history/."""
    backend: Literal["serial", "local", "dask"] = "serial"
    """serial: this process; local: one process per core; dask: a Dask LocalCluster, or --scheduler's workers."""
    workers: int | None = None
    """Worker processes for local and a dask LocalCluster (default: every core)."""
    scheduler: str | None = None
    """Address of a running Dask scheduler (tcp://host:8786); implies --backend dask."""
    timeout: float = 10.0
    """Seconds to wait for the scheduler to answer."""
    chunk: int | None = None
    """Cases per chunk (default: 64, or fewer so that every worker gets one: ceil(cases / workers) on local and a dask
    LocalCluster; --resume keeps the sweep's own; cases that cannot share an ensemble never share a chunk)."""
    resume: bool = False
    """Finish a sweep in --out: run only the chunks not done (a chunk file missing, unreadable or unlike its checksum in the manifest runs again)."""
    history_every: int | None = None
    """Also keep each case's pose every K steps (in --out/_history/)."""
    progress: bool | None = None
    """Progress bar (default: only on a terminal, never under CI)."""
    netcdf: str | None = None
    """Also gather every case's results into this netCDF file once the sweep is whole: the swept parameters its
    dimensions, each result a variable over them with its units (a farm's power matrix: d1_power over hs and tp;
    xarray.open_dataset reads it; the netcdf extra)."""


def parse_set(item: str) -> tuple[str, object]:
    if "=" not in item or "." not in item.split("=", 1)[0]:
        raise ConfigError(f"--set {item!r}: write SECTION.KEY=VALUE, e.g. fluid.forces=panels")
    key, text = item.split("=", 1)
    section, name = key.strip().split(".", 1)
    try:
        value: object = json.loads(text)
    except json.JSONDecodeError:
        value = text
    return f"{section}__{name}", value


def whole(value, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise ConfigError(f"sweep file: {name} must be a whole number, got {value!r}")
    return value


def set_table(table: dict) -> list[tuple[str, object]]:
    """A sweep file's [set] table, as 'section.key' = value or as [set.section] key = value."""
    items = []
    for section, value in table.items():
        if isinstance(value, dict):
            items += [(f"{section}__{key}", v) for key, v in value.items()]
        elif "." in section:
            head, key = section.split(".", 1)
            items.append((f"{head}__{key}", value))
        else:
            raise ConfigError(f"sweep file [set]: write SECTION.KEY = VALUE, got {section!r}")
    return items


def build(args: SweepArgs) -> Sweep:
    """The sweep a command line (and its file) describes, validated: every case's scene is checked."""
    data = load_sweep_file(args.file) if args.file else {}
    params = dict(data.get("params", []))
    for item in args.param:
        name, values = parse_param(item)
        params[name] = values
    if not params:
        raise ConfigError("nothing to sweep: give --param NAME=VALUES (e.g. --param density=100:900:41) or --file")
    overrides = dict(set_table(data.get("set", {})))
    overrides.update(dict(parse_set(s) for s in args.set))
    for key, flag in (("t_end", args.t_end), ("dt", args.dt), ("integrator", args.integrator)):
        value = flag if flag is not None else data.get(key)
        if value is not None:
            overrides[f"step__{key}"] = value
    chunk = args.chunk if args.chunk is not None else whole(data["chunk"], "chunk") if "chunk" in data else None
    if chunk is None:
        chunk = resumed_chunk(args) or default_chunk(math.prod(len(v) for v in params.values()), args)
    if chunk < 1:
        raise ConfigError(f"--chunk must be >= 1, got {chunk}")
    every = args.history_every if args.history_every is not None else whole(data.get("history_every", 0), "history_every")
    if every < 0:
        raise ConfigError(f"--history-every must be >= 0, got {every}")
    settle = args.settle or bool(data.get("settle", False))
    scene = args.scene or data.get("scene", "damped")
    sweep = Sweep(scene, tuple(params.items()), tuple(sorted(overrides.items())), settle, chunk, every)
    check_size(sweep)
    base = sweep.base()
    if base.bodies and (settle or every):
        raise ConfigError(f"--{'settle' if settle else 'history-every'} is for one-body scenes: a sweep of several bodies runs each case to "
                          "t_end and reports its take-offs' power and amplitudes")  # fmt: skip
    for case in sweep.cases():  # any bad value fails here, with its one line, before anything runs
        case_scene(base, case)
    return sweep


CHUNK = 64
"""Most cases in a chunk unless asked (--chunk)."""


def default_chunk(cases: int, args: SweepArgs) -> int:
    """CHUNK, or fewer so that each worker of `local` or a dask LocalCluster gets one (7 cases on 2 cores ran as one
    chunk of 7 on one core): ceil(cases / workers). A running scheduler's workers are not known before it answers: CHUNK."""
    if args.scheduler or args.backend == "serial":
        return CHUNK
    workers = args.workers or os.cpu_count() or 1
    return max(1, min(CHUNK, math.ceil(cases / workers)))


def resumed_chunk(args: SweepArgs) -> int | None:
    """With --resume and no --chunk: the chunk size the sweep in --out was started with (its chunks, and its key,
    depend on it, and the default depends on the workers, which may differ this time)."""
    if not args.resume:
        return None
    try:
        chunk = json.loads((Path(args.out) / MANIFEST).read_text()).get("chunk")
    except (OSError, ValueError, AttributeError):
        return None  # no manifest, or a damaged one: open_folder says so
    return chunk if isinstance(chunk, int) and not isinstance(chunk, bool) and chunk >= 1 else None


def check_size(sweep: Sweep) -> None:
    """The sweep's cases, its histories and one chunk in memory, against the stated limits."""
    n = len(sweep)
    if n > MAX_CASES:
        raise ConfigError(f"{n:,} cases is over the limit of {MAX_CASES:,}: use fewer values in --param, or split the sweep")
    base = sweep.base()
    steps = round(base.step.t_end / base.step.dt)
    samples = 6 * base.body.points_per_edge**2 if base.body.shape != "mesh" else base.body.samples
    check_memory(
        f"a chunk of {min(n, sweep.chunk)} cases of {samples:,} samples", min(n, sweep.chunk) * samples * BYTES_PER_SAMPLE, "--chunk"
    )
    if sweep.history_every:
        rows = steps // sweep.history_every + 1
        total = n * rows * 9 * 8
        if total > MAX_HISTORY_BYTES:
            raise ConfigError(f"histories of {n:,} cases x {rows:,} rows need about {size(total)}, over the limit of {size(MAX_HISTORY_BYTES)}: "
                              "raise --history-every")  # fmt: skip
        check_memory(f"the histories of a chunk ({min(n, sweep.chunk)} cases x {rows:,} rows)", min(n, sweep.chunk) * rows * 9 * 8 * 4,
                     "--history-every or --chunk")  # fmt: skip


def sweep(args: SweepArgs) -> int:
    check_output(args.netcdf, flag="netcdf", suffix=".nc", overwrite=False)  # (an earlier run's netCDF is replaced; no other file)
    spec = build(args)
    backend = "dask" if args.scheduler else args.backend
    base = spec.base()
    cases = spec.cases()
    scenes = [case_scene(base, c) for c in cases]
    plan = chunks(spec, scenes)
    out = Path(args.out)
    key = spec.key()
    files = open_folder(out, key, args.resume)
    if out.is_dir():
        remove_temporaries(out)
    todo = [(cid, idx) for cid, idx in enumerate(plan)]
    if files is not None:  # resuming: only chunks whose files check out count as done
        todo, files = verify(out, plan, files, bool(spec.history_every))
    files = files or {}
    info = {"key": key, "scene": spec.scene, "params": [[n, list(v)] for n, v in spec.params], "set": [[k, v] for k, v in spec.overrides],
            "settle": spec.settle, "chunk": spec.chunk, "cases": len(cases), "chunks": plan, "history_every": spec.history_every}  # fmt: skip

    def save_manifest() -> None:
        write_text(out / MANIFEST, json.dumps({**info, "files": files}, default=str))  # compact: rewritten after every chunk

    try:
        out.mkdir(parents=True, exist_ok=True)
        save_manifest()
    except OSError as e:
        raise ConfigError(f"--out {out}: cannot write there ({e.strerror})") from None
    skipped = len(plan) - len(todo)
    print(f"sweep {key}: {len(cases)} cases of '{base.name}' in {len(plan)} chunks of up to {spec.chunk}"
          + (f" ({skipped} already done, {len(todo)} to run)" if skipped else "") + f", backend {backend}", flush=True)  # fmt: skip
    bar = progress_bar(sum(len(idx) for _, idx in todo), unit="case", flag=args.progress)
    statuses: Counter = Counter()
    started = time.perf_counter()
    ran = 0

    def done(cid: int, rows: dict, history: dict | None) -> None:
        nonlocal ran
        names = [chunk_name(cid)] + ([f"{HISTORY}/{chunk_name(cid)}"] if history is not None else [])
        try:
            for name, columns in zip(names, (rows, history)):
                files[name] = write(out / name, columns)
            save_manifest()  # a chunk counts as done once its checksums are recorded here
        except WriteFailed:  # not done: none of its files stays unrecorded (--resume runs it again)
            for name in names:
                files.pop(name, None)
                with contextlib.suppress(OSError):
                    (out / name).unlink(missing_ok=True)
            raise
        statuses.update(rows["status"])
        ran += 1
        bar.update(len(rows["case"]))

    try:
        with StopOnCtrlC() as stop:
            run(spec, todo, done, backend, args.workers, args.scheduler, args.timeout, stop)
    except WorkerLost as e:
        print(f"floatsim: {e}: {ran} chunks of {len(todo)} written to {out}; rerun with --resume to finish", file=sys.stderr)
        return 4
    except WriteFailed as e:  # a full disk: the chunks written before are whole and recorded
        print(f"floatsim: {e}: {ran} chunks of {len(todo)} written to {out}; rerun with --resume to finish", file=sys.stderr)
        return 2
    except Interrupted:
        print(f"floatsim: interrupted (Ctrl-C): {ran} chunks of {len(todo)} written to {out} ({sum(statuses.values())} cases); "
              "rerun with --resume to finish", file=sys.stderr)  # fmt: skip
        return EXIT
    finally:
        bar.close()
    wall = time.perf_counter() - started
    summary = ", ".join(f"{n} {s}" for s, n in sorted(statuses.items()))
    print(f"ran {ran} chunks ({sum(statuses.values())} cases: {summary}) in {wall:.3g} s -> {out}/ (pandas.read_parquet('{out}'))")
    if args.netcdf is not None:
        gather(out, files, spec, info, args.netcdf)
        print(f"every case's results, over {' x '.join(name for name, _ in spec.params) or 'no parameter'} -> {args.netcdf}")
    return 3 if statuses.get("diverged") else 0


def gather(out: Path, files: dict, spec: Sweep, info: dict, path: str) -> None:
    """The sweep's chunks as one netCDF dataset over its swept parameters (sim/io/netcdf.grid_dataset), written whole."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.concat_tables([pq.read_table(out / name) for name in sorted(files) if name.startswith("chunk-")])
    params = [(name, *parameter_units(name)) for name, _ in spec.params]
    ds = netcdf.grid_dataset(table.to_pandas(), params, {"title": f"floatsim sweep {spec.key()} of scene {spec.scene!r}",
                                                         "history": "floatsim " + shlex.join(sys.argv[1:]), "floatsim_sweep": json.dumps(info, default=str)})  # fmt: skip
    write_whole(path, lambda tmp: netcdf.write(ds, tmp))


def parameter_units(name: str) -> tuple[str, str]:
    """(units, long name) of a swept parameter: a scene parameter's declared unit and help, a start parameter's."""
    if name in START:
        words = START[name]
        return ("degree" if name == "tilt" else "m" if name == "z0" else ""), words
    key = name.split(".", 1)[-1]
    param = VARIABLE.get(name) or BODY_VARIABLE.get(key)
    return (param.unit, param.help) if param is not None else ("", name)


def chunk_name(cid: int) -> str:
    return f"chunk-{cid:05d}.parquet"


def open_folder(out: Path, key: str, resume: bool) -> dict | None:
    """None for a fresh start; with --resume, the checksums the manifest recorded. Refuses a file, a folder
    of chunks that cannot be told apart from another sweep's, and a sweep that would mix with another."""
    if out.exists() and not out.is_dir():
        raise ConfigError(f"--out {out}: is a file, give a folder")
    if not (any(out.glob("chunk-*.parquet")) or any(out.glob(f"{HISTORY}/chunk-*.parquet"))):
        return None  # nothing done yet: any old manifest is simply replaced
    manifest = out / MANIFEST
    if not manifest.exists():
        raise ConfigError(f"{out} holds chunk files but no {MANIFEST}: they cannot be checked against this sweep, so they are not mixed with it; "
                          "choose another --out (or empty the folder)")  # fmt: skip
    old = read_manifest(manifest)
    if not resume:
        raise ConfigError(f"{out} already holds a sweep's results: add --resume to finish it, or choose another --out")
    if old["key"] != key:
        raise ConfigError(f"{out} holds a different sweep (another grid, scene or settings): --resume needs the same one")
    return old["files"]


def read_manifest(path: Path) -> dict:
    """The manifest's key and per-file records ({name: [sha256, rows]}), or a one-line error saying it is damaged."""
    try:
        data = json.loads(path.read_text())
    except OSError as e:
        raise ConfigError(f"{path}: cannot read it ({e.strerror})") from None
    except (json.JSONDecodeError, UnicodeDecodeError):
        data = None
    if not isinstance(data, dict) or not isinstance(data.get("key"), str) or not isinstance(data.get("files", {}), dict):
        raise ConfigError(f"{path} is damaged (not a floatsim sweep manifest), so the chunks beside it cannot be checked: "
                          f"choose another --out, or delete {path.parent} to start over")  # fmt: skip
    return {"key": data["key"], "files": data.get("files", {})}


def verify(out: Path, plan: list[list[int]], files: dict, history: bool) -> tuple[list, dict]:
    """(chunks to run, records of the chunks kept). A chunk is kept when each of its files (results and, if
    kept, history) reads as Parquet, has the rows recorded (the results: one per case) and the checksum
    recorded when it was written; a bad one is deleted and run again, with a note."""
    todo, kept, bad = [], {}, 0
    for cid, indices in enumerate(plan):
        names = [chunk_name(cid)] + ([f"{HISTORY}/{chunk_name(cid)}"] if history else [])
        if not any((out / n).exists() for n in names):
            todo.append((cid, indices))  # never written
            continue
        problems = [(n, why) for n in names if (why := check_chunk(out / n, files.get(n), len(indices) if n == names[0] else None))]
        if not problems:
            kept.update({n: files[n] for n in names})
            continue
        for n in names:
            (out / n).unlink(missing_ok=True)
        todo.append((cid, indices))
        bad += 1
        if bad <= 10:
            name, why = problems[0]
            print(f"floatsim: note: {out / name}: {why}; running chunk {cid} again", file=sys.stderr)
    if bad > 10:
        print(f"floatsim: note: {bad - 10} more damaged chunks run again", file=sys.stderr)
    return todo, kept


def check_chunk(path: Path, record, rows: int | None) -> str | None:
    """Why a chunk file cannot be trusted, or None."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    if not path.exists():
        return "missing"
    if not (isinstance(record, list) and len(record) == 2):
        return "no checksum in the manifest (written by a run that was killed, or by an older floatsim)"
    try:
        found = pq.read_metadata(path).num_rows
    except (OSError, ValueError, pa.ArrowException):
        return "not readable as Parquet (truncated, empty or damaged)"
    if found != record[1] or (rows is not None and found != rows):
        return f"{found} rows where {record[1] if rows is None else rows} were written"
    if digest(path) != record[0]:
        return "its checksum differs from the one recorded when it was written"
    return None


def digest(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def write_text(path: Path, text: str) -> None:
    """A text file, whole or not at all."""
    write_whole(path, lambda tmp: Path(tmp).write_text(text))


def write(path: Path, columns: dict) -> list:
    """A Parquet file, whole or not at all (written aside, then renamed): a killed run or a full disk leaves no half
    file under its name, and the temporary's name starts with '_', which readers of the folder skip.
    Returns its record for the manifest: [sha256 of its bytes, rows]."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise WriteFailed(path.parent, reason(e)) from None
    table = pa.table(columns)

    def parquet(tmp: str) -> list:
        pq.write_table(table, tmp)
        return [digest(Path(tmp)), table.num_rows]

    return write_whole(path, parquet)


OLD_TEMPORARY = re.compile(r"(chunk-\d{5}|_manifest)\.partial")
"""The temporaries earlier versions named (chunk-00003.partial: pandas.read_parquet of the folder failed on them)."""


def leftovers(folder: Path) -> list[Path]:
    return temporaries(folder) + [p for p in folder.glob("*.partial") if OLD_TEMPORARY.fullmatch(p.name) and p.is_file()]


def remove_temporaries(out: Path) -> None:
    """Remove the temporaries a killed or failed write left in the sweep's folder (and its history's), with a note."""
    found = leftovers(out) + leftovers(out / HISTORY)
    for p in found:
        with contextlib.suppress(OSError):
            p.unlink()
    if found:
        print(f"floatsim: note: removed {len(found)} temporary file{'s' if len(found) > 1 else ''} of a write that did not finish "
              f"({found[0].name}{', ...' if len(found) > 1 else ''})", file=sys.stderr)  # fmt: skip
