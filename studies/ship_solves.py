"""`python -m studies.ship_solves`: solve again every BEM case floatsim ships in assets/coefficients (needs the
.[bem] extra; about 10-20 minutes on two cores), then fit their memories again (`python -m sim.commands.memory_fits`).

The cases: each preset with radiation as it builds (its rest pose, moorings included, its grid, the excitation when
it has waves, a sphere in waves too), the cross-code checks' scenes (assets/scenes/*/), and the test hemisphere of tests/hydro/test_bem.py (Hulme's table). Run it after a
change to how solves are made (sim.hydro.bem.SOLVER_VERSION, the lid, the wet mesh) or to a preset's body: the old files'
keys no longer match, so the presets would otherwise solve on every machine.
"""

from __future__ import annotations

import os
import shutil

import numpy as np


def main() -> None:
    import trimesh

    import sim.hydro.bem as bem
    from sim import Simulation
    from sim.commands.memory_fits import main as fit_all
    from sim.scene.config import SCENES_DIR, available_scenes, load_scene, with_overrides
    from sim.system.tree import build

    shipped, work = bem.SHIPPED, bem.user_cache().parent / "ship-solves"  # kept: a run stopped half way resumes
    os.environ[bem.CACHE_ENV] = str(work)
    bem.SHIPPED = work / "none"
    used, stored_or_solved = [], bem._stored_or_solved

    def recorded(key, *args):
        used.append(key)
        return stored_or_solved(key, *args)

    bem._stored_or_solved = recorded
    checks = sorted(str(p) for p in SCENES_DIR.glob("*/*.toml"))  # the cross-code checks' scenes (assets/scenes/f3of/...)
    for name in [*available_scenes(), *checks]:
        scene = load_scene(name)
        if scene.fluid.radiation != "bem":
            continue
        print(f"{name}:", flush=True)
        if scene.bodies:
            build(scene)
            continue
        if scene.waves.kind == "still":  # its solve with the excitation, for the same body in waves
            scene = with_overrides(scene, waves__kind="regular", waves__height=0.02, waves__period=2.0)
        Simulation(scene, backend="numpy")
    print("the test hemisphere:", flush=True)
    s = trimesh.creation.icosphere(subdivisions=3, radius=1.0)
    ka = np.array([0.05, 0.3, 0.5, 1.0, 2.0, 5.0])
    bem.radiation_coefficients(s.vertices, s.faces, omega=np.sqrt(ka * 9.81), panel=0.12)
    bem._stored_or_solved, bem.SHIPPED = stored_or_solved, shipped
    for old in shipped.glob("*.npz"):
        old.unlink()
    for key in sorted(set(used)):
        shutil.copy(work / f"{key}.npz", shipped / f"{key}.npz")
        (shipped / f"{key}.npz").chmod(0o644)
        print(shipped / f"{key}.npz")
    fit_all()


if __name__ == "__main__":
    main()
