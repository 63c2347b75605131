"""The About pane: what is simulated, the legend of the scene, and the README one click away."""

from __future__ import annotations

import re
from pathlib import Path

import viser

README = Path(__file__).resolve().parents[2] / "README.md"

ABOUT = """**floatsim** simulates a rigid body floating in water: the water's pressure on its wet surface,
viscous damping (and drag, waves and radiation when a scene asks), gravity at its centre of mass.

- <span style="color:#1e6ee6">●</span> **blue points**: surface samples under water, where the water pushes; <span style="color:#f59628">●</span> **orange**: dry ones.
- **Red arrow**: the net force, 1 m = the body's weight. **Green arrow**: the net torque, 1 m = weight × the body's radius.
- **B**: centre of buoyancy; **M**: metacentre; **yellow line**: the waterline (the grey-blue hull is under water). G is the centre of mass (Layers: show body axes): a small heel rights itself when **GM > 0** (M above G) and grows when GM < 0.
- **Sliders** change the physics live (density: how deep it floats; damping: how fast motion dies out); **Reset** starts again with them.
- **The sea** is lighter on crests and slopes facing the light; **orange balls** are the scene's wave gauges ([[gauges]]), labelled with the elevation there; **Follow body** (View) keeps the body in view, **Reset view** the starting camera.
- **Record** keeps the run as one HTML page anyone can replay offline; **Your body** loads your own mesh; **Copy link** shares this setup."""


def readme_text(path: Path = README) -> str:
    """The README as the modal shows it: images dropped (they are files beside it, not in the page)."""
    try:
        text = path.read_text()
    except OSError:
        return "The README is not installed beside the code."
    return re.sub(r"!\[[^\]]*\]\([^)]*\)", "", text)


class About:
    def __init__(self, server: viser.ViserServer):
        gui = server.gui
        gui.add_markdown(ABOUT)  # in the panel's first tab (app/main.py)
        self.readme = gui.add_button("Read the README", icon=viser.Icon.BOOK, hint="What it is, the main commands and where the docs are")
        self.readme.on_click(lambda event: self.show_readme(event.client))

    @staticmethod
    def show_readme(client) -> None:
        if client is None:
            return
        with client.gui.add_modal("floatsim README") as modal:
            client.gui.add_markdown(readme_text())
            client.gui.add_button("Close").on_click(lambda _: modal.close())
