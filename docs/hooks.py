"""mkdocs hooks: the parameter reference made from the `Param` declarations (never written by hand), and the
generated reports (reports/: the accuracy and stability pages and their figures) served beside the docs."""

from __future__ import annotations

import math
from pathlib import Path

from mkdocs.structure.files import File

ROOT = Path(__file__).resolve().parent.parent


def parameter_table() -> str:
    """Every scene parameter by table: key, default, unit, valid range, CLI flag and what it does."""
    from sim.scene.config import SECTIONS

    out = ["# Parameter reference", "",
           "Every key a scene file takes, by table, with its command-line flag (`python -m sim run --help` lists the same).",
           "Generated from the `Param` declarations in `sim/scene/config.py` when the docs are built.", ""]  # fmt: skip
    for section, params in SECTIONS.items():
        out += [f"## [{section}]", "", "| key | default | unit | valid | flag | what it does |", "| --- | --- | --- | --- | --- | --- |"]
        for p in params:
            out.append(f"| `{p.key}` | {_default(p)} | {p.unit or ''} | {_valid(p)} | {('`--' + p.cli.replace('_', '-') + '`') if p.flag else ''} | "
                       f"{p.help.replace('|', '/')} |")  # fmt: skip
        out.append("")
    return "\n".join(out)


def _default(p) -> str:
    value = p.default
    if value in ((), "", None):
        return "-"
    return f"`{value}`"


def _valid(p) -> str:
    if p.kind == "choice":
        return ", ".join(f"`{c}`" for c in p.choices)
    if p.kind in ("text", "switch", "optional") and math.isinf(p.lo) and math.isinf(p.hi):
        return ""
    lo = "" if math.isinf(p.lo) else f"{'>' if p.lo_open else '≥'} {p.lo:g}"
    hi = "" if math.isinf(p.hi) else f"≤ {p.hi:g}"
    return ", ".join(x for x in (lo, hi) if x)


def examples_page() -> str:
    """examples/: each script's title and story (its docstring), how to run it, its picture (docs/examples/NN.png, made
    with its --plot flag) and its code."""
    import ast

    out = ["# Examples", "", "Numbered, runnable scripts in `examples/`, each a typed `main` run by tyro (`--help` lists its flags). "
           "`tests/test_examples.py` runs every one with short flags and checks the physics it prints.", ""]  # fmt: skip
    for path in sorted((ROOT / "examples").glob("[0-9][0-9]_*.py")):
        code = path.read_text()
        title, _, story = ast.get_docstring(ast.parse(code)).partition("\n")
        out += [f"## {path.stem[:2]}. {title}", "", story.strip(), "", "```bash", f"python examples/{path.name}", "```", ""]
        picture = ROOT / "docs" / "examples" / f"{path.stem[:2]}.png"
        if picture.exists():
            out += [f"![{title}](examples/{picture.name})", ""]
        out += ['??? example "The code"', "    ```python"] + [f"    {line}" if line else "" for line in code.splitlines()] + ["    ```", ""]
    return "\n".join(out)


def on_files(files, config):
    for path in sorted((ROOT / "reports").rglob("*")):
        if path.is_file() and path.suffix in (".md", ".png", ".svg", ".gif"):
            files.append(File(str(path.relative_to(ROOT)), str(ROOT), config["site_dir"], config["use_directory_urls"]))
    files.append(File.generated(config, "parameters.md", content=parameter_table()))
    files.append(File.generated(config, "changelog.md", content=(ROOT / "CHANGELOG.md").read_text()))
    files.append(File.generated(config, "examples.md", content=examples_page()))
    return files
