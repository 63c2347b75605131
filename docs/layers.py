"""The layers of sim/ and app/ as the code has them: `python docs/layers.py` rewrites the picture in docs/developer.md.

The layers come from pyproject.toml's import-linter contracts (`lint-imports` holds them); what each layer imports and
each package's job come from the code (grimp's import graph, each package's docstring). A test checks the page is
fresh (tests/test_structure.py), so the picture cannot rot.
"""

from __future__ import annotations

import ast
import importlib.util
import sys
import tomllib
from pathlib import Path

import grimp

ROOT = Path(__file__).resolve().parent.parent
PAGE = ROOT / "docs" / "developer.md"
START, END = "<!-- layers: made by `python docs/layers.py` -->", "<!-- layers end -->"


def contracts() -> list[dict]:
    """The layers contracts of pyproject.toml, as written."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"]["contracts"]
    return [c for c in config if c["type"] == "layers"]


def layers_of(contract: dict) -> list[list[str]]:
    """Each layer's modules, high to low, named in full (`sim.hydro`, `app.live`)."""
    prefix = [f"{c}." for c in contract.get("containers", [])] or [""]
    return [[prefix[0] + m.strip() for m in layer.replace(":", "|").split("|")] for layer in contract["layers"]]


def job(module: str) -> str:
    """The first sentence of a module's or package's docstring: its job."""
    spec = importlib.util.find_spec(module)
    doc = ast.get_docstring(ast.parse(Path(spec.origin).read_text())) or ""
    first = " ".join(doc.split("\n\n")[0].split())
    return first.split(". ")[0].rstrip(".").replace("|", "\\|")  # a bar would split the table's cell


def direct_imports(graph: grimp.ImportGraph, module: str, names: list[str]) -> list[str]:
    """Which of `names` (other layers' modules) `module` or anything inside it imports directly."""
    inside = {module} | graph.find_descendants(module)
    return [n for n in names if n != module and any(graph.direct_import_exists(importer=m, imported=n, as_packages=True) for m in inside)]


def reduced(edges: dict[str, list[str]]) -> dict[str, list[str]]:
    """The edges of a DAG no path of two or more steps already gives (its transitive reduction): the picture's arrows."""

    def reach(m: str, seen: set[str]) -> set[str]:
        for n in edges[m]:
            if n not in seen:
                seen.add(n)
                reach(n, seen)
        return seen

    return {m: [n for n in ns if not any(n in reach(k, set()) for k in ns if k != n)] for m, ns in edges.items()}


def diagram(layers: list[list[str]], graph: grimp.ImportGraph) -> list[str]:
    """A mermaid flowchart, high layers on top: an arrow where a module imports another and no chain of imports says it."""
    names = [m for layer in layers for m in layer]
    edges = {m: direct_imports(graph, m, [n for lower in layers[d + 1 :] for n in lower]) for d, layer in enumerate(layers) for m in layer}
    node = {m: f"n{i}" for i, m in enumerate(names)}
    out = ["```mermaid", "flowchart TD"]
    out += [f'  {node[m]}["{m.split(".", 1)[1]}"]' for m in names]
    out += [f"  {node[m]} --> {node[n]}" for m, ns in reduced(edges).items() for n in ns]
    return out + ["```", ""]


def picture() -> str:
    """The layers, high to low, as markdown: per contract a diagram, then a table of layer, module, job and imports."""
    graph = grimp.build_graph("sim", "app", include_external_packages=False, exclude_type_checking_imports=True, cache_dir=None)
    out = [START, ""]
    for contract in contracts():
        layers = layers_of(contract)
        everything = [m for layer in layers for m in layer]
        out += [f"**{contract['name']}**", "", *diagram(layers, graph)]
        out += ["| layer | module | its job | imports (of the layers below) |", "| --- | --- | --- | --- |"]
        for depth, layer in enumerate(layers, 1):
            for module in layer:
                below = [m for lower in layers[depth:] for m in lower]
                uses = direct_imports(graph, module, below)
                short = ", ".join(f"`{u.split('.', 1)[1]}`" for u in uses) or "none"
                out.append(f"| {depth} | `{module}` | {job(module)} | {short} |")
        out.append("")
        unlisted = sorted(
            m
            for m in graph.find_children(layers[0][0].split(".")[0])
            if m not in everything and not m.endswith("__main__") and not any(e.startswith(m + ".") for e in everything)
        )
        if unlisted:
            out += [f"Not in a layer: {', '.join(f'`{m}`' for m in unlisted)}.", ""]
    out.append(END)
    return "\n".join(out)


def page_with(text: str, block: str) -> str:
    start, end = text.index(START), text.index(END) + len(END)
    return text[:start] + block + text[end:]


def main() -> int:
    text = PAGE.read_text()
    fresh = page_with(text, picture())
    if fresh != text:
        PAGE.write_text(fresh)
        print(f"wrote the layers into {PAGE.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
