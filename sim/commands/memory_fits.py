"""`python -m sim.commands.memory_fits`: (re)write the radiation memory fits every preset and cross-code check
(assets/scenes/*/) makes into hydro.memory_fit.STORED, by building each with radiation once against an empty cache
and keeping what it fitted. A maintainer's command: run it after a change to hydro/memory_fit.py (its source is
part of every fit's key)."""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

from sim.hydro import memory_fit
from sim.hydro.bem import CACHE_ENV
from sim.scene.config import SCENES_DIR, available_scenes, load_scene
from sim.simulation import Simulation
from sim.system.tree import build


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        os.environ[CACHE_ENV] = tmp
        for old in memory_fit.STORED.glob("*.npz"):
            old.unlink()
        memory_fit.forget_fits()
        for name in [*available_scenes(), *sorted(str(p) for p in SCENES_DIR.glob("*/*.toml"))]:
            scene = load_scene(name)
            if scene.bodies:
                build(scene)  # building it fits its memory
            elif scene.fluid.radiation == "bem":
                Simulation(scene)
        memory_fit.STORED.mkdir(parents=True, exist_ok=True)
        for path in sorted(Path(tmp, "memory").glob("*.npz")):
            shutil.copy(path, memory_fit.STORED / path.name)
            print(f"{memory_fit.STORED / path.name}")


if __name__ == "__main__":
    main()
