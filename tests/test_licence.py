"""floatsim may be reused: it carries the Apache License 2.0 (the licence of WEC-Sim, Capytaine and OpenFAST), in its
files and its installed metadata, and NOTICE names every shipped file derived from another project with its source."""

from __future__ import annotations

import re
import tomllib
from importlib.metadata import metadata
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
OTHERS = re.compile(r"WEC-Sim|SEA-Stack|OpenFAST|r-test|WAMIT")
"""The projects whose files floatsim derives shipped files from (WAMIT: another code's run, whoever shared it)."""
TEXT = (".dat", ".txt", ".csv", ".json", ".out", ".1", ".3", ".hst", ".8", ".9", ".12d", ".cal", ".tec")
"""The shipped text files' suffixes (WAMIT's output and numeric files among them)."""


def test_the_licence_is_apache_2_in_the_files_and_the_installed_metadata():
    text = (ROOT / "LICENSE").read_text()
    assert text.split()[:4] == ["Apache", "License", "Version", "2.0,"] and "END OF TERMS AND CONDITIONS" in text
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert project["license"] == "Apache-2.0" and set(project["license-files"]) == {"LICENSE", "NOTICE"}
    assert metadata("floatsim")["License-Expression"] == "Apache-2.0"  # what pip show and a package index say


def _derived() -> set[str]:
    """Shipped text files that name another project as their source (a header or a `source` field)."""
    found = set()
    for path in (ROOT / "assets").rglob("*"):
        if path.suffix in TEXT and OTHERS.search(path.read_text(errors="replace")[:1500]):
            found.add(path.relative_to(ROOT).as_posix())
    return found


def test_notice_names_every_derived_file_and_each_file_it_names_is_shipped():
    notice = (ROOT / "NOTICE").read_text()
    named = set(re.findall(r"(?<![\w/])assets/[\w./-]+\.\w+", notice))  # (not another project's own assets/ paths)
    assert _derived() <= named, f"derived files missing from NOTICE: {sorted(_derived() - named)}"
    assert {"assets/coefficients/imported/rm3_wecsim.npz", "assets/meshes/f3of_base.stl", "assets/meshes/rm3_wecsim_spar.stl"} <= named
    missing = [name for name in named if not (ROOT / name).is_file()]
    assert not missing, f"NOTICE names files that are not shipped: {missing}"
    for source in ("Apache License 2.0", "MIT License", "commit 4d1eae6", "commit 3d884b1", "commit a23d299", "commit e6cb69e"):
        assert source in notice
